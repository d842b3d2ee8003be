"""Where a training run's epochs stand, saved after every epoch so an interrupted run continues.

A member of the v3 ensemble trains for hours and a session ends when it ends: ``resume.pt`` in
the run folder holds the network, the optimiser, the learning-rate schedule and the batch
generator after the last finished epoch, with the best weights so far and the history. It is
loaded with ``weights_only`` (tensors and plain types: a file can run no code), and only for the
configuration and data it was saved with (``threads`` may differ; the data is compared by content,
so the same file named by another path resumes). Every field is checked against the objects it is
restored into and against the others (epochs, history, best epoch, optimiser steps) before any is
used: a damaged or foreign file is refused with what is wrong, never half restored.
"""
from __future__ import annotations

import json
import math
import numbers
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import torch

from roughness.core.errors import InputError

from .config import TrainConfig

RESUME_FILE = "resume.pt"
SNAPSHOT_KEYS = ("key", "progress", "model", "optimizer", "schedule", "generator")
ADAM_STATE = ("step", "exp_avg", "exp_avg_sq")  # AdamW's state per parameter (amsgrad off)


@dataclass
class Progress:
    """The epochs so far: the next epoch, the best validation loss, its weights, the history and the clock."""

    epoch: int = 0  # the next epoch to run
    best_val: float = math.inf
    best_epoch: int = -1
    best_state: dict[str, torch.Tensor] | None = None  # weights of the best epoch
    history: list[tuple[int, float, float, float, float]] = field(default_factory=list)
    epochs_seconds: float = 0.0  # wall clock spent in epochs: the time budget's clock
    seconds: float = 0.0  # wall clock of earlier sessions, data loading included
    core_seconds: float = 0.0  # seconds x threads of earlier sessions


def improves(loss: float, best: float) -> bool:
    """Whether a validation ``loss`` is a new best: finite and below ``best`` (any finite loss beats a NaN best,
    so a NaN can never freeze the best epoch)."""
    return math.isfinite(loss) and not loss >= best


def fingerprint(cfg: TrainConfig, data_sha256: list[str]) -> str:
    """What a saved run depends on: its configuration (output folder, threads and the data files' paths aside)
    and its data's content (the files' checksums, in order)."""
    settings = {k: v for k, v in asdict(cfg).items() if k not in ("out", "threads", "data", "extra_data")}
    return json.dumps({"config": settings, "data_sha256": data_sha256}, sort_keys=True)


def snapshot(key: str, progress: Progress, model: torch.nn.Module, optimizer: torch.optim.Optimizer,
             schedule: torch.optim.lr_scheduler.LRScheduler, generator: torch.Generator) -> dict:
    """The state to save after an epoch (the caller writes it atomically)."""
    return {"key": key, "progress": asdict(progress), "model": model.state_dict(),
            "optimizer": optimizer.state_dict(), "schedule": schedule.state_dict(), "generator": generator.get_state()}


class _Damaged(Exception):
    """A field of a saved state that cannot be restored (the message says which and why)."""


def restore(path: Path, key: str, model: torch.nn.Module, optimizer: torch.optim.Optimizer,
            schedule: torch.optim.lr_scheduler.LRScheduler, generator: torch.Generator,
            steps_per_epoch: int) -> Progress:
    """Restore a saved run into freshly built objects (``steps_per_epoch``: optimiser steps per epoch); InputError
    for ``out`` if it was saved for another configuration or data, or if any field is damaged."""
    saved = _load(path)
    _check_key(path, saved, key)
    try:
        progress = _progress(saved["progress"], model, json.loads(key)["config"]["max_epochs"])
        steps = progress.epoch * steps_per_epoch
        _check_tensors("model", saved["model"], model.state_dict())
        _check_optimizer(saved["optimizer"], optimizer, steps)
        _check_schedule(saved["schedule"], schedule, steps)
        _check_tensors("generator", {"state": saved["generator"]}, {"state": generator.get_state()})
        model.load_state_dict(saved["model"])
        optimizer.load_state_dict(saved["optimizer"])
        schedule.load_state_dict(saved["schedule"])
        generator.set_state(saved["generator"])
    except (_Damaged, RuntimeError, ValueError, TypeError, KeyError) as err:
        raise InputError(f"{path} cannot be resumed: {err}; the file is damaged or was not written by `roughness "
                         "train`: start over with overwrite", parameter="out") from None
    return progress


def _load(path: Path) -> dict:
    """The saved state (plain data only), a dict of SNAPSHOT_KEYS; InputError otherwise."""
    try:
        saved = torch.load(path, weights_only=True)
    except Exception as err:  # torch raises several types for a damaged or foreign file
        raise InputError(f"{path}: not a saved training state that can be resumed ({err})", parameter="out") from err
    if not isinstance(saved, dict) or set(saved) != set(SNAPSHOT_KEYS):
        found = ", ".join(map(str, saved)) if isinstance(saved, dict) else type(saved).__name__
        raise InputError(f"{path}: not a saved training state that can be resumed (expected the fields "
                         f"{', '.join(SNAPSHOT_KEYS)}; found {found})", parameter="out")
    return saved


def _check_key(path: Path, saved: dict, key: str) -> None:
    """InputError naming what differs unless the state was saved for this configuration and data."""
    if isinstance(saved["key"], str) and saved["key"] == key:
        return
    theirs, ours = _settings(saved["key"]), json.loads(key)
    if not theirs:
        raise InputError(f"{path} cannot be resumed: its key is not the fingerprint of a training configuration; the "
                         "file is damaged or was not written by `roughness train`: start over with overwrite",
                         parameter="out")
    changed = sorted({*_differences(theirs.get("config", {}), ours["config"]),
                      *(["data"] if theirs.get("data_sha256") != ours["data_sha256"] else [])})
    raise InputError(f"{path} was saved by a run with other settings or data ({', '.join(changed) or 'unknown'}); "
                     "resume with the same options, or start over with overwrite", parameter="out")


def _settings(key: object) -> dict:
    """A saved fingerprint as a dict ({} if it is not one)."""
    try:
        settings = json.loads(key) if isinstance(key, str) else None
    except ValueError:
        return {}
    if not isinstance(settings, dict) or not isinstance(settings.get("config", {}), dict):
        return {}
    return settings


def _differences(saved: dict, ours: dict) -> list[str]:
    return [k for k in sorted(saved.keys() | ours.keys()) if saved.get(k) != ours.get(k)]


def _progress(saved: object, model: torch.nn.Module, max_epochs: int) -> Progress:
    """The saved Progress, each field checked and the best epoch checked against the history."""
    names = [f.name for f in fields(Progress)]
    if not isinstance(saved, dict) or set(saved) != set(names):
        raise _Damaged(f"its progress must hold {', '.join(names)}")
    epoch = saved["epoch"]
    if not (_whole(epoch) and 1 <= epoch <= max_epochs):
        raise _Damaged(f"its epoch must be a whole number in 1..{max_epochs} (max_epochs), got {epoch!r}")
    history = [_history_row(i, row) for i, row in enumerate(_sequence(saved["history"], "history", epoch))]
    best_val, best_epoch = math.inf, -1
    for row in history:
        if improves(row[2], best_val):
            best_val, best_epoch = row[2], row[0]
    if not (_whole(saved["best_epoch"]) and saved["best_epoch"] == best_epoch and _same_loss(saved["best_val"], best_val)):
        raise _Damaged(f"its best epoch {saved['best_epoch']!r} (validation loss {saved['best_val']!r}) is not its "
                       f"history's ({best_epoch}, {best_val!r})")
    if (saved["best_state"] is None) != (best_epoch < 0):
        raise _Damaged("its best weights must be saved exactly when an epoch was best")
    if saved["best_state"] is not None:
        _check_tensors("best weights", saved["best_state"], model.state_dict())
    for name in ("epochs_seconds", "seconds", "core_seconds"):
        if not (_real(saved[name]) and math.isfinite(saved[name]) and saved[name] >= 0):
            raise _Damaged(f"its {name} must be a finite number >= 0, got {saved[name]!r}")
    return Progress(**{**saved, "best_val": float(best_val), "history": history})


def _history_row(epoch: int, row: object) -> tuple[int, float, float, float, float]:
    """One epoch's (epoch, training loss, validation loss, learning rate, minutes); losses may be NaN (a diverged
    epoch), the rest are finite and >= 0."""
    row = _sequence(row, f"history row {epoch}", 5)
    if not (_whole(row[0]) and row[0] == epoch and all(_real(v) for v in row[1:])):
        raise _Damaged(f"history row {epoch} must be ({epoch}, training loss, validation loss, learning rate, "
                       f"minutes), got {row!r}")
    if not all(math.isfinite(v) and v >= 0 for v in row[3:]):
        raise _Damaged(f"history row {epoch}: learning rate and minutes must be finite and >= 0, got {row!r}")
    return epoch, float(row[1]), float(row[2]), float(row[3]), float(row[4])


def _same_loss(saved: object, expected: float) -> bool:
    return _real(saved) and float(saved) == expected


def _sequence(value: object, what: str, length: int) -> list:
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise _Damaged(f"its {what} must be a list of {length} entries, got "
                       f"{len(value) if isinstance(value, (list, tuple)) else type(value).__name__}")
    return list(value)


def _check_tensors(what: str, saved: object, expected: dict[str, torch.Tensor]) -> None:
    """``saved`` holds a tensor of the same shape and type under each name of ``expected``, and nothing else."""
    if not isinstance(saved, dict) or set(saved) != set(expected):
        names = set(saved) if isinstance(saved, dict) else set()
        raise _Damaged(f"its {what} must hold the tensors of this run: missing {sorted(set(expected) - names)[:5]}, "
                       f"unexpected {sorted(map(str, names - set(expected)))[:5]}")
    for name, tensor in expected.items():
        value = saved[name]
        if not isinstance(value, torch.Tensor) or value.shape != tensor.shape or value.dtype != tensor.dtype:
            found = f"{tuple(value.shape)} {value.dtype}" if isinstance(value, torch.Tensor) else type(value).__name__
            raise _Damaged(f"its {what} {name!r} must be a {tuple(tensor.shape)} {tensor.dtype} tensor, got {found}")


def _check_optimizer(saved: object, optimizer: torch.optim.Optimizer, steps: int) -> None:
    """AdamW's saved state: the groups and settings of ``optimizer`` (the learning rate within the schedule's
    range) and, per parameter, moments of its shape after ``steps`` steps."""
    ours = optimizer.state_dict()
    if not isinstance(saved, dict) or set(saved) != {"state", "param_groups"}:
        raise _Damaged("its optimizer must hold state and param_groups")
    groups = _sequence(saved["param_groups"], "optimizer param_groups", len(ours["param_groups"]))
    for group, our in zip(groups, ours["param_groups"]):
        if not isinstance(group, dict) or set(group) != set(our):
            raise _Damaged(f"its optimizer settings must be {', '.join(our)}")
        lr = group["lr"]
        if not (_real(lr) and 0 <= lr <= our["initial_lr"]):
            raise _Damaged(f"its learning rate must be in [0, {our['initial_lr']:g}], got {lr!r}")
        differ = [k for k in our if k != "lr" and group[k] != our[k]]
        if differ:
            raise _Damaged(f"its optimizer settings {', '.join(differ)} are not this run's")
    params = [p for group in optimizer.param_groups for p in group["params"]]
    state = saved["state"]
    if not isinstance(state, dict) or set(state) != set(range(len(params))):
        raise _Damaged(f"its optimizer state must hold the {len(params)} parameters of the network")
    for index, param in enumerate(params):
        moments = {name: torch.empty_like(param) for name in ADAM_STATE[1:]}
        _check_tensors(f"optimizer state {index}", state[index], {"step": torch.tensor(0.0), **moments})
        if state[index]["step"].item() != steps:
            raise _Damaged(f"its optimizer state {index} counts {state[index]['step'].item():g} steps, not the "
                           f"{steps} of its epochs")


def _check_schedule(saved: object, schedule: torch.optim.lr_scheduler.LRScheduler, steps: int) -> None:
    """The learning-rate schedule's saved state: this schedule's fields and base rates, at ``steps`` steps."""
    ours = schedule.state_dict()
    if not isinstance(saved, dict) or set(saved) != set(ours):
        raise _Damaged(f"its schedule must hold {', '.join(ours)}")
    if saved["base_lrs"] != ours["base_lrs"] or saved["lr_lambdas"] != ours["lr_lambdas"]:
        raise _Damaged("its schedule's base learning rates are not this run's")
    if saved["last_epoch"] != steps or saved.get("_step_count", steps + 1) != steps + 1:
        raise _Damaged(f"its schedule stands at step {saved['last_epoch']!r}, not the {steps} of its epochs")
    last = saved.get("_last_lr", [])
    if not (isinstance(last, list) and len(last) == len(ours["base_lrs"])
            and all(_real(v) and 0 <= v <= base for v, base in zip(last, ours["base_lrs"]))):
        raise _Damaged(f"its schedule's last learning rates must be within its base rates, got {last!r}")
    mistyped = [k for k, v in ours.items() if type(saved[k]) is not type(v)]
    if mistyped:
        raise _Damaged(f"its schedule's {', '.join(mistyped)} have the wrong type")


def _whole(x: object) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


def _real(x: object) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool)

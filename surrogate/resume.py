"""Where a training run's epochs stand, saved after every epoch so an interrupted run continues.

A member of the v3 ensemble trains for hours and a session ends when it ends: ``resume.pt`` in
the run folder holds the network, the optimiser, the learning-rate schedule and the batch
generator after the last finished epoch, with the best weights so far and the history. It is
loaded with ``weights_only`` (tensors and plain types: a file can run no code), and only for the
configuration and data it was saved with (``threads`` may differ).
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import torch

from roughness.core.errors import InputError

from .config import TrainConfig

RESUME_FILE = "resume.pt"


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


def fingerprint(cfg: TrainConfig, data_sha256: list[str]) -> str:
    """What a saved run depends on: its configuration (output folder and threads aside) and its data's content."""
    settings = {k: v for k, v in asdict(cfg).items() if k not in ("out", "threads")}
    return json.dumps({"config": settings, "data_sha256": data_sha256}, sort_keys=True)


def snapshot(key: str, progress: Progress, model: torch.nn.Module, optimizer: torch.optim.Optimizer,
             schedule: torch.optim.lr_scheduler.LRScheduler, generator: torch.Generator) -> dict:
    """The state to save after an epoch (the caller writes it atomically)."""
    return {"key": key, "progress": asdict(progress), "model": model.state_dict(),
            "optimizer": optimizer.state_dict(), "schedule": schedule.state_dict(), "generator": generator.get_state()}


def restore(path: Path, key: str, model: torch.nn.Module, optimizer: torch.optim.Optimizer,
            schedule: torch.optim.lr_scheduler.LRScheduler, generator: torch.Generator) -> Progress:
    """Restore a saved run into freshly built objects; refused if it was saved for another configuration or data."""
    try:
        saved_state = torch.load(path, weights_only=True)
    except Exception as err:  # torch raises several types for a damaged or foreign file
        raise InputError(f"{path}: not a saved training state that can be resumed ({err})", parameter="out") from err
    if not isinstance(saved_state, dict) or saved_state.get("key") != key:
        saved = json.loads(saved_state["key"]) if isinstance(saved_state, dict) and isinstance(
            saved_state.get("key"), str) else {}
        ours = json.loads(key)
        changed = sorted({*_differences(saved.get("config", {}), ours["config"]),
                          *(["data"] if saved.get("data_sha256") != ours["data_sha256"] else [])})
        raise InputError(f"{path} was saved by a run with other settings or data ({', '.join(changed) or 'unknown'}); "
                         "resume with the same options, or start over with overwrite", parameter="out")
    model.load_state_dict(saved_state["model"])
    optimizer.load_state_dict(saved_state["optimizer"])
    schedule.load_state_dict(saved_state["schedule"])
    generator.set_state(saved_state["generator"])
    saved = saved_state["progress"]
    return Progress(**{**saved, "history": [tuple(row) for row in saved["history"]]})


def _differences(saved: dict, ours: dict) -> list[str]:
    return [k for k in sorted(saved.keys() | ours.keys()) if saved.get(k) != ours.get(k)]

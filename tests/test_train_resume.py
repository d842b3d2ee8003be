"""Training resumes: an interrupted run continues from its last finished epoch to the run it would have been."""
from __future__ import annotations

import json
import os
import re

import pytest
import torch

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.surrogate import train as train_module
from roughness.surrogate.resume import RESUME_FILE, fingerprint, improves
from roughness.surrogate.train import TrainConfig, train
from test_surrogate import write_tiny_dataset

# max_minutes: a budget that never binds, so the learning rate follows the steps alone (its time fraction, ~1e-9 of
# the cosine, moves nothing at float32)
SETTINGS = dict(max_epochs=4, batch_size=8, val_fraction=0.2, max_minutes=1e6, threads=1)


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    path = tmp_path_factory.mktemp("resume") / "tiny.h5"
    write_tiny_dataset(path)
    return path


def interrupt_after_epoch(monkeypatch, epoch: int) -> None:
    """Stop the run as a session's end would, right after ``epoch`` is logged (and saved)."""
    log = train_module.log

    def stopping_log(message: str) -> None:
        log(message)
        if message.startswith(f"epoch {epoch:3d}"):
            raise KeyboardInterrupt

    monkeypatch.setattr(train_module, "log", stopping_log)


def test_an_interrupted_run_resumed_is_the_run_that_was_never_interrupted(data, tmp_path, monkeypatch):
    whole = train(TrainConfig(data=str(data), out=str(tmp_path / "whole"), **SETTINGS))
    cfg = TrainConfig(data=str(data), out=str(tmp_path / "cut"), **SETTINGS)
    with monkeypatch.context() as patch:
        interrupt_after_epoch(patch, 1)
        with pytest.raises(KeyboardInterrupt):
            train(cfg)
    assert (tmp_path / "cut" / RESUME_FILE).is_file() and not (tmp_path / "cut" / "checkpoint.pt").exists()
    resumed = train(cfg, resume=True)

    assert not (tmp_path / "cut" / RESUME_FILE).exists()  # a finished run leaves no state behind
    a, b = (torch.load(path, weights_only=True) for path in (whole, resumed))
    assert a["best_epoch"] == b["best_epoch"] and a["epochs"] == b["epochs"] == 4
    for name, weights in a["state_dict"].items():
        torch.testing.assert_close(b["state_dict"][name], weights, rtol=1e-5, atol=1e-6)
    history = [(tmp_path / run / "history.csv").read_text().splitlines() for run in ("whole", "cut")]
    losses = [[float(v) for row in h[1:] for v in row.split(",")[1:3]] for h in history]
    assert losses[0] == pytest.approx(losses[1], rel=1e-4)  # written to 6 digits
    metrics = json.loads((tmp_path / "cut" / "metrics.json").read_text())
    assert metrics["cost_core_seconds"]["training"] > 0


def test_resume_refuses_a_state_saved_with_other_settings_and_a_damaged_one(data, tmp_path, monkeypatch):
    cfg = TrainConfig(data=str(data), out=str(tmp_path / "run"), **SETTINGS)
    with monkeypatch.context() as patch:
        interrupt_after_epoch(patch, 0)
        with pytest.raises(KeyboardInterrupt):
            train(cfg)
    other = TrainConfig(data=str(data), out=str(tmp_path / "run"), **{**SETTINGS, "seed": 3, "hidden": 8})
    with pytest.raises(InputError, match="other settings or data .*hidden, seed"):
        train(other, resume=True)
    threads = TrainConfig(data=str(data), out=str(tmp_path / "run"), **{**SETTINGS, "threads": 2})
    (tmp_path / "run" / RESUME_FILE).write_bytes(b"not a torch file")
    with pytest.raises(InputError, match="not a saved training state"):
        train(threads, resume=True)


def test_resume_cli_starts_a_new_run_where_there_is_nothing_to_resume(data, tmp_path, capsys):
    out = tmp_path / "run"
    args = ["train", str(data), "--out", str(out), "--max-epochs", "2", "--batch-size", "8", "--threads", "1",
            "--resume"]
    assert main(args) == 0
    assert (out / "checkpoint.pt").is_file() and not (out / RESUME_FILE).exists()
    assert main(args) == 2  # a finished run is not overwritten by --resume
    assert "exists" in capsys.readouterr().err


def _break(saved: dict, change: str) -> None:
    """Damage one field of a saved state (after two finished epochs of SETTINGS: 2 steps each)."""
    if change == "key":
        saved["key"] = "not a fingerprint"
    elif change == "field":
        del saved["generator"]
    elif change == "shape":
        saved["model"]["features.0.0.weight"] = torch.zeros(3)
    elif change == "epoch":
        saved["progress"]["epoch"] = 3  # but two epochs of history
    elif change == "history":
        saved["progress"]["history"][1] = (1, 0.5, "x", 0.1, 0.0)
    elif change == "generator":
        saved["generator"] = torch.zeros(10, dtype=torch.uint8)
    elif change == "nan":
        saved["progress"]["best_val"] = float("nan")
    elif change == "steps":
        saved["optimizer"]["state"][0]["step"] = torch.tensor(99.0)
    elif change == "schedule":
        saved["schedule"]["last_epoch"] = 7
    elif change == "weight_decay":
        saved["optimizer"]["param_groups"][0]["weight_decay"] = float("nan")


@pytest.mark.parametrize("change, message", [
    ("key", "its key is not the fingerprint"), ("field", "expected the fields key, progress"),
    ("shape", "'features.0.0.weight' must be a (16, 1, 5, 5) torch.float32 tensor, got (3,)"),
    ("epoch", "history must be a list of 3 entries, got 2"), ("history", "history row 1 must be (1, "),
    ("generator", "generator 'state' must be a (5056,) torch.uint8 tensor"),
    ("nan", "best epoch 1 (validation loss nan) is not its history's (1, "),
    ("steps", "counts 99 steps, not the 4 of its epochs"), ("schedule", "stands at step 7, not the 4"),
    ("weight_decay", "settings weight_decay are not this run's")])
def test_resume_refuses_every_damaged_field_and_names_it(change, message, data, tmp_path, monkeypatch):
    cfg = TrainConfig(data=str(data), out=str(tmp_path / "run"), **SETTINGS)
    with monkeypatch.context() as patch:
        interrupt_after_epoch(patch, 1)
        with pytest.raises(KeyboardInterrupt):
            train(cfg)
    path = tmp_path / "run" / RESUME_FILE
    saved = torch.load(path, weights_only=True)
    _break(saved, change)
    torch.save(saved, path)
    with pytest.raises(InputError, match=re.escape(message)) as refused:
        train(cfg, resume=True)
    assert str(path) in str(refused.value) and refused.value.parameter == "out"
    assert not (tmp_path / "run" / "checkpoint.pt").exists()


def test_a_nan_best_loss_never_freezes_the_best_epoch():
    assert improves(0.5, float("nan")) and improves(0.5, float("inf")) and not improves(float("nan"), float("inf"))
    assert not improves(0.5, 0.5) and improves(0.4, 0.5)


def test_resume_takes_the_same_dataset_by_another_path(data, tmp_path, monkeypatch):
    link = tmp_path / "same.h5"
    link.symlink_to(data)
    with monkeypatch.context() as patch:
        interrupt_after_epoch(patch, 0)
        with pytest.raises(KeyboardInterrupt):
            train(TrainConfig(data=str(data), out=str(tmp_path / "run"), **SETTINGS))
    for other in (str(link), os.path.relpath(data)):
        assert fingerprint(TrainConfig(data=other, out="x", **SETTINGS), ["d"]) == \
            fingerprint(TrainConfig(data=str(data), out="y", **SETTINGS), ["d"])
    train(TrainConfig(data=str(link), out=str(tmp_path / "run"), **SETTINGS), resume=True)
    assert not (tmp_path / "run" / RESUME_FILE).exists() and (tmp_path / "run" / "checkpoint.pt").is_file()

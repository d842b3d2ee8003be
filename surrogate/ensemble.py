"""A deep ensemble of trained surrogates as one ONNX graph that returns its mean and spread.

    for k in 0 1 2 3 4; do roughness train DATA.h5 --out runs/m$k --seed $k; done
    roughness ensemble runs/m*/checkpoint.pt --out MODEL.onnx --data DATA.h5 [--int8 MODEL-int8.onnx]

The graph takes ``heights`` like a single model and returns ``log_roughness`` (the members' mean of
log(V + offset)), ``log_roughness_std`` (their standard deviation times ``std_scale``: the relative
spread of V + offset) and ``embedding`` (member 0's; the input domain is member 0's). The predictor
turns the spread into ``roughness_std`` (predictor.Estimate).

With ``--data`` (the members' training data, checked by its inputs checksum) the export measures the
uncertainty on the members' own validation split, never trained on: ``std_scale`` is chosen so that
95% of validation samples lie within 2 sigma of the mean (an ensemble of a few members is usually
over-confident), and ``max_std`` -- the default of ``predict --engine auto --max-std`` -- so that 10%
of validation inputs go to the FEM, counting those sent anyway as out of domain (member 0's domain). Their effect is then reported on the test split: the 2-sigma
coverage, the share sent to the FEM, and the share of predictions off by more than 15% that it catches.
Without ``--data`` neither is measured: ``std_scale`` is 1 and there is no default threshold.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import onnxruntime as ort
import torch
from torch import nn

from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.files import atomic_write, check_output
from roughness.core.hashing import file_sha256

from .domain import Domain
from .export import RTOL, ExportError, check_patches, load_checkpoint, write_graph
from .metadata import ModelMetadata
from .metrics import scores
from .network import RoughnessNet
from .patch import batch_descriptors
from .predictor import EMBEDDING_OUTPUT, INPUT, LOG_OUTPUT, STD_OUTPUT
from .target import roughness_from_log

MIN_MEMBERS = 2
COVERAGE = 0.95  # share of validation samples within 2 sigma after scaling
SENT_TO_FEM = 0.10  # share of validation inputs above the default threshold
LARGE_ERROR = 0.15  # "off by more than 15%": the predictions the threshold should catch
SHARED = ("patch_pixel_mm", "footprint_mm", "log_offset", "label_fidelity", "simulation")  # members must agree


class Ensemble(nn.Module):
    """Members' mean and (scaled) sample standard deviation of log(V + offset), and member 0's embedding."""

    def __init__(self, members: list[RoughnessNet], std_scale: float = 1.0) -> None:
        super().__init__()
        self.members = nn.ModuleList(members)
        self.register_buffer("std_scale", torch.tensor(float(std_scale)))

    def forward(self, heights: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        outputs = [member(heights) for member in self.members]
        logs = torch.stack([log_v for log_v, _ in outputs], dim=1)
        return logs.mean(dim=1), logs.std(dim=1) * self.std_scale, outputs[0][1]


def load_members(checkpoints: list[str | Path]) -> tuple[list[RoughnessNet], list[ModelMetadata]]:
    """The member networks and their metadata; InputError unless they predict the same quantity alike."""
    if len(checkpoints) < MIN_MEMBERS:
        raise InputError(f"an ensemble needs at least {MIN_MEMBERS} member checkpoints, got {len(checkpoints)}",
                         parameter="checkpoints")
    members, metas = zip(*(load_checkpoint(path) for path in checkpoints))
    for path, meta in zip(checkpoints[1:], metas[1:]):
        differ = [key for key in SHARED if getattr(meta, key) != getattr(metas[0], key)]
        if differ:
            raise InputError(f"{path} differs from {checkpoints[0]} in {', '.join(differ)}: the members must "
                             "imitate the same labels on the same input grid", parameter="checkpoints")
    return list(members), list(metas)


@torch.no_grad()
def member_logs(members: list[RoughnessNet], patches: np.ndarray, batch: int = 256) -> np.ndarray:
    """(n, members) predicted log(V + offset) for patches (n, P, P)."""
    out = []
    for i in range(0, len(patches), batch):
        x = torch.from_numpy(np.ascontiguousarray(patches[i:i + batch, None], dtype=np.float32))
        out.append(torch.stack([m.eval()(x)[0] for m in members], dim=1).numpy())
    return np.concatenate(out).astype(np.float64)


@torch.no_grad()
def out_of_domain(member: RoughnessNet, meta: ModelMetadata, patches: np.ndarray, batch: int = 256) -> np.ndarray:
    """Which patches (n, P, P) lie outside the member's input domain (the ensemble graph's domain is member 0's)."""
    embeddings = np.concatenate([member.eval()(torch.from_numpy(np.ascontiguousarray(
        patches[i:i + batch, None], dtype=np.float32)))[1].numpy() for i in range(0, len(patches), batch)])
    reasons = Domain.from_dict(meta.domain).check(batch_descriptors(patches, meta.patch_pixel_mm), embeddings)
    return np.array([bool(why) for why in reasons])


def calibrate(logs: np.ndarray, roughness: np.ndarray, split: np.ndarray, log_offset: float,
              outside: np.ndarray | None = None) -> dict:
    """``std_scale`` and ``max_std`` from the validation split and what they achieve on the test split.

    ``outside``: inputs out of domain (auto sends them to the FEM whatever their spread); the threshold
    spends only what is left of the SENT_TO_FEM budget (none if they alone exceed it).
    """
    mean, std = logs.mean(axis=1), logs.std(axis=1, ddof=1)
    outside = np.zeros(len(mean), bool) if outside is None else np.asarray(outside, bool)
    z = np.abs(np.log(roughness + log_offset) - mean) / np.maximum(std, 1e-12)
    val, test = split == "val", split == "test"
    if val.sum() < 10:
        raise InputError(f"{val.sum()} validation samples are too few to calibrate the uncertainty on",
                         parameter="data")
    std_scale = float(np.quantile(z[val], COVERAGE) / 2)
    inside = std[val & ~outside] * std_scale
    left = min(max(SENT_TO_FEM * val.sum() - (val & outside).sum(), 0) / max(len(inside), 1), 1.0)
    max_std = float(np.quantile(inside, 1 - left)) if len(inside) else float(std[val].max() * std_scale)
    out = {"std_scale": std_scale, "max_std": max_std, "validation_inputs": int(val.sum()),
           "raw_coverage_2sigma_val": float(np.mean(z[val] <= 2)),
           "out_of_domain_val": float(outside[val].mean())}
    if test.any():
        predicted = roughness_from_log(mean[test], log_offset)
        rel = np.abs(predicted - roughness[test]) / np.maximum(roughness[test], 1e-12)
        sent = (std[test] * std_scale > max_std) | outside[test]
        large = rel > LARGE_ERROR
        out |= {"test_inputs": int(test.sum()), "coverage_2sigma_test": float(np.mean(z[test] <= 2 * std_scale)),
                "sent_to_fem_test": float(sent.mean()), "out_of_domain_test": float(outside[test].mean()),
                "large_errors_test": int(large.sum()),
                "large_errors_caught_test": float(sent[large].mean()) if large.any() else None}
    return out


def export_ensemble(checkpoints: list[str | Path], out: str | Path,
                    data: str | Path | list[str | Path] | None = None, overwrite: bool = False,
                    model_version: int = 1) -> dict:
    """Write the ensemble graph (checked against PyTorch) and return what was measured; see the module docstring.

    ``model_version``: the ONNX ``model_version`` field (surrogate/versioning.py)."""
    out = check_output(out, overwrite, "out")
    integer("model_version", model_version, minimum=1)
    members, metas = load_members(checkpoints)
    first = metas[0]
    info: dict = {"members": len(members), "member_sha256": [file_sha256(p)[:16] for p in checkpoints],
                  "member_val": [m.metrics.get("val") for m in metas], "std_scale": 1.0, "max_std": None}
    metrics, by_family = first.metrics, first.test_by_family
    if data is not None:
        samples = _samples(data, first)
        logs = member_logs(members, samples.patches)
        info |= calibrate(logs, samples.roughness, samples.split, first.log_offset, out_of_domain(members[0], first,
                                                                                                samples.patches))
        predicted = roughness_from_log(logs.mean(axis=1), first.log_offset)
        metrics = {s: scores(samples.roughness[samples.split == s], predicted[samples.split == s])
                   for s in ("train", "val", "test", "ood") if (samples.split == s).any()}
        by_family = _scores_by_family(samples, predicted, samples.split == "test")
        info["ood_by_family"] = _scores_by_family(samples, predicted, samples.split == "ood")  # held-out families
    info["metrics_of"] = "ensemble" if data is not None else "member 0 (no --data given)"
    meta = replace(first, metrics=metrics, test_by_family=by_family, ensemble=info,
                   parameters=sum(m.parameters for m in metas), minutes=sum(m.minutes for m in metas),
                   cost_core_seconds={"data_fem": first.cost_core_seconds.get("data_fem", 0.0),
                                      "training": sum(m.cost_core_seconds.get("training", 0.0) for m in metas)})
    model = Ensemble(members, info["std_scale"]).eval()
    patches = check_patches(8)
    report: dict = {}

    def write(tmp: str) -> None:
        write_graph(model, patches, [LOG_OUTPUT, STD_OUTPUT, EMBEDDING_OUTPUT], meta, model_version, tmp)
        report.update(_verify(model, tmp, patches))

    atomic_write(out, write, overwrite)
    return {"path": str(out), "bytes": out.stat().st_size, "model_version": model_version, "check": report, **info}


def _scores_by_family(samples, predicted: np.ndarray, rows: np.ndarray) -> dict[str, dict]:
    """``scores`` of the predictions per family, over the selected rows."""
    return {f: scores(samples.roughness[rows & (samples.family == f)], predicted[rows & (samples.family == f)])
            for f in np.unique(samples.family[rows])}


def _samples(data: str | Path | list[str | Path], meta: ModelMetadata):
    """The members' training data (a multi-fidelity model's files, primary first) with their splits,
    labels at the spacing the model answers for; InputError if it is other data."""
    from contextlib import ExitStack

    from roughness.dataset.digest import inputs_sha256
    from roughness.dataset.reader import open_dataset

    from .data import load_samples

    paths = [data] if isinstance(data, (str, Path)) else list(data)
    expected = [meta.data.get("inputs_sha256")] + [e["inputs_sha256"] for e in (meta.multi_fidelity or {}).get(
        "extra_data", [])]
    if len(paths) != len(expected) or any(inputs_sha256(p) != e for p, e in zip(paths, expected)):
        raise InputError(f"{', '.join(map(str, paths))} is not the data the members were trained on ({len(expected)} "
                         "file(s) with the inputs checksums of their metadata): its validation split would not be "
                         "held out", parameter="data")
    with ExitStack() as stack:
        datasets = [stack.enter_context(open_dataset(p)) for p in paths]
        samples = load_samples(datasets, meta.test_fraction, meta.train_config["val_fraction"], meta.holdout_family,
                               progress=False, levels=meta.train_config.get("levels", "last"),
                               max_label_error=meta.train_config.get("max_label_error"))
    return samples if meta.query_h_mm is None else samples.at_level(meta.query_h_mm)


def _verify(model: Ensemble, path: str, patches: np.ndarray) -> dict:
    """onnxruntime matches PyTorch (mean, spread, embedding) at batch 1 and the full batch."""
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    session = ort.InferenceSession(path, options, providers=["CPUExecutionProvider"])
    with torch.no_grad():
        reference = [t.numpy() for t in model(torch.from_numpy(patches))]
    single = [np.concatenate(parts) for parts in zip(*(session.run(None, {INPUT: patches[i:i + 1]})
                                                       for i in range(len(patches))))]
    worst = 0.0
    for got in (single, session.run(None, {INPUT: patches})):
        for g, r in zip(got, reference):
            worst = max(worst, float(np.max(np.abs(g - r)) / max(float(np.max(np.abs(r))), 1e-12)))
    if not worst < RTOL:
        raise ExportError(f"onnxruntime differs from PyTorch by {worst:.2e} (relative; limit {RTOL:.0e})")
    return {"max_rel_diff": worst, "checked_inputs": len(patches)}


"""Training data for the surrogate: footprint patches, targets and splits from dataset files (torch-free).

Splits are drawn per *base texture* (family, parameters, texture seed; perturbation ignored),
so no perturbed sibling of a test texture is trained on; the held-out family goes to "ood".

Labels: one row per sample (its V, at the dataset's contact spacing), or with ``levels="all"``
one row per (sample, mesh level) over every level the FEM solved for it (``ladder_h_mm`` and
``ladder_V``: a ``default`` label comes with its ``coarse`` one) and over several files of the
same textures at other fidelities: the multi-fidelity rows a spacing-conditioned network
learns from (``h_mm`` is each row's contact spacing). Rows of the spectral engine (``engine``
"spectral") have no contact spacing (``h_mm`` nan). ``max_label_error`` keeps only the FEM labels
whose estimated discretization error is at most that fraction (each sample's finest level).
"""
from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import dataclass, fields

import numpy as np

from roughness.core.errors import InputError
from roughness.core.status_line import StatusLine
from roughness.dataset.reader import Dataset, Sample

from .patch import descriptors, footprint_patch


def base_key(record: dict) -> str:
    """Identity of the unperturbed texture a sample was made from."""
    # Not roughness.core.hashing.digest: its compact JSON would move 899 of training-v1's 3,000 samples
    # to another split, so the shipped model's held-out test set would hold training samples.
    base = {k: record[k] for k in ("family", "params", "seed")}
    return hashlib.sha1(json.dumps(base, sort_keys=True).encode()).hexdigest()


def families_in(record: dict) -> set[str]:
    """The families a texture is made of: its own and, for a composite (mixture, shallow), its base and overlay."""
    params = record.get("params") or {}
    return {record["family"]} | {params[k] for k in ("base", "overlay") if isinstance(params.get(k), str)}


def held_out_name(family: str, holdout_family: str | None) -> str:
    """How a family of held-out samples is named in scores: a composite is held out for a family it is made of."""
    held = (holdout_family or "").split(",")
    return family if family in held else f"{family} made with {' or '.join(held)}"


def split_of(record: dict, test_fraction: float, val_fraction: float, holdout_family: str | None) -> str:
    """Which split a sample belongs to: a fixed function of its base texture.

    ``holdout_family``: the family never trained on ("ood"), or several, comma-separated ("knit,waffle"); a
    composite texture with a held-out family as its base or overlay is held out with it.
    """
    if holdout_family and families_in(record) & set(holdout_family.split(",")):
        return "ood"
    u = int(base_key(record)[:8], 16) / 2**32
    return "test" if u < test_fraction else "val" if u < test_fraction + val_fraction else "train"


@dataclass
class Samples:
    """Patches (n, P, P) in mm (max 0), FEM V, and per-sample labels."""

    ids: np.ndarray
    patches: np.ndarray
    roughness: np.ndarray
    family: np.ndarray
    split: np.ndarray
    descriptors: np.ndarray  # (n, len(DESCRIPTOR_NAMES))
    h_mm: np.ndarray  # contact spacing (mm) of each row's FEM label (nan: a spectral label, or not recorded)
    engine: np.ndarray  # the engine of each row's label: "fem" or "spectral"

    def where(self, keep: np.ndarray) -> Samples:
        """The rows where ``keep`` is true."""
        return Samples(*(getattr(self, f.name)[keep] for f in fields(self)))

    def at_level(self, h_mm: float) -> Samples:
        """The rows labelled by the FEM at contact spacing ``h_mm``."""
        return self.where(np.isclose(self.h_mm, h_mm))

    def __len__(self) -> int:
        return len(self.ids)


def labels(sample: Sample, spacing_mm: float, levels: str) -> list[tuple[float, float]]:
    """(contact spacing in mm, V) of a sample: its V, or with ``levels="all"`` every level solved for it."""
    ladder = list(zip(sample.values.get("ladder_h_mm", []), sample.values.get("ladder_V", [])))
    if levels == "all" and ladder:
        return ladder
    return [(ladder[-1][0] if ladder else spacing_mm, sample.values["V"])]


def load_samples(data: Dataset | list[Dataset], test_fraction: float = 0.1, val_fraction: float = 0.1,
                 holdout_family: str | None = "knit", progress: bool = True, levels: str = "last",
                 max_label_error: float | None = None) -> Samples:
    """Every ok sample of open datasets as a footprint patch with its split and label rows.

    ``levels``: "last" (one row per sample: its V) or "all" (a row per solved mesh level; a
    level found in several files counts once, from the first). ``max_label_error``: FEM samples
    whose estimated discretization error exceeds this fraction give no row, the others only their
    finest level (coarser levels are less converged than the estimate says).
    """
    if levels not in LEVELS:
        raise InputError(f"levels must be one of {', '.join(LEVELS)}, got {levels!r}", parameter="levels")
    if max_label_error is not None and not max_label_error > 0:
        raise InputError(f"max_label_error must be a positive fraction, got {max_label_error!r}",
                         parameter="max_label_error")
    datasets = data if isinstance(data, list) else [data]
    rows: dict[str, list] = {f.name: [] for f in fields(Samples)}
    seen: set[tuple[str, str, float | None]] = set()
    made: dict[str, tuple[np.ndarray, np.ndarray]] = {}  # sample id -> (patch, descriptors), made once
    start, line = time.monotonic(), StatusLine()
    for ds in datasets:
        spacing, engine = _spacing_mm(ds.config.simulation), ds.config.simulation.get("engine", "fem")
        read = 0
        for read, sample in enumerate(ds.iter_samples("ok"), 1):
            if progress and read % 250 == 0:
                line.show(_reading(ds, read, start))
            rows_of = labels(sample, spacing, levels)
            if engine == "fem" and max_label_error is not None:
                error = sample.values.get("discretization_error")
                rows_of = rows_of[-1:] if error is not None and error <= max_label_error else []
            if not rows_of:
                continue
            if sample.id not in made:
                patch = footprint_patch(sample.heightmap)
                made[sample.id] = patch, descriptors(patch)
            patch, descr = made[sample.id]
            split = split_of(sample.texture_record, test_fraction, val_fraction, holdout_family)
            for h_mm, v in rows_of:
                level = (sample.id, engine, None if math.isnan(h_mm) else round(h_mm, 6))
                if level in seen:
                    continue
                seen.add(level)
                for key, value in (("ids", sample.id), ("patches", patch), ("roughness", v), ("split", split),
                                   ("family", sample.texture_record["family"]), ("descriptors", descr), ("h_mm", h_mm),
                                   ("engine", engine)):
                    rows[key].append(value)
        if progress:
            line.show(_reading(ds, read, start), last=True)
            line.close()
    if not rows["ids"]:
        raise InputError(f"{', '.join(str(ds.path) for ds in datasets)} holds no ok samples to train on")
    return Samples(*(np.asarray(rows[f.name], dtype=float if f.name == "h_mm" else None) for f in fields(Samples)))


def _reading(ds: Dataset, read: int, start: float) -> str:
    """The progress line of ``load_samples``: ok samples read of the file's samples, seconds since ``start``."""
    return f"reading {ds.path}: {read}/{len(ds)} samples ({time.monotonic() - start:.0f} s)"


LEVELS = ("last", "all")


def _spacing_mm(simulation: dict) -> float:
    """Contact spacing (mm) of a dataset's labels from its simulation configuration (nan if not fixed, and for
    the spectral engine, which has no mesh)."""
    from roughness.simulate.config import FIDELITY_SPACING_MM

    if simulation.get("engine", "fem") != "fem":
        return math.nan
    if simulation.get("h_contact_mm") is not None:
        return float(simulation["h_contact_mm"])
    return FIDELITY_SPACING_MM.get(simulation.get("fidelity", "default"), math.nan)

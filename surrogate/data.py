"""Training data for the surrogate: footprint patches, targets and splits from a dataset file (torch-free).

Splits are drawn per *base texture* (family, parameters, texture seed; perturbation ignored),
so no perturbed sibling of a test texture is trained on; the held-out family goes to "ood".
"""
from __future__ import annotations

import hashlib
import json
import sys
import time
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError
from roughness.dataset.store import Dataset

from .patch import descriptors, footprint_patch


def base_key(record: dict) -> str:
    """Identity of the unperturbed texture a sample was made from."""
    # Not roughness.core.hashing.digest: its compact JSON would move 899 of training-v1's 3,000 samples
    # to another split, so the shipped model's held-out test set would hold training samples.
    base = {k: record[k] for k in ("family", "params", "seed")}
    return hashlib.sha1(json.dumps(base, sort_keys=True).encode()).hexdigest()


def split_of(record: dict, test_fraction: float, val_fraction: float, holdout_family: str | None) -> str:
    """Which split a sample belongs to: a fixed function of its base texture.

    ``holdout_family``: the family never trained on ("ood"), or several, comma-separated ("knit,waffle").
    """
    if holdout_family and record["family"] in holdout_family.split(","):
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

    def subset(self, split: str) -> Samples:
        keep = self.split == split
        return Samples(*(getattr(self, f)[keep] for f in ("ids", "patches", "roughness", "family", "split",
                                                          "descriptors")))

    def __len__(self) -> int:
        return len(self.ids)


def load_samples(data: Dataset, test_fraction: float = 0.1, val_fraction: float = 0.1,
                 holdout_family: str | None = "knit", progress: bool = True) -> Samples:
    """Every ok sample of an open dataset as a footprint patch, with its split."""
    rows: dict[str, list] = {k: [] for k in ("ids", "patches", "roughness", "family", "split", "descriptors")}
    total, start = len(data), time.monotonic()
    for i, sample in enumerate(data.iter_samples("ok")):
        patch = footprint_patch(sample.heightmap)
        for key, value in (("ids", sample.id), ("patches", patch), ("roughness", sample.values["V"]),
                           ("family", sample.recipe["family"]), ("descriptors", descriptors(patch)),
                           ("split", split_of(sample.recipe, test_fraction, val_fraction, holdout_family))):
            rows[key].append(value)
        if progress and (i + 1) % 250 == 0:
            print(f"\rreading {data.path}: {i + 1}/{total} samples ({time.monotonic() - start:.0f} s)",
                  end="", file=sys.stderr, flush=True)
    if progress:
        print(file=sys.stderr)
    if not rows["ids"]:
        raise InputError(f"{data.path} holds no ok samples to train on")
    return Samples(*(np.asarray(rows[k]) for k in ("ids", "patches", "roughness", "family", "split", "descriptors")))

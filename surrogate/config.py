"""Training configuration (torch-free, so the CLI reads its defaults without importing torch)."""
from __future__ import annotations

from dataclasses import dataclass

from .target import LOG_OFFSET


@dataclass(frozen=True)
class TrainConfig:
    data: str  # HDF5 dataset file
    out: str  # output folder (created; must not exist unless overwriting)
    seed: int = 0
    holdout_family: str | None = None  # None: the dataset recipe's; "none": no family held out
    test_fraction: float | None = None  # None: the dataset recipe's
    val_fraction: float = 0.1
    widths: tuple[int, ...] = (16, 32, 64, 96)
    hidden: int = 64
    batch_size: int = 32  # also the minimum number of training samples
    learning_rate: float = 3e-3
    weight_decay: float = 1e-4
    max_epochs: int = 200
    patience: int = 60  # epochs without a better validation loss before stopping (the cosine schedule runs to 0)
    max_minutes: float = 25.0  # wall-clock budget; the best checkpoint so far is kept
    threads: int = 2  # torch threads
    extra_data: tuple[str, ...] = ()  # more files of the same recipe's textures at other fidelities ("all" levels)
    levels: str = "last"  # "last": each sample's V; "all": every solved mesh level, spacing as an input
    query_h_mm: float | None = None  # "all": the contact spacing (mm) the model answers for (default: finest)
    max_label_error: float | None = None  # keep only FEM labels whose estimated discretization error is at most this
    fem_weight: float = 1.0  # loss weight of a FEM label row relative to a spectral one
    log_offset: float = LOG_OFFSET  # the network predicts log(V + log_offset) (V of the finest standard: ~0.003)

    def minimum_samples(self, test_fraction: float = 0.1) -> int:
        """About how many ok samples a dataset needs: ``batch_size`` training samples after the splits."""
        return int(-(-self.batch_size // (1 - test_fraction - self.val_fraction)))

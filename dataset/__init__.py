"""Textures, perturbations and the HDF5 dataset of FEM results (torch-free reader: ``dataset.open``)."""
from __future__ import annotations

__all__ = ["open", "open_dataset"]


def __getattr__(name: str):
    """``open``/``open_dataset`` load the reader (h5py) on first use, not with every dataset module."""
    if name in __all__:
        from .reader import open_dataset

        return open_dataset
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

"""Textures, perturbations and the HDF5 dataset of FEM results (torch-free reader: ``dataset.open``)."""
from .store import open_dataset

open = open_dataset  # noqa: A001  (dataset.open(path) reads a dataset file)

__all__ = ["open", "open_dataset"]

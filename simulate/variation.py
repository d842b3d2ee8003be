"""Strain variation V: mean absolute difference of a field between paired disk samples."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PairSampling:
    """Disk pairs (radius r, centres d apart) placed uniformly in a square window."""

    window_mm: float = 8.0
    distance_mm: float = 0.8
    radius_mm: float = 0.8
    pairs: int = 8000
    seed: int = 0

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """Two (pairs, 2) arrays of sample points (mm, window centred at 0)."""
        rng = np.random.default_rng(self.seed)
        half = self.window_mm / 2 - self.distance_mm / 2 - self.radius_mm
        if half <= 0:
            raise ValueError("disk pairs do not fit in the sampling window")
        mid = rng.uniform(-half, half, (self.pairs, 2))
        theta = rng.uniform(0, 2 * np.pi, self.pairs)
        axis = np.c_[np.cos(theta), np.sin(theta)] * (self.distance_mm / 2)
        return mid - axis + self._in_disk(rng), mid + axis + self._in_disk(rng)

    def _in_disk(self, rng: np.random.Generator) -> np.ndarray:
        rad = self.radius_mm * np.sqrt(rng.uniform(0, 1, self.pairs))
        phi = rng.uniform(0, 2 * np.pi, self.pairs)
        return np.c_[rad * np.cos(phi), rad * np.sin(phi)]


def variation(field: np.ndarray, axis: np.ndarray, sampling: PairSampling) -> tuple[float, float]:
    """V = mean |s(p1) - s(p2)| and its Monte Carlo standard error.

    ``field`` is sampled on the grid ``axis`` (mm) in both directions (row = y).
    """
    p1, p2 = sampling.points()
    step = axis[1] - axis[0]

    def at(p: np.ndarray) -> np.ndarray:
        return bilinear(field, (p[:, 1] - axis[0]) / step, (p[:, 0] - axis[0]) / step)

    diff = np.abs(at(p1) - at(p2))
    return float(diff.mean()), float(diff.std(ddof=1) / np.sqrt(len(diff)))


def bilinear(field: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """``field`` linearly interpolated at fractional (row, column) indices inside it (numpy only: no scipy
    import on the spectral engine's path; the same values as scipy.ndimage.map_coordinates, order 1)."""
    r0 = np.clip(np.floor(rows).astype(int), 0, field.shape[0] - 2)
    c0 = np.clip(np.floor(cols).astype(int), 0, field.shape[1] - 2)
    fr, fc = rows - r0, cols - c0
    top = field[r0, c0] * (1 - fc) + field[r0, c0 + 1] * fc
    bottom = field[r0 + 1, c0] * (1 - fc) + field[r0 + 1, c0 + 1] * fc
    return top * (1 - fr) + bottom * fr

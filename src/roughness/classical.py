"""Classical roughness measures the paper compared its model against, on the skin footprint.

All take the 10 mm footprint of a heightmap (box-averaged to 0.05 mm, the printer's pixel):
- ``ra``: arithmetic mean deviation from the mean height (mm);
- ``p90``: 90th percentile of the height above the lowest point (mm);
- ``glcm_sum_of_squares``: Haralick's "sum of squares: variance" (f4), sum over i, j of (i - mu)^2 P(i, j);
- ``glcm_sum_variance``: Haralick's "sum variance" (f7), the variance of i + j under P.
The grey-level co-occurrence matrix P quantises heights to 32 levels over the footprint's range and
pools the four directions at a one-pixel offset (symmetric, normalised; scikit-image).
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from roughness.surface.heightmap import Heightmap
from roughness.surrogate.patch import FOOTPRINT_MM, footprint_patch

PIXEL_MM = 0.05
LEVELS = 32


def footprint(heightmap: Heightmap) -> np.ndarray:
    return footprint_patch(heightmap, pixel_mm=PIXEL_MM, width_mm=FOOTPRINT_MM).astype(float)


def ra(h: np.ndarray) -> float:
    return float(np.mean(np.abs(h - h.mean())))


def p90(h: np.ndarray) -> float:
    return float(np.percentile(h - h.min(), 90))


def glcm(h: np.ndarray) -> np.ndarray:
    """(LEVELS, LEVELS) co-occurrence probabilities, four directions pooled."""
    from skimage.feature import graycomatrix

    span = h.max() - h.min()
    levels = np.zeros(h.shape, np.uint8) if span == 0 else np.minimum(
        ((h - h.min()) / span * LEVELS).astype(np.uint8), LEVELS - 1)
    p = graycomatrix(levels, [1], [0, np.pi / 4, np.pi / 2, 3 * np.pi / 4], LEVELS, symmetric=True, normed=True)
    return p[:, :, 0, :].mean(axis=2)


def glcm_sum_of_squares(h: np.ndarray) -> float:
    p = glcm(h)
    i = np.arange(LEVELS)[:, None]
    mu = float(np.sum(i * p))
    return float(np.sum((i - mu) ** 2 * p))


def glcm_sum_variance(h: np.ndarray) -> float:
    p = glcm(h)
    i, j = np.indices(p.shape)
    sums = np.bincount((i + j).ravel(), p.ravel(), 2 * LEVELS - 1)
    k = np.arange(2 * LEVELS - 1)
    mean = float(np.sum(k * sums))
    return float(np.sum((k - mean) ** 2 * sums))


MEASURES: dict[str, Callable[[np.ndarray], float]] = {
    "ra": ra, "p90": p90, "glcm_sum_of_squares": glcm_sum_of_squares, "glcm_sum_variance": glcm_sum_variance,
}

"""Edges follow the shapes, not the pixels: a low-resolution picture's regions enlarged with smooth boundaries.

Each region's indicator (1 inside, 0 outside, on the picture's pixels) is blurred with a Gaussian of ``SIGMA_PX``
picture pixels and read at every plate pixel's centre (bilinear); the plate pixel goes to the region whose blurred
indicator is largest there. A straight edge stays where it was (a blurred step is 1/2 on the step), a pixel
staircase along a curve becomes the curve it approximates, and a corner is rounded by about a pixel. On the
bundled 60 x 40 pixel drawing on a 48 mm plate (0.8 mm pixels), the disc's edge departs from a fitted circle by
0.43 mm at most (RMS 0.19 mm) enlarged pixel by pixel, 0.15 mm (RMS 0.06 mm) smoothed (tests).
Lines (a mask) are blurred less (``LINE_SIGMA_PX``) and kept where the blur exceeds ``LINE_LEVEL``, so that a
stroke one pixel wide survives (its centre line is what the raised line follows).
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

SIGMA_PX = 1.0
LINE_SIGMA_PX = 0.7
LINE_LEVEL = 0.3


def _sample(values: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """``values`` (picture pixels) read bilinearly at the centres of a (ny, nx) grid spanning the same picture."""
    h, w = values.shape
    ny, nx = shape
    rows = (np.arange(ny) + 0.5) * h / ny - 0.5
    cols = (np.arange(nx) + 0.5) * w / nx - 0.5
    out = np.empty(shape)
    step = max(1, (1 << 20) // nx)  # rows at a time: bounded memory for the coordinates
    for top in range(0, ny, step):
        r, c = np.meshgrid(rows[top:top + step], cols, indexing="ij")
        out[top:top + step] = ndimage.map_coordinates(values, [r, c], order=1, mode="nearest")
    return out


def smooth_labels(labels: np.ndarray, shape: tuple[int, int], sigma_px: float = SIGMA_PX) -> np.ndarray:
    """Region indices (>= 0) of a picture on a (ny, nx) plate grid with smooth boundaries (module docstring)."""
    best = np.full(shape, -np.inf)
    out = np.zeros(shape, dtype=labels.dtype)
    for k in np.unique(labels):
        blurred = ndimage.gaussian_filter((labels == k).astype(float), sigma_px, mode="nearest")
        value = _sample(blurred, shape)
        better = value > best
        out[better] = k
        best[better] = value[better]
    return out


def smooth_mask(mask: np.ndarray, shape: tuple[int, int], sigma_px: float = LINE_SIGMA_PX,
                level: float = LINE_LEVEL) -> np.ndarray:
    """A picture's line mask on a (ny, nx) plate grid, blurred and kept above ``level`` (module docstring)."""
    return _sample(ndimage.gaussian_filter(mask.astype(float), sigma_px, mode="nearest"), shape) > level

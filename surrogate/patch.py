"""The surrogate's input: the heightmap under the 10 mm skin footprint, on the model's pixel grid.

Numpy only (prediction runs without torch). The patch is box-averaged from the heightmap
(bilinear sub-samples, so any input pixel size works; a 0.05 mm map averages exactly 2x2
pixels into 0.1 mm) and referenced to its highest point, as the FEM presses the skin onto
the highest point of the footprint: every value is <= 0 mm.
"""
from __future__ import annotations

import math

import numpy as np

from roughness.simulate.heightmap import Heightmap, bracket

FOOTPRINT_MM = 10.0  # the skin block's width (simulate.config default)
PATCH_PIXEL_MM = 0.1  # model pixel size
PATCH_SIZE = round(FOOTPRINT_MM / PATCH_PIXEL_MM)
DESCRIPTOR_NAMES = ("relief_mm", "feature_mm", "rms_slope", "p99_slope")


def footprint_patch(heightmap: Heightmap, centre_mm: tuple[float, float] | None = None, tile: bool = False,
                    pixel_mm: float = PATCH_PIXEL_MM, width_mm: float = FOOTPRINT_MM) -> np.ndarray:
    """Heights (mm, max 0) of the footprint square centred at ``centre_mm`` on ``pixel_mm`` pixels.

    Each patch pixel is the mean of sub x sub bilinear samples of the map (sub = ceil(pixel_mm /
    map pixel)); bilinear sampling is separable, so the patch is Wy @ H @ Wx.T with sparse-banded
    averaging matrices. Raises InputError (from the heightmap) if the footprint leaves a non-tiled map.
    """
    heightmap.require_footprint(width_mm, centre_mm, tile)
    cx, cy = centre_mm or heightmap.centre_mm
    n = round(width_mm / pixel_mm)
    sub = max(1, math.ceil(pixel_mm / heightmap.pixel_mm - 1e-9))
    ny, nx = heightmap.shape
    rows, wy = _averaging(cy - width_mm / 2, n, pixel_mm, sub, heightmap.pixel_mm, ny, tile)
    cols, wx = _averaging(cx - width_mm / 2, n, pixel_mm, sub, heightmap.pixel_mm, nx, tile)
    patch = wy @ heightmap.heights[np.ix_(rows, cols)] @ wx.T
    return (patch - patch.max()).astype(np.float32)


def _averaging(start_mm: float, n: int, pixel_mm: float, sub: int, map_pixel_mm: float, size: int,
               periodic: bool) -> tuple[np.ndarray, np.ndarray]:
    """Map indices used along one axis and the (n, len(indices)) weights averaging their bilinear samples."""
    offsets = (np.arange(sub) + 0.5) / sub * pixel_mm
    u = ((start_mm + np.arange(n)[:, None] * pixel_mm + offsets) / map_pixel_mm - 0.5).ravel()
    lower, upper, frac = bracket(u, size, periodic)
    used, index = np.unique(np.concatenate([lower, upper]), return_inverse=True)
    row = np.tile(np.arange(n * sub) // sub, 2)  # patch pixel of each sub-sample
    weights = np.bincount(row * len(used) + index, np.concatenate([1 - frac, frac]) / sub, n * len(used))
    return used, weights.reshape(n, len(used))


def descriptors(patch: np.ndarray, pixel_mm: float = PATCH_PIXEL_MM) -> np.ndarray:
    """Hand-made shape descriptors of a patch, in DESCRIPTOR_NAMES order.

    relief (mm): 99.5th minus 0.5th percentile height; feature (mm): 2 pi std / rms slope (capped
    at 100 mm for flat patches); rms and 99th-percentile slope magnitude (dimensionless).
    """
    gy, gx = np.gradient(patch.astype(float), pixel_mm)
    slope = np.hypot(gx, gy)
    rms = float(np.sqrt(np.mean(slope**2)))
    lo, hi = np.percentile(patch, [0.5, 99.5])
    feature = min(100.0, 2 * math.pi * float(np.std(patch)) / rms) if rms > 0 else 100.0
    return np.array([hi - lo, feature, rms, np.percentile(slope, 99)])

"""Non-square pixels made square: bilinear resampling of a (ny, nx) grid to the finer of its two pixel sizes.

The engines take square pixels; a scan with 10 x 12 um pixels is resampled only when asked
(``resample_square``), never read as if its pixels were square.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, check_size

from .heightmap import bracket

CHUNK_VALUES = 1 << 20  # values per block of output rows (8 MB: the temporaries stay small)


@dataclass(frozen=True)
class Resampling:
    """What ``square`` did: shapes (ny, nx) in pixels and pixel sizes in mm before and after."""

    shape_before: tuple[int, int]
    pixel_before_mm: tuple[float, float]  # (x, y)
    shape_after: tuple[int, int]
    pixel_after_mm: float

    def describe(self) -> str:
        (ny, nx), (px, py), (my, mx) = self.shape_before, self.pixel_before_mm, self.shape_after
        return (f"resampled (bilinear) from {nx} x {ny} pixels of {px:.6g} mm (x) by {py:.6g} mm (y) to "
                f"{mx} x {my} square pixels of {self.pixel_after_mm:.6g} mm")

    def as_dict(self) -> dict:
        return {"method": "bilinear", "shape_before": list(self.shape_before),
                "pixel_before_mm": list(self.pixel_before_mm), "shape_after": list(self.shape_after),
                "pixel_after_mm": self.pixel_after_mm}


def square(heights: np.ndarray, pixel_x_mm: float, pixel_y_mm: float) -> tuple[np.ndarray, Resampling]:
    """``heights`` (ny, nx) on pixels of ``pixel_x_mm`` x ``pixel_y_mm`` resampled bilinearly to square pixels
    of the smaller size, covering the same extent (sides rounded to whole pixels).

    The size is checked first (MAX_HEIGHTMAP_PIXELS), and the output is made in blocks of rows, so that
    resampling holds the output and temporaries of CHUNK_VALUES values, whatever the ratio of the pixel sizes
    (whole-map temporaries took five times the output: gigabytes at a 1000:1 ratio)."""
    ny, nx = heights.shape
    pixel = min(pixel_x_mm, pixel_y_mm)
    mx, my = max(2, round(nx * pixel_x_mm / pixel)), max(2, round(ny * pixel_y_mm / pixel))
    check_size(f"pixels of the {nx} x {ny} map resampled to square pixels of {pixel:g} mm ({mx:,} x {my:,})",
               mx * my, MAX_HEIGHTMAP_PIXELS, "resample_square")
    j0, j1, fx = bracket((np.arange(mx) + 0.5) * pixel / pixel_x_mm - 0.5, nx, False)
    i0, i1, fy = bracket((np.arange(my) + 0.5) * pixel / pixel_y_mm - 0.5, ny, False)
    out = np.empty((my, mx))
    block = max(1, CHUNK_VALUES // max(nx, mx))
    for start in range(0, my, block):
        b = slice(start, start + block)
        rows = heights[i0[b]] * (1 - fy[b])[:, None] + heights[i1[b]] * fy[b, None]  # (block, nx)
        out[b] = rows[:, j0] * (1 - fx) + rows[:, j1] * fx
    return out, Resampling((ny, nx), (pixel_x_mm, pixel_y_mm), (my, mx), pixel)

"""Heightmaps with physical units (mm).

Pixel (i, j) holds the height at x = (j + 0.5) * pixel_mm, y = (i + 0.5) * pixel_mm, so a
(ny, nx) map covers [0, nx * pixel_mm] x [0, ny * pixel_mm]; z points up, out of the texture.
"""
from __future__ import annotations

import math
import numbers
import sys
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.core.limits import (
    MAX_COORDINATE_MM,
    MAX_HEIGHT_MM,
    MAX_HEIGHTMAP_PIXELS,
    MAX_PIXEL_MM,
    MIN_PIXEL_MM,
    PIXEL_RTOL,
    check_size,
)
from roughness.core.reprs import shape_text, short_repr

TOLERANCE_MM = 1e-9


@dataclass(frozen=True)
class Heightmap:
    """Heights (ny, nx) in mm on square pixels of ``pixel_mm``; row index -> y, column -> x.

    ``heights`` is stored as a read-only float64 C-contiguous copy.
    """

    heights: np.ndarray
    pixel_mm: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "heights", _checked_heights(self.heights))
        object.__setattr__(self, "pixel_mm", pixel_size(self.pixel_mm))

    def __repr__(self) -> str:
        h = self.heights
        width, height = self.size_mm
        return short_repr(self, f"{shape_text(self.shape)} px", f"pixel {self.pixel_mm:g} mm",
                          f"{width:g} x {height:g} mm", f"heights {h.min():.4g}..{h.max():.4g} mm")

    @property
    def shape(self) -> tuple[int, int]:
        """(ny, nx) in pixels."""
        ny, nx = self.heights.shape
        return ny, nx

    @property
    def size_mm(self) -> tuple[float, float]:
        """(width along x, height along y) in mm."""
        ny, nx = self.shape
        return nx * self.pixel_mm, ny * self.pixel_mm

    @property
    def centre_mm(self) -> tuple[float, float]:
        """(x, y) of the map centre in mm."""
        width, height = self.size_mm
        return width / 2, height / 2

    def sample(self, x_mm: np.ndarray, y_mm: np.ndarray, periodic: bool = False) -> np.ndarray:
        """Bilinearly interpolated heights (mm) at points (mm); broadcasts x and y.

        Non-periodic: points beyond the outermost pixel centres take the edge value.
        Periodic: the map is one period of the texture, interpolated across the wrap.
        """
        x, y = np.broadcast_arrays(np.asarray(x_mm, dtype=float), np.asarray(y_mm, dtype=float))
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise InputError("sample coordinates must be finite",
                             parameter="x_mm" if not np.isfinite(x).all() else "y_mm")
        ny, nx = self.shape
        j0, j1, fx = bracket(x / self.pixel_mm - 0.5, nx, periodic)
        i0, i1, fy = bracket(y / self.pixel_mm - 0.5, ny, periodic)
        h = self.heights
        top = h[i0, j0] * (1 - fx) + h[i0, j1] * fx
        bottom = h[i1, j0] * (1 - fx) + h[i1, j1] * fx
        return top * (1 - fy) + bottom * fy

    def covers(self, width_mm: float, centre_mm: tuple[float, float] | None = None) -> bool:
        """True if the square of side ``width_mm`` centred at ``centre_mm`` (default: map centre) lies on the map."""
        half = positive("footprint width", width_mm) / 2
        cx, cy = centre_mm or self.centre_mm
        width, height = self.size_mm
        slack = self.slack_mm
        return (cx - half >= -slack and cx + half <= width + slack
                and cy - half >= -slack and cy + half <= height + slack)

    @property
    def slack_mm(self) -> float:
        """How far (mm) the map's edges are uncertain: its size times the pixel size's precision (PIXEL_RTOL), so a
        200-pixel map of 0.05 mm stored as float32 metres (9.99999974 mm) covers a 10 mm footprint."""
        return PIXEL_RTOL * max(self.size_mm)

    def require_footprint(self, width_mm: float, centre_mm: tuple[float, float] | None = None,
                          tile: bool = False) -> None:
        """Raise InputError unless the skin footprint (square, mm) fits on the map or ``tile`` is set.

        A given centre must be finite and within MAX_COORDINATE_MM of the origin (tiled maps too).
        """
        if centre_mm is not None:
            check_centre(centre_mm, tile)
        if tile or self.covers(width_mm, centre_mm):
            return
        width, height = self.size_mm
        footprint = f"{_mm(width_mm)} mm x {_mm(width_mm)} mm skin footprint"
        if min(width, height) < width_mm - self.slack_mm:
            raise InputError(f"heightmap is {width:.2f} mm x {height:.2f} mm, smaller than the {footprint}; "
                             "pass tile=True to repeat it as a periodic texture", parameter="tile")
        cx, cy = centre_mm or self.centre_mm
        half = width_mm / 2
        raise InputError(f"the {footprint} centred at ({cx:.2f}, {cy:.2f}) mm extends beyond the "
                         f"{width:.2f} mm x {height:.2f} mm heightmap; the centre must lie within "
                         f"x {half:.2f}..{width - half:.2f} mm, y {half:.2f}..{height - half:.2f} mm "
                         "(or pass tile=True to repeat it as a periodic texture)",
                         parameter=None if centre_mm is None else "centre_mm")

    def max_in_footprint(self, width_mm: float, centre_mm: tuple[float, float] | None = None,
                         periodic: bool = False) -> float:
        """Maximum height (mm) over pixels whose centres lie in the square of side ``width_mm`` (mm).

        Periodic maps wrap the indices; if no pixel centre falls inside, the height at the centre.
        """
        half = positive("footprint width", width_mm) / 2
        cx, cy = centre_mm or self.centre_mm
        ny, nx = self.shape
        cols = _indices_inside(cx - half, cx + half, self.pixel_mm, nx, periodic)
        rows = _indices_inside(cy - half, cy + half, self.pixel_mm, ny, periodic)
        if cols.size == 0 or rows.size == 0:
            return float(self.sample(cx, cy, periodic))
        return float(self.heights[np.ix_(rows, cols)].max())

    def resampled(self, pixel_mm: float) -> Heightmap:
        """Bilinear resampling to ``pixel_mm``; same origin, sides rounded to whole new pixels."""
        pixel_mm = pixel_size(pixel_mm)
        width, height = self.size_mm
        nx, ny = round(width / pixel_mm), round(height / pixel_mm)
        check_size(f"pixels of the {width:g} mm x {height:g} mm map resampled to {pixel_mm:g} mm", nx * ny,
                   MAX_HEIGHTMAP_PIXELS, "pixel_mm")
        x = (np.arange(nx) + 0.5) * pixel_mm
        y = (np.arange(ny) + 0.5) * pixel_mm
        return Heightmap(self.sample(x[None, :], y[:, None]), pixel_mm)

    def feature_size_mm(self) -> float:
        """Characteristic lateral wavelength (mm): 2 pi std(H) / rms|grad H|; inf for a flat map."""
        gy, gx = np.gradient(self.heights, self.pixel_mm)
        rms_slope = math.sqrt(float(np.mean(gx**2 + gy**2)))
        if rms_slope == 0:
            return math.inf
        return 2 * math.pi * float(np.std(self.heights)) / rms_slope

    def tiled(self, reps_y: int, reps_x: int) -> Heightmap:
        """The map repeated ``reps_y`` times along y and ``reps_x`` times along x."""
        for name, reps in (("reps_y", reps_y), ("reps_x", reps_x)):
            if isinstance(reps, bool) or not (isinstance(reps, (int, np.integer)) and reps >= 1):
                raise InputError(f"{name} must be a positive integer, got {reps!r}", parameter=name)
        check_size(f"pixels of the {self.shape[0]} x {self.shape[1]} pixel map repeated {reps_y} x {reps_x} times",
                   self.heights.size * int(reps_y) * int(reps_x), MAX_HEIGHTMAP_PIXELS)
        return Heightmap(np.tile(self.heights, (reps_y, reps_x)), self.pixel_mm)


def flat(size_mm: float = 12.0, pixel_mm: float = 0.05, height_mm: float = 0.0) -> Heightmap:
    """Square flat map of side ``size_mm`` (rounded to whole pixels) at ``height_mm``."""
    n = round(positive("size_mm", size_mm) / pixel_size(pixel_mm))
    check_size(f"pixels of a flat {size_mm:g} mm map at {pixel_mm:g} mm", n * n, MAX_HEIGHTMAP_PIXELS, "pixel_mm")
    return Heightmap(np.full((n, n), float(height_mm)), pixel_mm)


def _checked_heights(heights: object) -> np.ndarray:
    """A read-only float64 C-contiguous copy of ``heights``, or InputError (parameter ``heights``) naming the defect.

    Missing points (NaN, or masked in a NumPy masked array) are refused: ``as_heightmap(..., fill=True)`` fills them.
    """
    out = with_missing(heights)
    bad = ~np.isfinite(out)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        why = ("NaN and masked points are missing data: give every height, or fill them by harmonic interpolation "
               "(as_heightmap(heights, pixel_mm, fill=True), as the command line's --fill)" if np.isnan(out).any()
               else "an infinite height is no height in mm")
        raise InputError(f"heightmap has {int(bad.sum()):,} NaN/Inf pixel(s); first at row {i}, column {j}: {why}",
                         parameter="heights")
    tall = np.abs(out) > MAX_HEIGHT_MM
    if tall.any():
        i, j = np.argwhere(tall)[0]
        raise InputError(f"heightmap has {int(tall.sum())} pixel(s) higher or lower than {MAX_HEIGHT_MM:g} mm "
                         f"(MAX_HEIGHT_MM), e.g. {out[i, j]:.6g} mm at row {i}, column {j}: heights are "
                         "millimetres; check the file's unit (or --height-mm)", parameter="heights")
    out.flags.writeable = False
    return out


def heights_array(heights: object) -> np.ndarray:
    """``heights`` as an array of real numbers, shape (ny, nx) with ny, nx >= 2, at most MAX_HEIGHTMAP_PIXELS (not
    copied), or InputError (parameter ``heights``); a nested list of rows is one map."""
    try:
        raw = np.asarray(heights)
    except (TypeError, ValueError) as err:  # rows of different lengths, or values that are not numbers
        raise InputError(f"heightmap must be a 2-D array of heights in mm, not {type(heights).__name__} ({err})",
                         parameter="heights") from None
    if raw.dtype.kind not in "iuf":
        raise InputError(f"heightmap must hold real numbers, got dtype {raw.dtype}", parameter="heights")
    if raw.ndim != 2:
        raise InputError(f"heightmap must be 2-D, got shape {raw.shape}", parameter="heights")
    if raw.size == 0:
        raise InputError(f"heightmap is empty (shape {raw.shape})", parameter="heights")
    if min(raw.shape) < 2:
        raise InputError(f"heightmap needs at least 2 pixels along each axis, got shape {raw.shape}",
                         parameter="heights")
    check_size(f"heightmap pixels ({raw.shape[0]:,} x {raw.shape[1]:,})", raw.size, MAX_HEIGHTMAP_PIXELS, "heights")
    return raw


def with_missing(heights: object) -> np.ndarray:
    """A float64 copy of ``heights`` (checked by ``heights_array``) with NaN at the masked points of a NumPy masked
    array: missing points are NaN everywhere after this."""
    out = np.array(heights_array(heights), dtype=np.float64, order="C", copy=True)
    ma = sys.modules.get("numpy.ma")  # a masked array exists only once numpy.ma is loaded (not loaded here: ~20 ms)
    if ma is not None and isinstance(heights, ma.MaskedArray):
        out[ma.getmaskarray(heights)] = np.nan
    return out


def pixel_size(pixel_mm: object) -> float:
    """``pixel_mm`` as a float, or InputError unless it is a finite number in MIN_PIXEL_MM..MAX_PIXEL_MM."""
    pixel_mm = positive("pixel_mm", pixel_mm)
    if pixel_mm < MIN_PIXEL_MM:
        raise InputError(f"the pixel size {pixel_mm:g} mm is below {MIN_PIXEL_MM:g} mm (MIN_PIXEL_MM): not a pixel "
                         "of any instrument; check its unit (mm)", parameter="pixel_mm")
    if pixel_mm > MAX_PIXEL_MM:
        raise InputError(f"the pixel size {pixel_mm:g} mm is above {MAX_PIXEL_MM:g} mm (MAX_PIXEL_MM): no texture "
                         "has pixels that large; check its unit (mm)", parameter="pixel_mm")
    return pixel_mm


def check_centre(centre_mm: object, tile: bool = False) -> tuple[float, float]:
    """``centre_mm`` as two floats (x, y) in mm, or InputError (parameter centre_mm) unless they are two finite
    numbers (not bools) within MAX_COORDINATE_MM of the origin."""
    pair = list(centre_mm) if isinstance(centre_mm, (tuple, list, np.ndarray)) else []
    if len(pair) != 2 or not all(isinstance(c, numbers.Real) and not isinstance(c, bool) for c in pair):
        raise InputError(f"the footprint centre must be two numbers (x, y) in mm, got {centre_mm!r}",
                         parameter="centre_mm")
    cx, cy = (float(c) for c in pair)
    if not (math.isfinite(cx) and math.isfinite(cy)):
        raise InputError(f"the footprint centre must be two finite numbers (x, y) in mm, got ({cx}, {cy})",
                         parameter="centre_mm")
    if max(abs(cx), abs(cy)) > MAX_COORDINATE_MM:
        raise InputError(f"the footprint centre ({cx:.6g}, {cy:.6g}) mm lies beyond {MAX_COORDINATE_MM:g} mm "
                         "(MAX_COORDINATE_MM) of the origin" + ("; on a periodic texture the same point within the map "
                         "is the same centre" if tile else ""), parameter="centre_mm")
    return cx, cy


def bracket(u: np.ndarray, n: int, periodic: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Neighbouring indices and weight of the upper one for continuous pixel indices ``u`` on an axis of n."""
    if periodic:
        base = np.floor(u)
        lower = base.astype(np.intp) % n
        return lower, (lower + 1) % n, u - base
    u = np.clip(u, 0, n - 1)
    lower = np.minimum(np.floor(u).astype(np.intp), n - 2)
    return lower, lower + 1, u - lower


def _indices_inside(lo_mm: float, hi_mm: float, pixel_mm: float, n: int, periodic: bool) -> np.ndarray:
    """Indices of pixels whose centres lie in [lo_mm, hi_mm] on an axis of n pixels (wrapped if periodic), to the
    pixel size's precision (PIXEL_RTOL)."""
    slack = PIXEL_RTOL * max(abs(lo_mm), abs(hi_mm))
    first = math.ceil((lo_mm - slack) / pixel_mm - 0.5)
    last = math.floor((hi_mm + slack) / pixel_mm - 0.5)
    if periodic:
        return np.arange(n) if last - first + 1 >= n else np.arange(first, last + 1) % n
    return np.arange(max(first, 0), min(last, n - 1) + 1)


def _mm(value: float) -> str:
    """Length for messages: one decimal (as in "10.0") unless more digits are needed."""
    return f"{value:.1f}" if round(value, 1) == value else f"{value:g}"

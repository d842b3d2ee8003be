"""Scan clean-up, each step explicit and recorded: fill missing points, remove spikes, level.

Steps run in this order, each only when asked for:

1. fill: missing points (NaN, as scanners mark them) are interpolated harmonically (the
   Laplace equation over the holes, the measured points around them as boundary values, the
   map's edges free), the smoothest surface through the hole's rim. Refused above
   ``max_fill`` of the map: a surface that is mostly invented is not a measurement.
2. despike: a pixel whose residual from the 3 x 3 median exceeds ``k`` times the map's RMS
   height step between neighbouring pixels is replaced by that median. (A median absolute
   deviation of the residual is no scale here: it is 0 on textures with flat or straight
   parts, 63-100% of the pixels of the product's bump textures and gratings.) On the
   product's clean textures the largest residual is 1.0 (bumps), 1.7 (fBm) and 3.0 (grains)
   RMS steps: k = 5 leaves them untouched.
3. level: the least-squares plane or polynomial (degree 2 or 3) over the map is subtracted
   (roughness.surface.detrend's quadratic fit is the degree-2 case; detrend's low-pass is
   for curved objects, ``simulate --detrend``).

Every step returns a typed record of what it did (``Filled``, ``Despiked``, ``Levelled``).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from roughness.core.checks import real
from roughness.core.errors import InputError
from roughness.core.limits import MAX_FILL_PIXELS, MAX_WORKING_VALUES, check_size

from .heightmap import Heightmap

MAX_FILL_FRACTION = 0.2  # default limit of --fill (see docs/how-to/real-surfaces.md: the clean-up table)
LEVELS = {"plane": 1, "poly2": 2, "poly3": 3}
# Largest despike k: a spike's residual is at most about sqrt(pixels) times the RMS step it inflates (10,000 at
# MAX_HEIGHTMAP_PIXELS), so no larger k can find one.
MAX_DESPIKE = 10_000.0
# Map-sized arrays despike holds at once beside the map (measured 5.1: its median, the residual, the candidate,
# the differences of the RMS step, the spike masks).
DESPIKE_MAPS = 6


@dataclass(frozen=True)
class Cleanup:
    """Which steps to run: ``fill`` holes (up to ``max_fill`` of the map), ``despike`` at k RMS steps
    (None: off), ``level`` one of LEVELS (None: off)."""

    fill: bool = False
    max_fill: float = MAX_FILL_FRACTION
    despike: float | None = None
    level: str | None = None

    def __post_init__(self) -> None:
        if not 0 < real("max_fill", self.max_fill) < 1:
            raise InputError(f"max_fill must be a fraction between 0 and 1, got {self.max_fill!r}",
                             parameter="max_fill")
        if self.despike is not None and not real("despike", self.despike) > 0:
            raise InputError(f"despike must be a positive number of RMS steps, got {self.despike!r}",
                             parameter="despike")
        if self.level is not None and self.level not in LEVELS:
            raise InputError(f"level must be one of {', '.join(LEVELS)}, got {self.level!r}", parameter="level")


@dataclass(frozen=True)
class Filled:
    """Missing points interpolated: how many, and their fraction of the map."""

    pixels: int
    fraction: float

    def describe(self) -> str:
        return (f"filled {self.pixels:,} missing points ({100 * self.fraction:.2f}% of the map) by harmonic "
                "interpolation")


@dataclass(frozen=True)
class Despiked:
    """Spikes replaced by their 3 x 3 median: how many, beyond ``sigmas`` x ``step_mm`` (the RMS step)."""

    pixels: int
    sigmas: float
    step_mm: float

    def describe(self) -> str:
        return (f"replaced {self.pixels:,} spikes (residual from the 3 x 3 median beyond {self.sigmas:g} x the "
                f"RMS step between pixels, {self.step_mm:.3g} mm) by the median")


@dataclass(frozen=True)
class Levelled:
    """The fitted ``method`` surface subtracted; its peak to valley over the map (mm)."""

    method: str
    removed_relief_mm: float

    def describe(self) -> str:
        return f"levelled: subtracted the least-squares {self.method} ({self.removed_relief_mm:.3g} mm peak to valley)"


Step = Filled | Despiked | Levelled


@dataclass(frozen=True)
class Cleaned:
    """What the clean-up did to one map, in order."""

    steps: tuple[Step, ...] = ()

    def lines(self) -> list[str]:
        """The steps in words."""
        return [s.describe() for s in self.steps]

    def as_dict(self) -> list[dict]:
        """The steps for JSON output, each named by its ``step`` (filled, despiked, levelled)."""
        return [{"step": type(s).__name__.lower(), **asdict(s)} for s in self.steps]


def clean(heights: np.ndarray, pixel_mm: float, spec: Cleanup, source: str = "heightmap") -> tuple[Heightmap, Cleaned]:
    """The heightmap after the steps of ``spec`` and their record; InputError for holes without ``spec.fill``."""
    heights = np.array(heights, dtype=float)
    steps: list[Step] = []
    holes = np.isnan(heights)
    if holes.any():
        fraction = float(holes.mean())
        if not spec.fill:
            raise InputError(f"{source}: {int(holes.sum()):,} missing points (NaN), {100 * fraction:.2f}% of the "
                             "map; pass fill=True to interpolate them", parameter="fill")
        if fraction > spec.max_fill:
            raise InputError(f"{source}: {100 * fraction:.2f}% of the map is missing (NaN), more than max_fill, "
                             f"{100 * spec.max_fill:g}%: filling would invent most of what is felt",
                             parameter="max_fill")
        heights = fill_holes(heights)
        steps.append(Filled(int(holes.sum()), fraction))
    if spec.despike is not None:
        heights, step = despike(heights, spec.despike)
        steps.append(step)
    if spec.level is not None:
        trend = polynomial_fit(heights, LEVELS[spec.level])
        heights -= trend  # heights is this function's own copy
        steps.append(Levelled(spec.level, float(np.ptp(trend))))
    return Heightmap(heights, pixel_mm), Cleaned(tuple(steps))


def fill_holes(heights: np.ndarray) -> np.ndarray:
    """``heights`` with NaN pixels replaced by the solution of Laplace's equation over them (4-neighbour
    stencil; known pixels are boundary values; beyond the map's edges nothing: a free edge)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.linalg import spsolve

    holes = np.isnan(heights)
    count = int(holes.sum())
    check_size("missing points to fill", count, MAX_FILL_PIXELS, "fill")
    index = np.full(heights.shape, -1)
    index[holes] = np.arange(count)
    ny, nx = heights.shape
    rows_i, cols_j = np.nonzero(holes)
    diag = np.zeros(count)
    rhs = np.zeros(count)
    rows, cols = [], []
    for di, dj in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        i, j = rows_i + di, cols_j + dj
        inside = (i >= 0) & (i < ny) & (j >= 0) & (j < nx)
        me, i, j = index[rows_i[inside], cols_j[inside]], i[inside], j[inside]
        diag[me] += 1
        unknown = holes[i, j]
        rows.append(me[unknown])
        cols.append(index[i[unknown], j[unknown]])
        np.add.at(rhs, me[~unknown], heights[i[~unknown], j[~unknown]])
    rows_all, cols_all = np.concatenate(rows), np.concatenate(cols)
    matrix = coo_matrix((np.concatenate([diag, -np.ones(rows_all.size)]),
                         (np.concatenate([np.arange(count), rows_all]), np.concatenate([np.arange(count), cols_all]))),
                        shape=(count, count)).tocsc()
    out = heights.copy()
    out[holes] = spsolve(matrix, rhs) if count > 1 else rhs / diag
    return out


def despike(heights: np.ndarray, sigmas: float) -> tuple[np.ndarray, Despiked]:
    """``heights`` with spikes replaced by their 3 x 3 median: pixels whose residual from it exceeds
    ``sigmas`` times the map's RMS height step between neighbouring pixels (np.gradient per pixel),
    that step measured again once the first spikes are out (they inflate it). Its working arrays (DESPIKE_MAPS
    maps) are checked against MAX_WORKING_VALUES first."""
    from scipy.ndimage import median_filter

    check_size(f"values despike holds at once ({DESPIKE_MAPS} maps of {heights.size:,} pixels)",
               DESPIKE_MAPS * heights.size, MAX_WORKING_VALUES, "despike")
    median = median_filter(heights, size=3, mode="nearest")
    residual = heights - median
    np.abs(residual, out=residual)
    spikes = np.zeros(heights.shape, bool)
    for _ in range(2):
        step = _rms_step(np.where(spikes, median, heights))
        spikes = residual > sigmas * step  # a step of 0 (flat once the spikes are out): any residual is one
    return np.where(spikes, median, heights), Despiked(int(spikes.sum()), sigmas, step)


def _rms_step(heights: np.ndarray) -> float:
    """RMS height difference (mm) between neighbouring pixels: np.gradient's (central differences inside,
    one-sided at the edges), one difference array at a time."""
    total = 0.0
    for h in (heights, heights.T):
        inner = (h[:, 2:] - h[:, :-2]).ravel(order="K")  # "K": no copy of the transposed axis's differences
        edges = np.concatenate([h[:, 1] - h[:, 0], h[:, -1] - h[:, -2]])
        total += float(inner @ inner) / 4 + float(edges @ edges)
    return float(np.sqrt(total / heights.size))


def polynomial_fit(heights: np.ndarray, degree: int) -> np.ndarray:
    """The least-squares polynomial of total ``degree`` in x and y over the map (coordinates centred, in units
    of the map's side).

    On a grid, products of polynomials orthonormal along each axis are orthonormal, and those of total degree
    <= ``degree`` span the same space as the monomials x^a y^b: the fit is their projection, computed from
    (degree + 1) values per row and column, with no basis matrix of a value per pixel and monomial (4 GB for a
    50 Mpx map at degree 3): memory one map, time a few passes over it.
    """
    ny, nx = heights.shape
    qy, qx = _orthonormal(ny, degree), _orthonormal(nx, degree)
    coef = qy.T @ heights @ qx  # coef[b, a]: of q_b(y) q_a(x)
    b, a = np.indices(coef.shape)
    coef[a + b > degree] = 0.0
    return (qy @ coef) @ qx.T


def _orthonormal(n: int, degree: int) -> np.ndarray:
    """(n, k) orthonormal columns, column j a polynomial of degree j in the centred pixel coordinate (i - n/2) / n
    (k = degree + 1, or n if fewer pixels: they span every function on them)."""
    t = (np.arange(n) - n / 2) / n
    q, _ = np.linalg.qr(np.vander(t, degree + 1, increasing=True))
    return q

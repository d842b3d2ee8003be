"""Procedural "natural-like" texture families standing in for scanned materials (heightmaps in mm).

Every family is ``family(size_mm=12.0, pixel_mm=0.05, seed=0, **params) -> Heightmap`` on a square
map of side ``size_mm`` (rounded to whole pixels) with heights re-referenced to start at 0 and
peaking at most at the family's ``height_mm`` (``fbm`` has an RMS height instead). Parameters are
checked against PARAMETER_RANGES, which doubles as the range a dataset recipe should sample:
numeric ranges are (low, high), inclusive; categorical ones list the choices. Lengths are in mm,
angles in degrees, counter-clockwise (x towards y). ``cellular`` and ``grains`` are seamless periodic tiles;
the others are periodic when their periods divide the map side.
"""
from __future__ import annotations

import functools
import inspect
import math
from collections.abc import Callable

import numpy as np
from scipy.spatial import cKDTree

from roughness.core.checks import in_range
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from .fractal import fbm_surface
from .grid import PIXEL_MM, SIZE_MM, check_seed, map_side

PARAMETER_RANGES: dict[str, dict[str, tuple]] = {
    "cellular": {"cell_mm": (0.5, 3.0), "profile": ("dome", "wall"), "height_mm": (0.05, 1.0),
                 "wall_mm": (0.1, 0.5)},
    "woven": {"pitch_mm": (0.4, 3.0), "width_mm": (0.3, 2.5), "height_mm": (0.05, 1.0),
              "angle_deg": (0.0, 90.0)},
    "knit": {"wale_mm": (0.6, 3.0), "course_mm": (0.5, 2.5), "yarn_mm": (0.15, 0.8), "height_mm": (0.05, 1.0)},
    "grating": {"period_mm": (0.3, 3.0), "duty": (0.1, 0.9), "profile": ("sine", "square", "triangle"),
                "angle_deg": (0.0, 180.0), "height_mm": (0.05, 1.0)},
    "grains": {"grain_min_mm": (0.2, 0.5), "grain_max_mm": (0.5, 1.5), "density": (0.3, 2.0),
               "height_mm": (0.05, 1.0)},
    "dots": {"pitch_mm": (0.4, 3.0), "diameter_mm": (0.2, 2.0), "shape": ("dome", "flat", "cone"),
             "height_mm": (0.05, 1.0), "lattice": ("square", "hex"), "jitter_mm": (0.0, 0.3)},
    "fbm": {"hurst": (0.3, 0.9), "rms_mm": (0.02, 0.25), "cutoff_mm": (0.2, 1.5)},
}
# Lateral scales that must span at least MIN_PIXELS_PER_FEATURE pixels and at most half the map.
SCALE_PARAMETERS: dict[str, tuple[str, ...]] = {
    "cellular": ("cell_mm",), "woven": ("pitch_mm",), "knit": ("wale_mm", "course_mm"),
    "grating": ("period_mm",), "grains": ("grain_min_mm", "grain_max_mm"),
    "dots": ("pitch_mm", "diameter_mm"), "fbm": ("cutoff_mm",),
}
MIN_PIXELS_PER_FEATURE = 4
# Knit stitch geometry: a stitch spans KNIT_STITCH_COURSES courses; its two legs run from
# KNIT_LEG_START to KNIT_LEG_START + KNIT_LEG_SPREAD wale widths either side of the wale centre.
KNIT_STITCH_COURSES = 1.5
KNIT_LEG_START = 0.08
KNIT_LEG_SPREAD = 0.34

ProfileFn = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def _check_value(ranges: dict[str, dict[str, tuple]], family: str, name: str, value: object) -> None:
    """InputError unless ``value`` lies in ranges[family][name]."""
    allowed = ranges[family][name]
    if isinstance(allowed[0], str):
        if value not in allowed:
            raise InputError(f"{family} parameter {name}={value!r} must be one of {', '.join(allowed)}")
        return
    in_range(f"{family} parameter {name}", value, *allowed)


def _check_scales(scales: tuple[str, ...], family: str, arguments: dict) -> None:
    """InputError unless each scale parameter spans >= MIN_PIXELS_PER_FEATURE pixels and <= half the map."""
    pixel_mm, size_mm = arguments["pixel_mm"], arguments["size_mm"]
    for name in scales:
        value = arguments[name]
        if value < MIN_PIXELS_PER_FEATURE * pixel_mm:
            raise InputError(f"{family} parameter {name}={value:g} mm is below {MIN_PIXELS_PER_FEATURE} pixels "
                             f"of {pixel_mm:g} mm; use pixel_mm <= {value / MIN_PIXELS_PER_FEATURE:g}")
        if 2 * value > size_mm:
            raise InputError(f"{family} parameter {name}={value:g} mm needs a map of at least {2 * value:g} mm, "
                             f"got size_mm={size_mm:g}")


def validated(ranges: dict[str, dict[str, tuple]], scales: dict[str, tuple[str, ...]]
              ) -> Callable[[Callable[..., Heightmap]], Callable[..., Heightmap]]:
    """Decorator for a family function (named as its family): its grid, seed, parameters (against
    ``ranges[family]``) and lateral scales (``scales[family]``) are checked before it runs."""
    def decorate(func: Callable[..., Heightmap]) -> Callable[..., Heightmap]:
        family, signature = func.__name__, inspect.signature(func)

        @functools.wraps(func)
        def checked(*args, **kwargs) -> Heightmap:
            bound = signature.bind(*args, **kwargs)
            bound.apply_defaults()
            arguments = bound.arguments
            map_side(arguments["size_mm"], arguments["pixel_mm"])
            check_seed(arguments["seed"])
            for name in ranges[family]:
                _check_value(ranges, family, name, arguments[name])
            _check_scales(scales[family], family, arguments)
            return func(**arguments)

        return checked

    return decorate


RELIEF_PARAMETERS = ("height_mm", "wave_height_mm", "rms_mm", "relief_mm")
LIMIT_SCALE_MM = (0.1, 4.0)  # lateral scales a family accepts (with 4 pixels per feature, and half the map)
RELIEF_FACTOR = 5  # reliefs a family accepts: down to a fifth of its default range's lowest


def limits(ranges: dict[str, dict[str, tuple]], scales: dict[str, tuple[str, ...]],
           exceptions: dict[str, dict[str, tuple]] | None = None) -> dict[str, dict[str, tuple]]:
    """What the families accept, for a direct call and a recipe's ranges: their default ``ranges`` widened
    to the finer, lower and longer textures people print (fine print layers and engraving from 0.1 mm, low
    relief, long wavelengths to 4 mm), so that a recipe can reach them while the defaults (and every recipe
    that relies on them) stay as they were. Reliefs reach down to 1 / ``RELIEF_FACTOR`` of the lowest default,
    lateral scales span ``LIMIT_SCALE_MM``; ``exceptions`` replace a parameter's limits (a family's own
    invariants)."""
    out = {}
    for family, params in ranges.items():
        out[family] = {}
        for name, allowed in params.items():
            if isinstance(allowed[0], str):
                out[family][name] = allowed
            elif name in RELIEF_PARAMETERS:
                out[family][name] = (allowed[0] / RELIEF_FACTOR, allowed[1])
            elif name in scales[family]:
                out[family][name] = (min(allowed[0], LIMIT_SCALE_MM[0]), max(allowed[1], LIMIT_SCALE_MM[1]))
            else:
                out[family][name] = allowed
        out[family].update((exceptions or {}).get(family, {}))
    return out


# grains: the minimum and maximum diameter ranges meet at 0.5 mm, so grain_min_mm <= grain_max_mm always
PARAMETER_LIMITS = limits(PARAMETER_RANGES, SCALE_PARAMETERS,
                          {"grains": {"grain_min_mm": (0.1, 0.5), "grain_max_mm": (0.5, 4.0)}})
_validated = validated(PARAMETER_LIMITS, SCALE_PARAMETERS)


def _finish(heights: np.ndarray, pixel_mm: float) -> Heightmap:
    """Heightmap with the minimum moved to 0."""
    return Heightmap(heights - heights.min(), pixel_mm)


def _centred_coords(n: int, pixel_mm: float, angle_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-centre coordinates (mm) about the map centre, in axes rotated by ``angle_deg``: (u, v), (n, n)."""
    c = (np.arange(n) + 0.5 - n / 2) * pixel_mm
    x, y = c[None, :], c[:, None]
    cos, sin = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    return x * cos + y * sin, y * cos - x * sin


def _phases(seed: int, periods_mm: tuple[float, float]) -> tuple[float, float]:
    """Random offsets (mm), uniform over one period each, that place a regular pattern per ``seed``."""
    fractions = np.random.default_rng(seed).random(2)
    return fractions[0] * periods_mm[0], fractions[1] * periods_mm[1]


def _section(offset_mm: np.ndarray, width_mm: float) -> np.ndarray:
    """Elliptical thread cross-section in [0, 1] at lateral ``offset_mm`` from its axis; 0 beyond width/2."""
    return np.sqrt(np.clip(1 - (2 * offset_mm / width_mm) ** 2, 0.0, 1.0))


def _stamp(n: int, pixel_mm: float, centres_mm: np.ndarray, radii_mm: np.ndarray, heights_mm: np.ndarray,
           profile: ProfileFn, periodic: bool) -> np.ndarray:
    """(n, n) maximum over round features: ``profile(r, radius, height)`` (mm) at each centre (k, 2) x, y (mm).

    ``profile`` must vanish beyond radius + pixel/2; periodic maps wrap features across the edges.
    """
    reach = math.ceil(radii_mm.max() / pixel_mm) + 1
    offsets = np.arange(-reach, reach + 1)
    centre_cols = np.rint(centres_mm[:, 0] / pixel_mm - 0.5).astype(np.intp)
    centre_rows = np.rint(centres_mm[:, 1] / pixel_mm - 0.5).astype(np.intp)
    rows = centre_rows[:, None, None] + offsets[None, :, None]
    cols = centre_cols[:, None, None] + offsets[None, None, :]
    r = np.hypot((cols + 0.5) * pixel_mm - centres_mm[:, 0, None, None],
                 (rows + 0.5) * pixel_mm - centres_mm[:, 1, None, None])
    values = profile(r, radii_mm[:, None, None], heights_mm[:, None, None])
    rows, cols = np.broadcast_arrays(rows, cols)
    if periodic:
        rows, cols = rows % n, cols % n
    else:
        inside = (rows >= 0) & (rows < n) & (cols >= 0) & (cols < n)
        rows, cols, values = rows[inside], cols[inside], values[inside]
    canvas = np.zeros((n, n))
    np.maximum.at(canvas, (rows, cols), values)
    return canvas


@_validated
def cellular(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, cell_mm: float = 1.5,
             profile: str = "dome", height_mm: float = 0.5, wall_mm: float = 0.2) -> Heightmap:
    """Voronoi (Worley) cells, e.g. pebbles, leather grain or honeycomb; seamless periodic.

    cell_mm: mean cell size (mm), seeds jittered on a grid of that pitch; profile: "dome" (each cell
    a rounded pillow, h (1 - (F1/F2)^2), 0 on the cell borders) or "wall" (rounded ridges of width
    ``wall_mm`` (mm) on the borders, ignored for domes); height_mm: peak height (mm).
    """
    n = map_side(size_mm, pixel_mm)
    side = n * pixel_mm
    cells = max(2, round(side / cell_mm))
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(np.arange(cells), np.arange(cells)), axis=-1).reshape(-1, 2)
    seeds = (grid + rng.random(grid.shape)) * (side / cells)
    c = (np.arange(n) + 0.5) * pixel_mm
    points = np.stack(np.meshgrid(c, c), axis=-1).reshape(-1, 2)
    distances, nearest = cKDTree(seeds, boxsize=side).query(points, k=2)
    f1, f2 = distances[:, 0], distances[:, 1]
    if profile == "dome":
        return _finish((height_mm * (1 - (f1 / f2) ** 2)).reshape(n, n), pixel_mm)
    to_first, to_second = (points - seeds[nearest[:, k]] for k in (0, 1))
    to_first -= side * np.round(to_first / side)
    to_second -= side * np.round(to_second / side)
    border_mm = (f2**2 - f1**2) / (2 * np.linalg.norm(to_first - to_second, axis=1))
    return _finish((height_mm * _section(border_mm, wall_mm)).reshape(n, n), pixel_mm)


@_validated
def woven(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, pitch_mm: float = 1.0,
          width_mm: float = 0.8, height_mm: float = 0.4, angle_deg: float = 0.0) -> Heightmap:
    """Plain over-under weave of elliptical threads, e.g. canvas or linen.

    pitch_mm: thread spacing (mm); width_mm: thread width (mm; wider than the pitch packs the threads
    flat); height_mm: peak height (mm) at a crossing; angle_deg: warp direction (degrees from +y).
    ``seed`` sets the position of the weave.
    """
    u, v = _centred_coords(map_side(size_mm, pixel_mm), pixel_mm, angle_deg)
    du, dv = _phases(seed, (2 * pitch_mm, 2 * pitch_mm))
    u, v = u + du, v + dv
    warp_index, weft_index = np.floor(u / pitch_mm), np.floor(v / pitch_mm)
    warp_sign, weft_sign = 1 - 2 * (warp_index % 2), 1 - 2 * (weft_index % 2)
    warp_lift = 0.5 * (1 + warp_sign * np.cos(np.pi * (v / pitch_mm - 0.5)))
    weft_lift = 0.5 * (1 - weft_sign * np.cos(np.pi * (u / pitch_mm - 0.5)))
    warp = _section(u - (warp_index + 0.5) * pitch_mm, width_mm) * (1 + warp_lift)
    weft = _section(v - (weft_index + 0.5) * pitch_mm, width_mm) * (1 + weft_lift)
    return _finish(0.5 * height_mm * np.maximum(warp, weft), pixel_mm)


@_validated
def knit(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, wale_mm: float = 1.2,
         course_mm: float = 0.9, yarn_mm: float = 0.35, height_mm: float = 0.4) -> Heightmap:
    """Stockinette knit: columns (wales) of interlocking V-shaped stitches.

    wale_mm: column width (mm, along x); course_mm: row spacing (mm, along y); yarn_mm: yarn
    diameter (mm); height_mm: peak height (mm), reached mid-leg where the yarn is on top.
    ``seed`` sets the position of the stitches.
    """
    n = map_side(size_mm, pixel_mm)
    dx, dy = _phases(seed, (wale_mm, course_mm))
    c = (np.arange(n) + 0.5) * pixel_mm
    x, y = c[None, :] + dx, c[:, None] + dy
    across = np.abs(x - (np.floor(x / wale_mm) + 0.5) * wale_mm)
    stitch_mm = KNIT_STITCH_COURSES * course_mm
    leg_slope = KNIT_LEG_SPREAD * wale_mm / stitch_mm
    heights = np.zeros((n, n))
    for back in (0, 1):
        t = (y - (np.floor(y / course_mm) - back) * course_mm) / stitch_mm
        leg = wale_mm * (KNIT_LEG_START + KNIT_LEG_SPREAD * t)
        offset = (across - leg) / math.sqrt(1 + leg_slope**2)
        lift = np.where(t < 1, 0.4 + 0.6 * np.sin(np.pi * np.minimum(t, 1)), 0.0)
        heights = np.maximum(heights, height_mm * lift * _section(offset, yarn_mm))
    return _finish(heights, pixel_mm)


@_validated
def grating(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, period_mm: float = 1.0,
            duty: float = 0.5, profile: str = "square", angle_deg: float = 0.0, height_mm: float = 0.5) -> Heightmap:
    """Parallel ridges, e.g. corduroy, ribbed plastic or wood grain.

    period_mm: ridge spacing (mm); duty: ridge base width / period for "square" (anti-aliased walls)
    and "triangle" (unused by "sine", a pure sinusoid); angle_deg: direction across the ridges (the
    grating vector, degrees from +x; 0 gives ridges along y); height_mm: ridge height (mm).
    ``seed`` sets the position of the ridges.
    """
    u, _ = _centred_coords(map_side(size_mm, pixel_mm), pixel_mm, angle_deg)
    u = u + _phases(seed, (period_mm, period_mm))[0]
    if profile == "sine":
        return _finish(0.5 * height_mm * (1 + np.cos(2 * np.pi * u / period_mm)), pixel_mm)
    from_ridge = np.abs((u / period_mm + 0.5) % 1 - 0.5) * period_mm
    half_width = duty * period_mm / 2
    if profile == "square":
        return _finish(height_mm * np.clip((half_width - from_ridge) / pixel_mm + 0.5, 0, 1), pixel_mm)
    return _finish(height_mm * np.clip(1 - from_ridge / half_width, 0, 1), pixel_mm)


def _spheroid(r: np.ndarray, radius: np.ndarray, height: np.ndarray) -> np.ndarray:
    """Half-spheroid of base ``radius`` and ``height`` (mm) at radial distance r (mm)."""
    return height * np.sqrt(np.clip(1 - (r / radius) ** 2, 0.0, 1.0))


@_validated
def grains(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, grain_min_mm: float = 0.3,
           grain_max_mm: float = 0.8, density: float = 1.0, height_mm: float = 0.5) -> Heightmap:
    """Random sand or grit: overlapping half-spheroid grains, uniformly placed; seamless periodic.

    grain_min_mm, grain_max_mm: grain diameter range (mm, uniform); density: total grain footprint
    area per map area (dimensionless; the covered fraction is about 1 - exp(-density));
    the allowed diameter ranges meet at 0.5 mm, so grain_min_mm <= grain_max_mm always;
    height_mm: height (mm) of the largest possible grain, smaller grains scale down with diameter.
    """
    n = map_side(size_mm, pixel_mm)
    side = n * pixel_mm
    mean_area = math.pi / 12 * (grain_min_mm**2 + grain_min_mm * grain_max_mm + grain_max_mm**2)
    count = max(1, round(density * side**2 / mean_area))
    rng = np.random.default_rng(seed)
    centres = rng.random((count, 2)) * side
    diameters = rng.uniform(grain_min_mm, grain_max_mm, count)
    heights = _stamp(n, pixel_mm, centres, diameters / 2, height_mm * diameters / grain_max_mm, _spheroid,
                     periodic=True)
    return _finish(heights, pixel_mm)


def _lattice(side_mm: float, pitch_mm: float, lattice: str, margin_mm: float,
             origin_mm: tuple[float, float]) -> np.ndarray:
    """Lattice points (k, 2) x, y (mm) within ``margin_mm`` of a map of side ``side_mm``.

    One point lies at ``origin_mm`` (x, y; mm, within a pitch of the map centre).
    """
    row_mm = pitch_mm * math.sqrt(3) / 2 if lattice == "hex" else pitch_mm
    reach = side_mm / 2 + margin_mm
    cols = np.arange(-math.ceil(reach / pitch_mm) - 2, math.ceil(reach / pitch_mm) + 3)
    rows = np.arange(-math.ceil(reach / row_mm) - 2, math.ceil(reach / row_mm) + 3)
    a, b = np.meshgrid(cols, rows)
    stagger = 0.5 * (b % 2) if lattice == "hex" else 0.0
    points = np.column_stack(((a + stagger).ravel() * pitch_mm, b.ravel() * row_mm)) + origin_mm
    return points[np.all(np.abs(points) <= reach, axis=1)] + side_mm / 2


def _dot_profile(shape: str, pixel_mm: float) -> ProfileFn:
    """Radial dot profile (mm) for ``shape``: spherical cap, anti-aliased flat cylinder or cone."""
    def dome(r: np.ndarray, radius: np.ndarray, height: np.ndarray) -> np.ndarray:
        sphere = (radius**2 + height**2) / (2 * height)
        return np.maximum(np.sqrt(np.maximum(sphere**2 - r**2, 0.0)) - (sphere - height), 0.0)

    def flat(r: np.ndarray, radius: np.ndarray, height: np.ndarray) -> np.ndarray:
        return height * np.clip((radius - r) / pixel_mm + 0.5, 0.0, 1.0)

    def cone(r: np.ndarray, radius: np.ndarray, height: np.ndarray) -> np.ndarray:
        return height * np.clip(1 - r / radius, 0.0, 1.0)

    return {"dome": dome, "flat": flat, "cone": cone}[shape]


@_validated
def dots(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, pitch_mm: float = 1.0,
         diameter_mm: float = 0.5, shape: str = "dome", height_mm: float = 0.5, lattice: str = "square",
         jitter_mm: float = 0.0) -> Heightmap:
    """Dot arrays, e.g. Braille-like studs, rubber mats or perforated-sheet negatives.

    pitch_mm: lattice spacing (mm; nearest-neighbour distance for both lattices); diameter_mm: dot base
    diameter (mm; overlapping dots merge); shape: "dome" (spherical cap), "flat" (cylinder) or "cone";
    height_mm: dot height (mm); lattice: "square" or "hex"; jitter_mm: each centre moves by up to
    this much (mm, uniform) along x and y. ``seed`` sets the position of the lattice and the jitter.
    """
    n = map_side(size_mm, pixel_mm)
    radius = diameter_mm / 2
    rng = np.random.default_rng(seed)
    origin = tuple(rng.random(2) * pitch_mm)
    centres = _lattice(n * pixel_mm, pitch_mm, lattice, radius + jitter_mm + pixel_mm, origin)
    centres = centres + rng.uniform(-jitter_mm, jitter_mm, centres.shape)
    k = len(centres)
    heights = _stamp(n, pixel_mm, centres, np.full(k, radius), np.full(k, height_mm),
                     _dot_profile(shape, pixel_mm), periodic=False)
    return _finish(heights, pixel_mm)


@_validated
def fbm(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, hurst: float = 0.8, rms_mm: float = 0.15,
        cutoff_mm: float = 0.4) -> Heightmap:
    """Isotropic fractal (fBm) roughness, e.g. stone or bark: dataset.fractal.fbm_surface.

    hurst: Hurst exponent (roughness falls as k^-(2 + 2 hurst)); rms_mm: RMS height (mm);
    cutoff_mm: shortest wavelength generated (mm); seamless periodic.
    """
    return fbm_surface(size_mm, pixel_mm, hurst=hurst, rms_mm=rms_mm, cutoff_mm=cutoff_mm, seed=seed)


FAMILIES: dict[str, Callable[..., Heightmap]] = {
    func.__name__: func for func in (cellular, woven, knit, grating, grains, dots, fbm)
}

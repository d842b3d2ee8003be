"""Engineered and composite texture families (heightmaps in mm): machined and knurled surfaces, rib
lattices, sparse isolated features on flat ground, multi-scale and low-relief surfaces, and mixtures.

They widen what the surrogate is trained on beyond the paper's bumps and the natural-like families
(dataset/natural.py), whose conventions they share: ``family(size_mm=12.0, pixel_mm=0.05, seed=0,
**params) -> Heightmap``, heights from 0 up to at most ``height_mm`` (``multiscale``: the waviness'
peak-to-valley plus the fine roughness; ``shallow``: ``relief_mm``), parameters checked against
PARAMETER_RANGES (inclusive numeric (low, high), or the choices), which is also the range a dataset
recipe samples. Lengths in mm, angles in degrees counter-clockwise from +x. Deterministic per seed.

- knurl: diamond knurl, two crossed triangular grooves; ``land`` flattens the pyramid tops (worn knurl).
- milled: ball-end-mill scallops (concave circular arcs between cusps), one pass direction or two crossed.
- waffle: raised ribs on the borders of a square or hexagonal (honeycomb) cell lattice.
- sparse: a few isolated domes, cones, flat studs or pits on flat ground; one always lies within
  3 mm of the map centre, so the centred skin footprint touches at least one feature.
- multiscale: long waviness (a random-phase band at ``wave_mm``) carrying fine fBm roughness.
- shallow: a natural-like family with random parameters, rescaled to a low relief (5-100 um).
- mixture: two families (natural-like or engineered) with random parameters, added or maximised.
"""
from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.spatial import cKDTree

from roughness.surface.heightmap import Heightmap

from . import natural
from .fractal import fbm_surface
from .grid import PIXEL_MM, SIZE_MM, map_side
from .natural import _centred_coords, _dot_profile, _finish, _phases, _stamp, validated
from .textures import _ring_field

SHAPED = ("knurl", "milled", "waffle", "sparse", "multiscale")  # mixture parts besides the natural families
PARAMETER_RANGES: dict[str, dict[str, tuple]] = {
    "knurl": {"pitch_mm": (0.4, 2.5), "helix_deg": (20.0, 70.0), "angle_deg": (0.0, 180.0), "land": (0.0, 0.6),
              "height_mm": (0.05, 1.0)},
    "milled": {"step_mm": (0.2, 2.5), "pattern": ("parallel", "crossed"), "angle_deg": (0.0, 180.0),
               "height_mm": (0.01, 0.5)},
    "waffle": {"pitch_mm": (0.6, 4.0), "rib": (0.05, 0.5), "lattice": ("square", "hex"), "angle_deg": (0.0, 90.0),
               "height_mm": (0.05, 1.0)},
    "sparse": {"density_per_cm2": (0.5, 10.0), "diameter_mm": (0.3, 3.0), "shape": ("dome", "cone", "flat", "pit"),
               "height_mm": (0.05, 1.0)},
    "multiscale": {"wave_mm": (2.0, 6.0), "wave_height_mm": (0.05, 1.0), "hurst": (0.3, 0.9),
                   "rms_mm": (0.005, 0.1), "cutoff_mm": (0.2, 1.0)},
    "shallow": {"base": tuple(natural.FAMILIES), "relief_mm": (0.005, 0.1)},
    "mixture": {"base": tuple(natural.FAMILIES) + SHAPED, "overlay": tuple(natural.FAMILIES) + SHAPED,
                "overlay_share": (0.1, 0.9), "combine": ("add", "max"), "height_mm": (0.05, 1.0)},
}
SCALE_PARAMETERS: dict[str, tuple[str, ...]] = {
    "knurl": ("pitch_mm",), "milled": ("step_mm",), "waffle": ("pitch_mm",), "sparse": ("diameter_mm",),
    "multiscale": ("wave_mm", "cutoff_mm"), "shallow": (), "mixture": (),
}
SPARSE_CENTRE_MM = 3.0  # the first sparse feature lies within this distance (along x and y) of the map centre

PARAMETER_LIMITS = natural.limits(PARAMETER_RANGES, SCALE_PARAMETERS)  # what a family accepts (natural.limits)
_family = validated(PARAMETER_LIMITS, SCALE_PARAMETERS)


def _triangle(u: np.ndarray, period_mm: float) -> np.ndarray:
    """Triangle wave in [0, 1] of period ``period_mm``: 1 on the ridges, 0 in the grooves."""
    return 1 - 2 * np.abs((u / period_mm) % 1 - 0.5)


@_family
def knurl(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, pitch_mm: float = 1.0,
          helix_deg: float = 45.0, angle_deg: float = 0.0, land: float = 0.0, height_mm: float = 0.4) -> Heightmap:
    """Diamond knurl: two sets of V grooves of pitch ``pitch_mm`` at +-``helix_deg`` from the direction
    ``angle_deg`` leave a lattice of pyramids of height ``height_mm``; ``land`` (0..0.6) is the fraction of
    the pyramid height cut flat from the tops. ``seed`` places the pattern."""
    n = map_side(size_mm, pixel_mm)
    du, dv = _phases(seed, (pitch_mm, pitch_mm))
    u, _ = _centred_coords(n, pixel_mm, angle_deg + helix_deg)
    v, _ = _centred_coords(n, pixel_mm, angle_deg - helix_deg)
    pyramids = np.minimum(_triangle(u + du, pitch_mm), _triangle(v + dv, pitch_mm))
    return _finish(height_mm * np.minimum(pyramids, 1 - land) / (1 - land), pixel_mm)


@_family
def milled(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, step_mm: float = 0.8,
           pattern: str = "parallel", angle_deg: float = 0.0, height_mm: float = 0.05) -> Heightmap:
    """Ball-end-milled surface: passes ``step_mm`` apart leave concave circular scallops with cusps of
    height ``height_mm`` (the tool radius follows: (step^2/4 + h^2) / 2h); ``pattern`` "crossed" adds a
    second set of passes at right angles (the surface is the lower of both cuts). ``angle_deg`` is the
    direction across the first passes; ``seed`` places them."""
    n = map_side(size_mm, pixel_mm)
    radius = (step_mm**2 / 4 + height_mm**2) / (2 * height_mm)
    du, dv = _phases(seed, (step_mm, step_mm))
    u, v = _centred_coords(n, pixel_mm, angle_deg)

    def scallops(w: np.ndarray) -> np.ndarray:
        d = np.abs((w / step_mm + 0.5) % 1 - 0.5) * step_mm  # distance to the nearest pass centre
        return radius - np.sqrt(np.maximum(radius**2 - d**2, 0.0))

    heights = scallops(u + du)
    if pattern == "crossed":
        heights = np.minimum(heights, scallops(v + dv))
    return _finish(np.minimum(heights, height_mm), pixel_mm)


@_family
def waffle(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, pitch_mm: float = 1.5,
           rib: float = 0.2, lattice: str = "square", angle_deg: float = 0.0, height_mm: float = 0.4) -> Heightmap:
    """Raised flat-topped ribs of width ``rib`` x ``pitch_mm`` on the borders of a regular cell lattice
    (``lattice`` "square": a square grid; "hex": a honeycomb) with cell centres ``pitch_mm`` apart,
    rotated by ``angle_deg``; anti-aliased walls. ``seed`` places the lattice."""
    n = map_side(size_mm, pixel_mm)
    u, v = _centred_coords(n, pixel_mm, angle_deg)
    du, dv = _phases(seed, (pitch_mm, pitch_mm))
    row_mm = pitch_mm * math.sqrt(3) / 2 if lattice == "hex" else pitch_mm
    reach = n * pixel_mm + 2 * pitch_mm
    a, b = np.meshgrid(np.arange(-math.ceil(reach / pitch_mm), math.ceil(reach / pitch_mm) + 1),
                       np.arange(-math.ceil(reach / row_mm), math.ceil(reach / row_mm) + 1))
    stagger = 0.5 * (b % 2) if lattice == "hex" else 0.0
    centres = np.column_stack(((a + stagger).ravel() * pitch_mm, b.ravel() * row_mm))
    points = np.column_stack(((u + du).ravel(), (v + dv).ravel()))
    distances, nearest = cKDTree(centres).query(points, k=2)
    gap = np.linalg.norm(centres[nearest[:, 0]] - centres[nearest[:, 1]], axis=1)
    border_mm = (distances[:, 1] ** 2 - distances[:, 0] ** 2) / (2 * gap)  # distance to the cell border
    walls = np.clip((rib * pitch_mm / 2 - border_mm) / pixel_mm + 0.5, 0.0, 1.0)
    return _finish(height_mm * walls.reshape(n, n), pixel_mm)


@_family
def sparse(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, density_per_cm2: float = 2.0,
           diameter_mm: float = 1.0, shape: str = "dome", height_mm: float = 0.5) -> Heightmap:
    """Isolated features on flat ground: round(``density_per_cm2`` x map area) features (at least one) of
    base diameter ``diameter_mm``, uniformly placed, the first within SPARSE_CENTRE_MM of the centre.
    ``shape`` "dome" (spherical cap), "cone" or "flat" (cylinder) rise ``height_mm`` above the ground;
    "pit" is a spherical-cap hole ``height_mm`` deep in it."""
    n = map_side(size_mm, pixel_mm)
    side = n * pixel_mm
    rng = np.random.default_rng(seed)
    count = max(1, round(density_per_cm2 * side**2 / 100))
    centres = rng.random((count, 2)) * side
    centres[0] = side / 2 + rng.uniform(-SPARSE_CENTRE_MM, SPARSE_CENTRE_MM, 2)
    radii, heights = np.full(count, diameter_mm / 2), np.full(count, height_mm)
    features = _stamp(n, pixel_mm, centres, radii, heights, _dot_profile("dome" if shape == "pit" else shape,
                                                                         pixel_mm), periodic=False)
    return _finish(height_mm - features if shape == "pit" else features, pixel_mm)


@_family
def multiscale(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, wave_mm: float = 4.0,
               wave_height_mm: float = 0.3, hurst: float = 0.7, rms_mm: float = 0.03,
               cutoff_mm: float = 0.4) -> Heightmap:
    """Waviness with roughness on it: a random-phase band of wavelength ~``wave_mm`` with peak-to-valley
    ``wave_height_mm``, plus fBm roughness (``hurst``, RMS ``rms_mm``, shortest wavelength ``cutoff_mm``)."""
    n = map_side(size_mm, pixel_mm)
    wave = _ring_field(wave_mm, n, pixel_mm, np.random.default_rng(seed))
    wave = wave_height_mm * (wave - wave.min()) / (wave.max() - wave.min())
    fine = fbm_surface(size_mm, pixel_mm, hurst=hurst, rms_mm=rms_mm, cutoff_mm=cutoff_mm, seed=seed + 1).heights
    return _finish(wave + fine, pixel_mm)


def _random_member(family: str, rng: np.random.Generator, size_mm: float, pixel_mm: float) -> np.ndarray:
    """Heights of ``family`` with parameters and seed drawn from ``rng`` over its full ranges, scaled to peak 1."""
    ranges = natural.PARAMETER_RANGES.get(family) or PARAMETER_RANGES[family]
    params = {k: str(v[int(rng.integers(len(v)))]) if isinstance(v[0], str) else float(rng.uniform(*v))
              for k, v in ranges.items()}
    make: Callable[..., Heightmap] = natural.FAMILIES.get(family) or FAMILIES[family]
    heights = make(size_mm=size_mm, pixel_mm=pixel_mm, seed=int(rng.integers(2**31)), **params).heights
    return heights / heights.max() if heights.max() > 0 else heights


@_family
def shallow(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, base: str = "grains",
            relief_mm: float = 0.03) -> Heightmap:
    """Low relief: family ``base`` (natural-like) with parameters drawn per ``seed`` over its ranges,
    rescaled to a peak of ``relief_mm``."""
    rng = np.random.default_rng([seed, 1])
    return _finish(relief_mm * _random_member(base, rng, size_mm, pixel_mm), pixel_mm)


@_family
def mixture(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, seed: int = 0, base: str = "fbm",
            overlay: str = "dots", overlay_share: float = 0.3, combine: str = "add",
            height_mm: float = 0.5) -> Heightmap:
    """Two families with parameters drawn per ``seed`` over their ranges, each scaled to peak 1:
    ``combine`` "add": (1 - s) base + s overlay; "max": max((1 - s) base, s overlay), with
    s = ``overlay_share``; then scaled to a peak of ``height_mm``."""
    rng = np.random.default_rng([seed, 2])
    lower = (1 - overlay_share) * _random_member(base, rng, size_mm, pixel_mm)
    upper = overlay_share * _random_member(overlay, rng, size_mm, pixel_mm)
    heights = lower + upper if combine == "add" else np.maximum(lower, upper)
    heights = heights - heights.min()
    return _finish(height_mm * heights / heights.max() if heights.max() > 0 else heights, pixel_mm)


FAMILIES: dict[str, Callable[..., Heightmap]] = {
    func.__name__: func for func in (knurl, milled, waffle, sparse, multiscale, shallow, mixture)
}

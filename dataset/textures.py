"""The paper's parametric bump textures (Tymms, Gardner & Zorin 2018), as heightmaps in mm.

Bump centres are the local maxima of a random-phase field whose magnitude spectrum is a thin
ring at spatial frequency ``RING_FACTOR / lambda`` (cycles/mm); each centre carries a truncated
cone topped by a spherical cap or a flat plateau. The field is periodic on the map, so the
bump density is uniform up to the edges and every map is a seamless periodic tile.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import fields as dataclass_fields

import numpy as np
from scipy import ndimage, optimize
from scipy.spatial import cKDTree

from roughness.core.checks import positive, real
from roughness.core.errors import InputError
from roughness.core.limits import MAX_HEIGHT_MM
from roughness.surface.heightmap import Heightmap, flat

from .grid import PIXEL_MM, SIZE_MM, check_seed, map_side

STANDARD_LAMBDAS_MM = (0.625, 0.6875, 0.75, 0.8125, 0.875, 0.9375, 1.0, 1.0625, 1.125, 1.25, 1.375, 1.5, 1.625)
FLAT_TOP_DIAMETERS_MM = (0.1, 0.2, 0.3, 0.4, 0.5)
TOPS = ("cap", "flat")
# Ring radius = RING_FACTOR / lambda (cycles/mm): calibrated so that the mean nearest-neighbour
# spacing of the local maxima equals lambda (within a few % for lambda = 0.5..2.5 mm, 0.05 mm pixels).
RING_FACTOR = 0.884
RING_WIDTH = 0.1  # Gaussian sigma of the ring, as a fraction of its radius
MIN_PIXELS_PER_LAMBDA = 4
FLANK_RUN_MM = 0.8  # default horizontal run of the cone flank (base = top + 1.6 mm)


@dataclass(frozen=True)
class BumpRecipe:
    """Parameters of one bump texture; all lengths in mm.

    The cone base is not given in the paper. By default (``base_diameter_mm=None``) the flank
    has a fixed horizontal run of FLANK_RUN_MM, so base = top + 2 * FLANK_RUN_MM (1.9 mm for
    the standard 0.3 mm caps). With it both of the paper's orderings hold at its 10 N: V grows
    with lambda over the standard scale and falls as the flat top widens (see
    studies/results/ordering_coarse.md and flat_top.md; a 0.9 mm base breaks the first,
    a fixed 1.5 mm base the second). ``base_mm`` is the base in use. For ``top="cap"``,
    ``top_diameter_mm`` is the footprint diameter of a spherical cap tangent to the cone flank;
    for ``top="flat"`` it is the diameter of the plateau (0.1..0.5 mm).
    """

    lambda_mm: float
    top: str = "cap"
    top_diameter_mm: float = 0.3
    height_mm: float = 1.0
    base_diameter_mm: float | None = None
    size_mm: float = SIZE_MM
    pixel_mm: float = PIXEL_MM
    seed: int = 0

    @property
    def base_mm(self) -> float:
        """Cone base diameter (mm): given, or top + 2 * FLANK_RUN_MM."""
        if self.base_diameter_mm is not None:
            return self.base_diameter_mm
        return self.top_diameter_mm + 2 * FLANK_RUN_MM


def _check_grid(lambda_mm: float, size_mm: float, pixel_mm: float) -> int:
    """Pixels per side; InputError unless lambda, map side and pixel size (mm) are usable together."""
    n = map_side(size_mm, pixel_mm)
    positive("lambda_mm", lambda_mm)
    if lambda_mm < MIN_PIXELS_PER_LAMBDA * pixel_mm:
        raise InputError(f"lambda_mm={lambda_mm} is below {MIN_PIXELS_PER_LAMBDA} pixels of {pixel_mm} mm; "
                         f"use lambda >= {MIN_PIXELS_PER_LAMBDA * pixel_mm} mm or smaller pixels", "lambda_mm")
    if size_mm < 2 * lambda_mm:
        raise InputError(f"size_mm={size_mm} is too small for lambda_mm={lambda_mm} (need >= 2 lambda)", "size_mm")
    return n


def _check_recipe(recipe: BumpRecipe) -> int:
    """Pixels per side; InputError with a specific message for any invalid recipe parameter."""
    check_seed(recipe.seed)
    for name in ("lambda_mm", "top_diameter_mm", "height_mm"):
        positive(name, getattr(recipe, name))
    if recipe.height_mm > MAX_HEIGHT_MM:
        raise InputError(f"height_mm={recipe.height_mm:g} is above {MAX_HEIGHT_MM:g} mm (MAX_HEIGHT_MM): no texture",
                         parameter="height_mm")
    if recipe.base_diameter_mm is not None:
        positive("base_diameter_mm", recipe.base_diameter_mm)
    n = _check_grid(recipe.lambda_mm, recipe.size_mm, recipe.pixel_mm)
    if recipe.top not in TOPS:
        raise InputError(f"top must be one of {TOPS}, got {recipe.top!r}", "top")
    if recipe.size_mm <= recipe.base_mm:
        raise InputError(f"size_mm={recipe.size_mm} must exceed base_diameter_mm={recipe.base_mm}", "size_mm")
    d = recipe.top_diameter_mm
    if recipe.top == "flat" and not 0.1 - 1e-9 <= d <= 0.5 + 1e-9:
        raise InputError(f"flat top_diameter_mm must be within 0.1..0.5 mm, got {d}", "top_diameter_mm")
    if not d < recipe.base_mm:
        raise InputError(f"top_diameter_mm={d} must be below base_diameter_mm={recipe.base_mm}", "top_diameter_mm")
    return n


def _ring_field(lambda_mm: float, n: int, pixel_mm: float, rng: np.random.Generator) -> np.ndarray:
    """Periodic (n, n) random-phase field with a ring spectrum at RING_FACTOR / lambda cycles/mm."""
    f = np.fft.fftfreq(n)  # cycles/pixel
    radius = np.hypot(f[:, None], f[None, :])
    r0 = RING_FACTOR * pixel_mm / lambda_mm
    magnitude = np.exp(-0.5 * ((radius - r0) / (RING_WIDTH * r0)) ** 2)
    phase = np.exp(2j * np.pi * rng.random((n, n)))
    return np.fft.ifft2(magnitude * phase).real


def _strict_maxima(field: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row and column indices of pixels strictly above their 8 periodic neighbours (no plateaus)."""
    footprint = np.ones((3, 3), dtype=bool)
    footprint[1, 1] = False
    neighbours = ndimage.maximum_filter(field, footprint=footprint, mode="wrap")
    return np.nonzero(field > neighbours)


def bump_centres(lambda_mm: float, size_mm: float, pixel_mm: float, rng: np.random.Generator) -> np.ndarray:
    """Bump centres (k, 2) as x, y in mm on pixel centres of a periodic map of side ``size_mm``.

    The side is rounded to whole pixels; all centres lie in [0, side).
    """
    n = _check_grid(lambda_mm, size_mm, pixel_mm)
    rows, cols = _strict_maxima(_ring_field(lambda_mm, n, pixel_mm, rng))
    return np.column_stack(((cols + 0.5) * pixel_mm, (rows + 0.5) * pixel_mm))


def _cap_slope(height_mm: float, base_radius_mm: float, top_radius_mm: float) -> float:
    """Flank slope (mm/mm) of a cone whose tangent spherical cap of footprint radius a reaches the height."""
    run, a = base_radius_mm - top_radius_mm, top_radius_mm

    def excess(s: float) -> float:
        return s * run + a * (math.sqrt(1 + s * s) - 1) / s - height_mm

    return optimize.brentq(excess, 1e-9, height_mm / run)


def _bump_profile(recipe: BumpRecipe, r: np.ndarray) -> np.ndarray:
    """Bump height (mm) at radial distance r (mm) from its centre; 0 beyond the base."""
    big_r, a, h = recipe.base_mm / 2, recipe.top_diameter_mm / 2, recipe.height_mm
    if recipe.top == "flat":
        z = np.minimum(h, h * (big_r - r) / (big_r - a))
    else:
        s = _cap_slope(h, big_r, a)
        sphere_r = a * math.sqrt(1 + 1 / s**2)
        sphere_z = h - sphere_r
        cap = sphere_z + np.sqrt(np.maximum(sphere_r**2 - r**2, 0.0))
        z = np.where(r < a, cap, s * (big_r - r))
    return np.clip(z, 0.0, h)


def _render(recipe: BumpRecipe, centres: np.ndarray, n: int) -> np.ndarray:
    """Periodic (n, n) heightmap (mm): the maximum over bumps at the given centres (mm)."""
    p = recipe.pixel_mm
    reach = math.ceil(recipe.base_mm / 2 / p)
    offsets = np.arange(-reach, reach + 1)
    local = _bump_profile(recipe, p * np.hypot(offsets[:, None], offsets[None, :]))
    heights = np.zeros((n, n))
    for ci, cj in np.rint(centres[:, ::-1] / p - 0.5).astype(int):
        window = np.ix_((ci + offsets) % n, (cj + offsets) % n)
        heights[window] = np.maximum(heights[window], local)
    return heights


def bump_texture(recipe: BumpRecipe) -> Heightmap:
    """Heightmap (mm) of a bump texture; deterministic per ``recipe.seed``, seamlessly periodic."""
    n = _check_recipe(recipe)
    rng = np.random.default_rng(recipe.seed)
    centres = bump_centres(recipe.lambda_mm, recipe.size_mm, recipe.pixel_mm, rng)
    return Heightmap(heights=_render(recipe, centres, n), pixel_mm=recipe.pixel_mm)


def standard_texture(lambda_mm: float, seed: int = 0, **overrides) -> Heightmap:
    """Cap-topped texture at a lambda (mm) of STANDARD_LAMBDAS_MM; overrides go to BumpRecipe."""
    if not any(math.isclose(real("lambda_mm", lambda_mm), lam) for lam in STANDARD_LAMBDAS_MM):
        raise InputError(f"lambda_mm={lambda_mm} is not on the standard scale {STANDARD_LAMBDAS_MM}",
                         parameter="lambda_mm")
    return bump_texture(bump_recipe({"lambda_mm": lambda_mm, "top": "cap", "seed": seed}, overrides))


def bump_recipe(fixed: dict, overrides: dict) -> BumpRecipe:
    """The BumpRecipe of a named kind of texture (its ``fixed`` fields) with a caller's ``overrides``; InputError
    naming an override that is not a field, or that the kind fixes."""
    known = {f.name for f in dataclass_fields(BumpRecipe)}
    for name in overrides:
        if name not in known:
            raise InputError(f"{name!r} is not a bump texture parameter; BumpRecipe's fields are "
                             f"{', '.join(sorted(known))}", parameter=name)
        if name in fixed:
            raise InputError(f"this texture sets {name}={fixed[name]!r}; bump_texture(BumpRecipe(...)) takes any",
                             parameter=name)
    return BumpRecipe(**fixed, **overrides)


def flat_top_texture(top_diameter_mm: float, seed: int = 0, lambda_mm: float = 1.0, **overrides) -> Heightmap:
    """Flat-topped texture with plateau diameter ``top_diameter_mm`` (0.1..0.5 mm)."""
    return bump_texture(bump_recipe({"lambda_mm": lambda_mm, "top": "flat", "top_diameter_mm": top_diameter_mm,
                                     "seed": seed}, overrides))


def texture_names() -> list[str]:
    """Names accepted by named_texture."""
    return ([f"standard-{lam}" for lam in STANDARD_LAMBDAS_MM]
            + [f"flattop-{d}" for d in FLAT_TOP_DIAMETERS_MM] + ["flat"])


def named_texture(name: str, seed: int = 0) -> Heightmap:
    """Texture by name: ``standard-<lambda>``, ``flattop-<diameter>`` (lambda 1 mm) or ``flat`` (zeros)."""
    check_seed(seed)
    if name not in texture_names():
        raise InputError(f"unknown texture {name!r}; valid names: {', '.join(texture_names())}", parameter="name")
    if name == "flat":
        recipe = BumpRecipe(lambda_mm=1.0)
        return flat(recipe.size_mm, recipe.pixel_mm)
    kind, value = name.split("-")
    if kind == "standard":
        return standard_texture(float(value), seed=seed)
    return flat_top_texture(float(value), seed=seed)


def nearest_neighbour_spacing(centres: np.ndarray, period_mm: float | None = None) -> float:
    """Mean nearest-neighbour distance (mm) of (k, 2) centres; toroidal if ``period_mm`` is given."""
    centres = np.asarray(centres, dtype=float)
    if centres.ndim != 2 or centres.shape[1] != 2 or len(centres) < 2:
        raise InputError(f"need at least two (x, y) centres, got shape {centres.shape}")
    distances, _ = cKDTree(centres, boxsize=period_mm).query(centres, k=2)
    return float(distances[:, 1].mean())

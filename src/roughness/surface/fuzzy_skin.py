"""Fuzzy skin as the slicers print it: a vertical wall seen by a finger, as a heightmap (mm).

The slicers' rule (PrusaSlicer 2.9.4, src/libslic3r/Feature/FuzzySkin/FuzzySkin.cpp, ``fuzzy_polyline``, commit
69c8e569410e; OrcaSlicer, same file, ``fuzzy_polyline`` / ``fuzzy_extrusion_line``, commit 0051ba1662e1; both
after Cura): the outer perimeter of each layer is replaced by new points, the first a uniform random distance in
[0, 3/8 ``fuzzy_skin_point_distance``) along it, each next one 3/4 to 5/4 of the point distance further
(uniform); each point is moved perpendicular to the perimeter by the noise (``fuzzy_noise``) times
``fuzzy_skin_thickness``, and the points are joined by straight extrusions. OrcaSlicer's ``fuzzy_skin_mode``:
displacement moves the points; extrusion widens the line by the noise instead (its outer face moves by half of
it); combined widens it and moves its centre by half the widening (the outer face moves by all of it). OrcaSlicer
applies the mode to Arachne walls only (``fuzzy_extrusion_line``); its classic wall generator always displaces. The
slicers start every layer afresh with new random numbers (Classic differs at every slice); here ``seed`` makes a
wall repeatable.

The wall is a periodic tile: x along the wall (one closed perimeter of ``tile_mm``, as a loop is fuzzed: the
seam's gap is whatever the rule leaves), y up the wall in whole layers, height out of the wall. The printed
surface is the bead swept along each layer's path: its cross-section a stadium ``line_width_mm`` wide (into the
wall) and one layer tall (semicircular faces of radius half a layer; nophead 2014, as in ``printing``), so at a
height u from the layer's middle the outer face is the path offset by (w - h) / 2 + sqrt((h/2)^2 - u^2): the
upper envelope of disks of that radius on the path (a bead cannot follow a zigzag finer than its width). Heights
are measured from the crest of the plain wall (its layers' middles are at 0, the seams between layers at -h/2).
The line width shapes the surface along the wall, the layer height across it; the nozzle bounds neither.
Not modelled: Orca's ripple noise, ``fuzzy_skin_first_layer``, seams and blobs, the melt's sag between layers.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import in_range
from roughness.core.errors import InputError
from roughness.core.limits import MAX_FILTER_TAPS, MAX_HEIGHTMAP_PIXELS, check_size

from .fuzzy_noise import NOISE_TYPES, noise
from .heightmap import Heightmap
from .printing import FdmProfile

MODES = ("displacement", "extrusion", "combined")  # OrcaSlicer's fuzzy_skin_mode
MIN_SPACING = 0.75  # the slicers' hard-coded point spacing: 3/4 to 5/4 of fuzzy_skin_point_distance
SPACING_RANGE = 0.5
SUPERSAMPLE = 4  # path samples per map pixel along the wall, for the bead's envelope
MIN_EXTRUSION_WIDTH = 0.01  # mm: OrcaSlicer's least line width in extrusion mode
MAX_WALL_POINTS = 5_000_000  # fuzzy points x layers of one tile
MIN_LAYER_PIXELS = 2  # a layer's bead needs this many pixel rows at least
MAX_LAYER_UNIT = 100  # the wall's period up it: at most this many layers to span whole pixels
# the settings' domains (mm where lengths): OrcaSlicer's for the noise; thickness and point distance up to what a
# hand can feel on a wall (OrcaSlicer allows thickness 0-1 mm and any point distance)
RANGES = {"fuzzy_skin_thickness": (0.0, 5.0), "fuzzy_skin_point_distance": (0.01, 50.0),
          "fuzzy_skin_scale": (0.1, 500.0), "fuzzy_skin_octaves": (1, 10), "fuzzy_skin_persistence": (0.01, 1.0)}


@dataclass(frozen=True)
class FuzzySkin:
    """The slicers' fuzzy skin settings (lengths in mm), named as OrcaSlicer names them."""

    fuzzy_skin_thickness: float = 0.3
    fuzzy_skin_point_distance: float = 0.8
    fuzzy_skin_noise_type: str = "classic"
    fuzzy_skin_scale: float = 1.0  # feature size of the coherent noises
    fuzzy_skin_octaves: int = 4
    fuzzy_skin_persistence: float = 0.5
    fuzzy_skin_mode: str = "displacement"

    def __post_init__(self) -> None:
        for name in ("fuzzy_skin_thickness", "fuzzy_skin_point_distance", "fuzzy_skin_scale", "fuzzy_skin_persistence"):
            object.__setattr__(self, name, in_range(name, getattr(self, name), *RANGES[name]))
        low, high = RANGES["fuzzy_skin_octaves"]
        if isinstance(self.fuzzy_skin_octaves, bool) or not isinstance(self.fuzzy_skin_octaves, int | np.integer) \
                or not low <= self.fuzzy_skin_octaves <= high:
            raise InputError(f"fuzzy_skin_octaves must be a whole number from {low} to {high}, got "
                             f"{self.fuzzy_skin_octaves!r}", parameter="fuzzy_skin_octaves")
        for name, allowed in (("fuzzy_skin_noise_type", NOISE_TYPES), ("fuzzy_skin_mode", MODES)):
            if getattr(self, name) not in allowed:
                raise InputError(f"{name} must be one of {', '.join(allowed)}, got {getattr(self, name)!r}",
                                 parameter=name)

    def describe(self) -> str:
        text = (f"fuzzy skin {self.fuzzy_skin_noise_type}, thickness {self.fuzzy_skin_thickness:g} mm, point distance "
                f"{self.fuzzy_skin_point_distance:g} mm")
        if self.fuzzy_skin_noise_type != "classic":
            text += f", feature size {self.fuzzy_skin_scale:g} mm"
            if self.fuzzy_skin_noise_type != "voronoi":
                text += f", {self.fuzzy_skin_octaves} octaves"
            if self.fuzzy_skin_noise_type in ("perlin", "billow"):
                text += f", persistence {self.fuzzy_skin_persistence:g}"
        return text + ("" if self.fuzzy_skin_mode == "displacement" else f", {self.fuzzy_skin_mode} mode")


@dataclass(frozen=True)
class FuzzyLayer:
    """One layer's fuzzy points along the wall: positions (mm from the tile's start) and outer-face offsets (mm)."""

    x_mm: np.ndarray
    offset_mm: np.ndarray


@dataclass(frozen=True)
class FuzzyWall:
    """A printed fuzzy-skin wall: the heightmap tile, its layers' points, and what made it."""

    heightmap: Heightmap
    layers: tuple[FuzzyLayer, ...]
    skin: FuzzySkin
    profile: FdmProfile
    seed: int


def fuzzy_points(skin: FuzzySkin, length_mm: float, slice_z_mm: float, line_width_mm: float, seed: int,
                 rng: np.random.Generator) -> FuzzyLayer:
    """One layer's perimeter of ``length_mm`` (a closed loop along x, at height ``slice_z_mm``) fuzzed by the
    slicers' rule; Classic and the spacing draw from ``rng``."""
    d = skin.fuzzy_skin_point_distance
    start = rng.uniform() * MIN_SPACING * d / 2
    count = int(math.ceil(length_mm / (MIN_SPACING * d))) + 1
    x = start + np.concatenate(([0.0], np.cumsum(MIN_SPACING * d + rng.uniform(size=count) * SPACING_RANGE * d)))
    x = x[x < length_mm]
    r = skin.fuzzy_skin_thickness * noise(skin.fuzzy_skin_noise_type, x, np.zeros_like(x), np.full_like(x, slice_z_mm),
                                          skin.fuzzy_skin_scale, skin.fuzzy_skin_octaves,
                                          skin.fuzzy_skin_persistence, seed, rng)
    return FuzzyLayer(x, _outer_offset(r, skin.fuzzy_skin_mode, line_width_mm))


def _outer_offset(r: np.ndarray, mode: str, width_mm: float) -> np.ndarray:
    """How far the line's outer face moves (mm) for noise ``r`` (mm) in OrcaSlicer's ``fuzzy_skin_mode``:
    displacement moves the line by r; extrusion makes it max(w + r + 0.01, 0.01) mm wide about its centre (the
    face moves by half the change); combined also moves the centre out by half the change (the face moves by
    all of it)."""
    if mode == "displacement":
        return r
    change = np.maximum(width_mm + r + MIN_EXTRUSION_WIDTH, MIN_EXTRUSION_WIDTH) - width_mm
    return change / 2 if mode == "extrusion" else change


def fuzzy_wall(skin: FuzzySkin, profile: FdmProfile, tile_mm: float = 12.0, pixel_mm: float = 0.05,
               seed: int = 0, bead: bool = True) -> FuzzyWall:
    """The printed wall of ``skin`` on ``profile`` (its layer height and line width) as a periodic tile on
    ``pixel_mm`` pixels: ``tile_mm`` along the wall (x), and up it (y) the fewest whole layers that span whole pixels
    and at least ``tile_mm``. ``bead`` False: each layer's path alone over the layer's rows (no bead; an
    ablation that shows what the bead changes)."""
    if not isinstance(profile, FdmProfile):
        raise InputError(f"fuzzy skin is a setting of FDM slicers; printer {profile.name} is {profile.kind}",
                         parameter="printer")
    tile_mm = in_range("tile_mm", tile_mm, 1.0, 200.0)
    pixel_mm = in_range("pixel_mm", pixel_mm, 0.001, 1.0)
    h, w = profile.layer_mm, profile.line_width_mm
    nx = int(round(tile_mm / pixel_mm))
    if abs(nx * pixel_mm - tile_mm) > 1e-6 * tile_mm:
        raise InputError(f"tile_mm ({tile_mm:g}) must be a whole number of {pixel_mm:g} mm pixels",
                         parameter="tile_mm")
    if h < MIN_LAYER_PIXELS * pixel_mm * (1 - 1e-9):
        raise InputError(f"the {h:g} mm layer spans fewer than {MIN_LAYER_PIXELS} pixels of {pixel_mm:g} mm: its bead "
                         f"cannot be represented; use --pixel-mm {h / MIN_LAYER_PIXELS:g} or less", parameter="pixel_mm")
    unit = _layer_unit(h, pixel_mm)
    layers = unit * math.ceil(tile_mm / (unit * h) - 1e-9)
    ny = int(round(layers * h / pixel_mm))
    points = layers * (tile_mm / (MIN_SPACING * skin.fuzzy_skin_point_distance) + 2)
    if points > MAX_WALL_POINTS:
        raise InputError(f"{points:,.0f} fuzzy points in a {tile_mm:g} mm tile (above {MAX_WALL_POINTS:,}): use a "
                         "larger fuzzy_skin_point_distance or a smaller tile", parameter="fuzzy_skin_point_distance")
    check_size(f"a {tile_mm:g} mm wall tile of {pixel_mm:g} mm pixels", float(ny * nx), MAX_HEIGHTMAP_PIXELS,
               "pixel_mm")
    taps = 2 * int(w / 2 / (pixel_mm / SUPERSAMPLE)) + 1  # the widest bead envelope's kernel
    check_size("bead envelope filter taps", float(ny * nx * SUPERSAMPLE) * taps, MAX_FILTER_TAPS, "pixel_mm")
    rng = np.random.default_rng(seed)
    fine = (np.arange(nx * SUPERSAMPLE) + SUPERSAMPLE / 2) * pixel_mm / SUPERSAMPLE  # every SUPERSAMPLE-th: a pixel centre
    made = tuple(fuzzy_points(skin, tile_mm, (k + 0.5) * h, w, seed, rng) for k in range(layers))
    paths = [_path(layer, fine, tile_mm) for layer in made]
    y = (np.arange(ny) + 0.5) * pixel_mm
    row_layer = np.minimum((y / h).astype(int), layers - 1)
    u = y - (row_layer + 0.5) * h  # each row's height above its layer's middle
    radius = (w - h) / 2 + np.sqrt(np.maximum((h / 2) ** 2 - u**2, 0.0))
    if not bead:
        return FuzzyWall(Heightmap(np.array([paths[k][::SUPERSAMPLE] for k in row_layer]), pixel_mm), made, skin,
                         profile, seed)
    out = np.empty((ny, nx))
    for row, (k, rad) in enumerate(zip(row_layer, radius)):
        out[row] = _envelope(paths[k], rad, pixel_mm / SUPERSAMPLE)[::SUPERSAMPLE]
    return FuzzyWall(Heightmap(out - w / 2, pixel_mm), made, skin, profile, seed)


def _layer_unit(layer_mm: float, pixel_mm: float) -> int:
    """The fewest layers that span a whole number of pixels (the wall's period up it is a multiple)."""
    for n in range(1, MAX_LAYER_UNIT + 1):
        span = n * layer_mm / pixel_mm
        if abs(span - round(span)) <= 1e-6 * span:
            return n
    raise InputError(f"no {MAX_LAYER_UNIT} or fewer {layer_mm:g} mm layers span a whole number of {pixel_mm:g} mm "
                     "pixels: choose a pixel size that divides a few layers", parameter="pixel_mm")


def _path(layer: FuzzyLayer, x: np.ndarray, length_mm: float) -> np.ndarray:
    """The outer face's offset along the closed loop at ``x``: straight lines between the points (the last joined
    to the first across the tile's end)."""
    if len(layer.x_mm) == 0:
        return np.zeros_like(x)
    xp = np.concatenate((layer.x_mm[-1:] - length_mm, layer.x_mm, layer.x_mm[:1] + length_mm))
    fp = np.concatenate((layer.offset_mm[-1:], layer.offset_mm, layer.offset_mm[:1]))
    return np.interp(x, xp, fp)


def _envelope(path: np.ndarray, radius_mm: float, step_mm: float) -> np.ndarray:
    """The upper envelope of disks of ``radius_mm`` centred on the periodic ``path`` (samples ``step_mm`` apart),
    measured from the path's level: a grey dilation with a semicircular structuring element."""
    from scipy import ndimage

    reach = int(radius_mm / step_mm)
    k = np.arange(-reach, reach + 1) * step_mm
    return ndimage.grey_dilation(path, structure=np.sqrt(np.maximum(radius_mm**2 - k**2, 0.0)), mode="wrap")

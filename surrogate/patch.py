"""The surrogate's input: the heightmap under the 10 mm skin footprint, on the model's pixel grid.

Numpy only (prediction runs without torch). The patch is box-averaged from the heightmap
(bilinear sub-samples, so any input pixel size works; a 0.05 mm map averages exactly 2x2
pixels into 0.1 mm) and referenced to its highest point, as the FEM presses the skin onto
the highest point of the footprint: every value is <= 0 mm.
"""
from __future__ import annotations

import math

import numpy as np

from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, PIXEL_RTOL, check_size
from roughness.simulate.config import SimConfig
from roughness.surface.heightmap import Heightmap, bracket

FOOTPRINT_MM = SimConfig.width_mm  # the skin block's width (mm) that the surrogate was trained for
PATCH_PIXEL_MM = 0.1  # model pixel size
PATCH_SIZE = round(FOOTPRINT_MM / PATCH_PIXEL_MM)
ROUNDINGS = 16  # float64 roundings a sample position or a centre's offset carries (a few operations, with margin)
DESCRIPTOR_NAMES = ("relief_mm", "feature_mm", "rms_slope", "p99_slope")


def footprint_patch(heightmap: Heightmap, centre_mm: tuple[float, float] | None = None, tile: bool = False,
                    pixel_mm: float = PATCH_PIXEL_MM, width_mm: float = FOOTPRINT_MM) -> np.ndarray:
    """Heights (mm, max 0) of the footprint square centred at ``centre_mm`` on ``pixel_mm`` pixels.

    Each patch pixel is the mean of sub x sub bilinear samples of the map (sub: ``samples_per_pixel``,
    about pixel_mm / map pixel); bilinear sampling is separable, so rows are averaged first, then columns
    (``_average``: gathers and weighted sums, no matrix product, so no BLAS threads start for a
    small patch). Raises InputError (from the heightmap) if the footprint leaves a non-tiled map; the map's own
    centre (no ``centre_mm``) is not checked as a given centre would be.
    """
    if centre_mm is not None:
        return footprint_patches(heightmap, np.array([centre_mm]), tile, pixel_mm, width_mm)[0]
    heightmap.require_footprint(width_mm, None, tile)
    return _patches(heightmap, np.array([heightmap.centre_mm]), tile, pixel_mm, width_mm)[0]


def samples_per_pixel(pixel_mm: float, map_pixel_mm: float) -> int:
    """Bilinear samples per patch pixel of ``pixel_mm`` along each axis, so that none lies further than a map pixel
    of ``map_pixel_mm`` from the next: a ratio within the pixel size's precision (PIXEL_RTOL) above a whole number
    is that number, so a 0.05 mm pixel stored as float32 metres (0.0499999987 mm) is sampled as 0.05 mm is."""
    return max(1, math.ceil(pixel_mm / map_pixel_mm * (1 - PIXEL_RTOL)))


def _round_off(magnitude: float) -> float:
    """The float64 round-off of a few operations (ROUNDINGS) on numbers up to ``magnitude``."""
    return ROUNDINGS * np.finfo(float).eps * (1.0 + magnitude)


def _average(values: np.ndarray, axis: int, start_mm: float, n: int, pixel_mm: float, sub: int,
             map_pixel_mm: float, periodic: bool) -> np.ndarray:
    """``values`` (2-D) averaged along ``axis`` into ``n`` pixels of ``pixel_mm`` from ``start_mm``:
    each the mean of ``sub`` bilinear samples.

    Works on rows (axis 1 through the transposed view: gathering rows and summing strided row slices is
    several times faster than np.take along the last axis and a reshaped mean). Samples that fall on
    pixel centres (a 0.05 mm map on the 0.1 mm grid, footprint on the pixel lattice) are read, not
    interpolated. The samples taken (n * sub rows of the other axis's length) are checked against
    MAX_HEIGHTMAP_PIXELS first: a map pixel far finer than ``pixel_mm`` would take billions."""
    check_size(f"samples of the {map_pixel_mm:g} mm map pixels to average into {n} patch pixels of {pixel_mm:g} mm "
               f"({sub:,} per patch pixel, over {values.shape[1 - axis]:,} map pixels across)",
               n * sub * values.shape[1 - axis], MAX_HEIGHTMAP_PIXELS, "pixel_mm")
    offsets = (np.arange(sub) + 0.5) / sub * pixel_mm
    u = ((start_mm + np.arange(n)[:, None] * pixel_mm + offsets) / map_pixel_mm - 0.5).ravel()
    lower, upper, frac = bracket(u, values.shape[axis], periodic)
    rows = values if axis == 0 else values.T
    on_centre = _round_off(float(np.abs(u).max()))  # a sample this close to a pixel centre (in pixels) reads it
    if np.all((frac < on_centre) | (frac > 1 - on_centre)):
        samples = rows[np.where(frac > 0.5, upper, lower)]
    else:
        low = rows[lower]
        samples = low + (rows[upper] - low) * frac[:, None]
    out = samples[0::sub].copy()  # sample k of output pixel i is row i * sub + k
    for k in range(1, sub):
        out += samples[k::sub]
    out *= 1.0 / sub
    return out if axis == 0 else out.T


def footprint_patches(heightmap: Heightmap, centres_mm: np.ndarray, tile: bool = False,
                      pixel_mm: float = PATCH_PIXEL_MM, width_mm: float = FOOTPRINT_MM) -> np.ndarray:
    """``footprint_patch`` at each of the centres (k, 2) x, y in mm, as (k, P, P) float32.

    The same arithmetic, shared between footprints. When the centres lie on a grid of pitch
    ``pixel_mm`` (a map whose step is a multiple of the patch pixel), every footprint is a window of
    one box-averaged grid over their bounding box (strided patches); otherwise the rows are
    averaged once per distinct y.
    """
    centres_mm = np.asarray(centres_mm, dtype=float).reshape(-1, 2)
    for centre in dict.fromkeys(map(tuple, centres_mm.tolist())):  # distinct centres (np.unique of floats
        heightmap.require_footprint(width_mm, centre, tile)            # imports numpy.ma: 20 ms at start-up)
    return _patches(heightmap, centres_mm, tile, pixel_mm, width_mm)


def _patches(heightmap: Heightmap, centres_mm: np.ndarray, tile: bool, pixel_mm: float,
             width_mm: float) -> np.ndarray:
    """``footprint_patches`` at centres already checked."""
    n = round(width_mm / pixel_mm)
    sub = samples_per_pixel(pixel_mm, heightmap.pixel_mm)  # finite: heightmap pixels >= MIN_PIXEL_MM
    origin = centres_mm.min(axis=0)
    steps = (centres_mm - origin) / pixel_mm
    out = np.empty((len(centres_mm), n, n), dtype=np.float32)
    if np.allclose(steps, np.rint(steps), rtol=0, atol=_round_off(float(np.abs(centres_mm).max()) / pixel_mm)):
        ix, iy = np.rint(steps).astype(int).T
        band = _average(heightmap.heights, 0, origin[1] - width_mm / 2, n + iy.max(), pixel_mm, sub,
                        heightmap.pixel_mm, tile)
        grid = _average(band, 1, origin[0] - width_mm / 2, n + ix.max(), pixel_mm, sub, heightmap.pixel_mm, tile)
        for i, (x, y) in enumerate(zip(ix, iy)):
            window = grid[y:y + n, x:x + n]
            out[i] = window - window.max()
        return out
    for y in sorted(set(centres_mm[:, 1].tolist())):
        band = _average(heightmap.heights, 0, y - width_mm / 2, n, pixel_mm, sub, heightmap.pixel_mm, tile)
        for i in np.flatnonzero(centres_mm[:, 1] == y):
            patch = _average(band, 1, centres_mm[i, 0] - width_mm / 2, n, pixel_mm, sub, heightmap.pixel_mm, tile)
            out[i] = patch - patch.max()
    return out


def descriptors(patch: np.ndarray, pixel_mm: float = PATCH_PIXEL_MM) -> np.ndarray:
    """Hand-made shape descriptors of a patch, in DESCRIPTOR_NAMES order (``batch_descriptors`` of one)."""
    return batch_descriptors(np.asarray(patch)[None], pixel_mm)[0]


def batch_descriptors(patches: np.ndarray, pixel_mm: float = PATCH_PIXEL_MM, chunk: int = 32) -> np.ndarray:
    """Descriptors (n, 4) of patches (n, P, P), in DESCRIPTOR_NAMES order; ``chunk`` patches at a time
    (their temporaries stay in cache).

    relief (mm): 99.5th minus 0.5th percentile height; feature (mm): 2 pi std / rms slope (capped
    at 100 mm for flat patches); rms and 99th-percentile slope magnitude (dimensionless).
    """
    patches = np.asarray(patches, dtype=np.float32)
    if len(patches) > chunk:
        return np.concatenate([_descriptors(patches[i:i + chunk], pixel_mm) for i in range(0, len(patches), chunk)])
    return _descriptors(patches, pixel_mm)


def _descriptors(heights: np.ndarray, pixel_mm: float) -> np.ndarray:
    """batch_descriptors of one chunk of float32 patches (float32 like the network's input: half the traffic)."""
    k = len(heights)
    gx = np.empty_like(heights)
    gy = np.empty_like(heights)
    for g, axis in ((gy, 1), (gx, 2)):  # np.gradient: central differences inside, one-sided at the edges
        src = np.moveaxis(heights, axis, 1)
        dst = np.moveaxis(g, axis, 1)
        dst[:, 1:-1] = (src[:, 2:] - src[:, :-2]) / np.float32(2 * pixel_mm)
        dst[:, 0] = (src[:, 1] - src[:, 0]) / np.float32(pixel_mm)
        dst[:, -1] = (src[:, -1] - src[:, -2]) / np.float32(pixel_mm)
    squared = (gx * gx + gy * gy).reshape(k, -1)
    rms = np.sqrt(squared.mean(axis=1, dtype=np.float64))
    flat = heights.reshape(k, -1)
    lo, hi = _percentiles(np.sort(flat, axis=1), (0.5, 99.5))
    std = flat.std(axis=1, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        feature = np.where(rms > 0, np.minimum(100.0, 2 * math.pi * std / rms), 100.0)
    [p99] = _percentiles(np.sqrt(np.sort(squared, axis=1)), (99,))
    return np.column_stack([hi - lo, feature, rms, p99])


def _percentiles(ordered: np.ndarray, qs: tuple[float, ...]) -> list[np.ndarray]:
    """np.percentile's default (linear) of each row of row-sorted values; sorting is the fast way on x86."""
    m = ordered.shape[1]
    out = []
    for q in qs:
        position = q / 100 * (m - 1)
        below = math.floor(position)
        above = min(below + 1, m - 1)
        low, high = ordered[:, below].astype(np.float64), ordered[:, above].astype(np.float64)
        out.append(low + (high - low) * (position - below))
    return out

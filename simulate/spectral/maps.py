"""Roughness maps of whole objects from spectral solves: one over the whole map, or one per window of a larger map.

The whole heightmap, mirrored across its edges (or periodic with ``tile``), is pressed at the
footprint's mean pressure in one contact solve, the strain
fluctuation is computed once over the whole map, and every footprint position's V is sampled from
that one field with the FEM's disk pairs in the position's window. Where the skin is in full
contact (the usual case at 10 N) the texture's strain is a linear, local response (it decays over
about a tissue thickness), so the one field is what each footprint would see on its own; in partial
contact the pressure is shared over the whole map instead of 10 N per footprint, which the result
notes. Positions follow ``simulate.footprints.centres`` (the same grid as the surrogate's ``predict --map``).

A map of more than ``MAX_MAP_PIXELS`` pixels is solved in overlapping windows of at most that many
(``windows``): each window, mirrored across its edges, answers the positions a guard band inside them, and
the answers are stitched. In full contact the stitched map equals the one solve's within the error the
guard band leaves (``windows.GUARD_TISSUES``); in partial contact each window shares the pressure over
itself, which the notes say. Windows run one after the other here, or on Dask (``distributed``).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import positive
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, Limit, check_size
from roughness.surface.heightmap import Heightmap

from ..config import SimConfig
from ..footprints import RoughnessMap, centres, map_positions
from ..variation import PairSampling
from .contact import solve_contact
from .engine import fluctuation, lambda3, tissue_of
from .flat_state import block_flat_state
from .modes import GridKey, modes
from .windows import GUARD_TISSUES, Window, plan_windows

MAX_MAP_PIXELS = Limit(2048 * 2048, "MAX_MAP_PIXELS")  # pixels of one solve: larger maps are solved in windows of at
# most this many. A solve's peak memory grows by about 580 bytes per pixel in full contact (measured: +0.63 GB at 1024^2,
# +2.4 GB at 2048^2 pixels, 2.8 GB in all; 4096^2, the limit before windows, passed 11 GB), more for the real contact
# operators in partial contact.
SAMPLE_CHUNK = 1 << 21  # values interpolated at once (16 MB per float64 array)
MIN_PAIRS_PER_CHUNK = 256  # position rows per chunk are chosen to leave at least this many pairs


@dataclass(frozen=True)
class MapTask:
    """One solve of a map: heights (mm) of the map or of a window, the positions it answers in its own
    coordinates (mm from its corner), and how it is mirrored (``periodic``: a whole tiled map)."""

    heights: np.ndarray
    pixel_mm: float
    xs: np.ndarray
    ys: np.ndarray
    periodic: bool
    config: SimConfig


@dataclass(frozen=True)
class MapAnswer:
    """A solve's sum over disk pairs of |fluctuation difference| at its positions (rows = y), and its contact."""

    sums: np.ndarray
    contact_fraction: float
    message: str


Runner = Callable[[list[MapTask], Callable[[int, MapAnswer], None]], None]  # solves the tasks, reports each answer


def spectral_map(heightmap: Heightmap, step_mm: float = 1.0, tile: bool = False, config: SimConfig | None = None,
                 progress: Callable[[int, int], None] | None = None,
                 runner: Runner | None = None) -> tuple[RoughnessMap, list[str]]:
    """V at footprint centres ``step_mm`` apart over the whole map, and notes on how it was obtained
    (the flat state: ``flat_state.block_flat_state``, as the engine's default). A map of more than
    ``MAX_MAP_PIXELS`` pixels is solved in windows, by ``runner`` (default: here, one after the other;
    ``distributed.dask_runner``: on Dask; a map of one solve is solved here); ``progress(done, total)`` counts
    positions."""
    config = config or SimConfig()
    step_mm = positive("step_mm", step_mm)
    heightmap.require_footprint(config.width_mm, None, tile)
    pixel = heightmap.pixel_mm
    width, height = heightmap.size_mm
    map_positions(heightmap.size_mm, config.width_mm, step_mm, tile)  # before the positions are made
    xs, ys = centres(width, config.width_mm, step_mm, tile), centres(height, config.width_mm, step_mm, tile)
    check_size("pixels of the map (resample it to a coarser pixel)", heightmap.heights.size, MAX_HEIGHTMAP_PIXELS,
               "pixel_mm")
    one = heightmap.heights.size <= MAX_MAP_PIXELS
    windows = [Window.whole(heightmap.shape, len(xs), len(ys))] if one else \
        plan_windows(heightmap.shape, pixel, xs, ys, guard_mm(config, pixel), MAX_MAP_PIXELS, tile)
    tasks = [MapTask(w.heights(heightmap.heights), pixel, xs[w.cols.first:w.cols.stop] - w.cols.start * pixel,
                     ys[w.rows.first:w.rows.stop] - w.rows.start * pixel, tile and one, config) for w in windows]
    total = np.full((len(ys), len(xs)), np.nan)
    answers: dict[int, MapAnswer] = {}

    def stitch(i: int, answer: MapAnswer) -> None:
        w = windows[i]
        total[w.rows.first:w.rows.stop, w.cols.first:w.cols.stop] = answer.sums
        answers[i] = answer
        if progress:
            progress(sum(windows[j].positions for j in answers), total.size)

    def within(done: int) -> Callable[[int, int], None] | None:
        """``progress`` during a solve here that follows ``done`` positions."""
        return None if progress is None else (lambda d, _: progress(done + d, total.size))

    if runner is not None and not one:
        runner(tasks, stitch)
    for i, task in enumerate(tasks):  # here, one after the other, with progress within each solve
        if i not in answers:
            stitch(i, solve(task, within(sum(windows[j].positions for j in answers))))
    notes = _contact_notes([answers[i] for i in range(len(tasks))], block_flat_state(config).pressure_mpa, config)
    if not one:
        notes.insert(0, f"{heightmap.shape[1]} x {heightmap.shape[0]} pixels are more than one solve's "
                        f"{MAX_MAP_PIXELS:,} ({MAX_MAP_PIXELS.name}): solved in {len(windows)} overlapping windows of "
                        f"{tasks[0].heights.shape[1]} x {tasks[0].heights.shape[0]} pixels, each answering the "
                        f"positions at least {guard_mm(config, pixel):.3g} mm inside its edges that cut the map")
    return RoughnessMap(xs, ys, total / config.pairs, np.ones(total.shape, bool)), notes


def guard_mm(config: SimConfig, pixel_mm: float) -> float:
    """How far inside a window's edge its positions lie (mm): their sampled strain's reach (half the
    sampling window and a pixel) and the guard band of ``GUARD_TISSUES`` tissue thicknesses."""
    return config.window_mm / 2 + pixel_mm + GUARD_TISSUES * config.tissue_mm


def solve(task: MapTask, progress: Callable[[int, int], None] | None = None) -> MapAnswer:
    """One contact solve over ``task``'s heights and the pair sums at its positions (``progress(done, total)``
    counts them)."""
    config, pixel = task.config, task.pixel_mm
    grid = modes(GridKey(task.heights.shape, pixel, tissue_of(config), config.depth_mm,
                         "periodic" if task.periodic else "mirror"))
    flat = block_flat_state(config)
    state = solve_contact(grid, task.heights, flat.pressure_mpa, config.contact == "frictionless")
    field = fluctuation(lambda3(grid.strain(state.face), flat.strain), flat.strain)
    p1, p2 = PairSampling(config.window_mm, config.pair_distance_mm, config.disk_radius_mm, config.pairs,
                          config.seed).points()
    sums = _sum_of_differences(field, task.xs, task.ys, p1, p2, pixel, task.periodic, progress)
    return MapAnswer(sums, float(state.in_contact.mean()), state.message)


def _contact_notes(answers: list[MapAnswer], pressure_mpa: float, config: SimConfig) -> list[str]:
    """A note on the solves in partial contact: the load is shared over the map, or over each window."""
    partial = [a for a in answers if a.message != "full contact"]
    if not partial:
        return []
    count = len(answers)
    where = "the whole map" if count == 1 else f"each window ({len(partial)} of {count} windows in partial contact)"
    return [f"partial contact ({100 * min(a.contact_fraction for a in partial):.1f}% of the "
            f"{'map' if count == 1 else 'least touching window'} touches): the load is shared over {where} at "
            f"{pressure_mpa:.3g} MPa, not {config.force_n:g} N per footprint; {partial[0].message}"]


def _sum_of_differences(field: np.ndarray, xs: np.ndarray, ys: np.ndarray, p1: np.ndarray, p2: np.ndarray,
                        pixel: float, wrap: bool, progress: Callable[[int, int], None] | None) -> np.ndarray:
    """Sum over pairs of |field(centre + p1) - field(centre + p2)| at every (ys, xs) centre (mm)."""
    lattice = _lattice(xs, pixel), _lattice(ys, pixel)
    if None not in lattice:
        total = _on_lattice(field, lattice, len(xs), len(ys), p1, p2, pixel, wrap)
        if progress:
            progress(total.size, total.size)
        return total
    ny, nx = field.shape
    total = np.zeros((len(ys), len(xs)))
    rows = max(1, min(len(ys), SAMPLE_CHUNK // (len(xs) * MIN_PAIRS_PER_CHUNK)))
    per_chunk = max(1, SAMPLE_CHUNK // (rows * len(xs)))
    for start in range(0, len(ys), rows):
        part = ys[start:start + rows]
        for first in range(0, len(p1), per_chunk):
            a, b = p1[first:first + per_chunk], p2[first:first + per_chunk]
            at_a = sample_grid(field, _axis(part, a[:, 1], pixel, ny, wrap), _axis(xs, a[:, 0], pixel, nx, wrap))
            at_b = sample_grid(field, _axis(part, b[:, 1], pixel, ny, wrap), _axis(xs, b[:, 0], pixel, nx, wrap))
            total[start:start + len(part)] += np.abs(at_a - at_b).sum(axis=0)
        if progress:
            progress((start + len(part)) * len(xs), total.size)
    return total


def _lattice(centres_mm: np.ndarray, pixel_mm: float) -> tuple[float, int] | None:
    """(the first centre in pixels, the step in whole pixels) if the centres lie whole pixels apart."""
    at = centres_mm / pixel_mm
    step = round(at[1] - at[0]) if len(at) > 1 else 1
    if step >= 1 and np.allclose(at - at[0], step * np.arange(len(at)), rtol=0, atol=1e-9):
        return float(at[0]), step
    return None


def _on_lattice(field: np.ndarray, lattice: tuple[tuple[float, int], tuple[float, int]], count_x: int, count_y: int,
                p1: np.ndarray, p2: np.ndarray, pixel: float, wrap: bool) -> np.ndarray:
    """``_sum_of_differences`` for centres whole pixels apart: every centre sees a point at the same
    fraction of a pixel, so its bilinear value is four strided slices of the field, with one weight each."""
    (x0, step_x), (y0, step_y) = lattice
    reach = int(np.ceil(max(np.abs(p1).max(), np.abs(p2).max()) / pixel)) + 2
    padded = np.pad(field, reach, mode="wrap" if wrap else "edge")

    def at(point: np.ndarray) -> np.ndarray:
        cx, cy = x0 + point[0] / pixel - 0.5, y0 + point[1] / pixel - 0.5
        ix, iy = int(np.floor(cx)), int(np.floor(cy))
        wx, wy = cx - ix, cy - iy
        ix, iy = ix + reach, iy + reach
        rows = [slice(i, i + step_y * (count_y - 1) + 1, step_y) for i in (iy, iy + 1)]
        cols = [slice(i, i + step_x * (count_x - 1) + 1, step_x) for i in (ix, ix + 1)]
        top = padded[rows[0], cols[0]] * (1 - wx) + padded[rows[0], cols[1]] * wx
        bottom = padded[rows[1], cols[0]] * (1 - wx) + padded[rows[1], cols[1]] * wx
        return top * (1 - wy) + bottom * wy

    total = np.zeros((count_y, count_x))
    for a, b in zip(p1, p2, strict=True):
        total += np.abs(at(a) - at(b))
    return total


AxisWeights = tuple[np.ndarray, np.ndarray, np.ndarray]  # lower and upper pixel index, upper weight: (points, positions)


def _axis(centres_mm: np.ndarray, offsets_mm: np.ndarray, pixel_mm: float, n: int, wrap: bool) -> AxisWeights:
    """Linear interpolation along an axis of ``n`` pixels (centres at (i + 1/2) pixel) at every
    centre + offset: past the outer pixel centres the edge value (map_coordinates' ``nearest``) or,
    with ``wrap``, the other side's (``grid-wrap``)."""
    coord = (centres_mm[None, :] + offsets_mm[:, None]) / pixel_mm - 0.5
    low = np.floor(coord)
    weight = coord - low
    low = low.astype(np.intp)
    if wrap:
        return low % n, (low + 1) % n, weight
    return np.clip(low, 0, n - 1), np.clip(low + 1, 0, n - 1), weight


def sample_grid(field: np.ndarray, rows: AxisWeights, cols: AxisWeights) -> np.ndarray:
    """``field`` bilinearly at point j of every (row position, column position): (points, rows, columns).
    Bilinear interpolation is separable, so a grid of positions needs only each axis's weights."""
    r0, r1, wr = (v[:, :, None] for v in rows)
    c0, c1, wc = (v[:, None, :] for v in cols)
    top = field[r0, c0] * (1 - wc) + field[r0, c1] * wc
    bottom = field[r1, c0] * (1 - wc) + field[r1, c1] * wc
    return top * (1 - wr) + bottom * wr

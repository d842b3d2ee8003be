"""Roughness maps of whole objects from one spectral solve.

The whole heightmap is pressed at the footprint's mean pressure in one contact solve, the strain
fluctuation is computed once over the whole map, and every footprint position's V is sampled from
that one field with the FEM's disk pairs in the position's window. Where the skin is in full
contact (the usual case at 10 N) the texture's strain is a linear, local response (it decays over
about a tissue thickness), so the one field is what each footprint would see on its own; in partial
contact the pressure is shared over the whole map instead of 10 N per footprint, which the result
notes. Positions follow ``simulate.footprints.centres`` (the same grid as the surrogate's ``predict --map``).
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.fft import next_fast_len
from scipy.ndimage import map_coordinates

from roughness.core.checks import positive
from roughness.core.limits import MAX_MAP_POSITIONS, Limit, check_size

from ..config import SimConfig
from ..footprints import RoughnessMap, centre_count, centres
from roughness.surface.heightmap import Heightmap
from ..variation import PairSampling
from .contact import solve_contact
from .engine import fluctuation, lambda3, tissue_of
from .flat_state import block_flat_state
from .modes import GridKey, modes

MARGIN_TISSUES = 2.0  # a non-periodic map is mirror-padded by this many tissue thicknesses on each side
MAX_MAP_PIXELS = Limit(4096 * 4096, "MAX_MAP_PIXELS")  # the padded map's pixels (about 3 GB of fields at the limit)
BATCH_POSITIONS = 256  # footprint positions sampled at once


def padded(heights: np.ndarray, margin: int) -> np.ndarray:
    """``heights`` mirrored outward by ``margin`` pixels, then to FFT-friendly sides (edge values)."""
    out = np.pad(heights, margin, mode="symmetric")
    ny, nx = out.shape
    return np.pad(out, ((0, next_fast_len(ny, real=True) - ny), (0, next_fast_len(nx, real=True) - nx)), mode="edge")


def spectral_map(heightmap: Heightmap, step_mm: float = 1.0, tile: bool = False, config: SimConfig | None = None,
                 progress: Callable[[int, int], None] | None = None) -> tuple[RoughnessMap, list[str]]:
    """V at footprint centres ``step_mm`` apart over the whole map, and notes on how it was obtained
    (the flat state: ``flat_state.block_flat_state``, as the engine's default)."""
    config = config or SimConfig()
    step_mm = positive("step_mm", step_mm)
    heightmap.require_footprint(config.width_mm, None, tile)
    pixel = heightmap.pixel_mm
    width, height = heightmap.size_mm
    count = centre_count(width, config.width_mm, step_mm, tile) * centre_count(height, config.width_mm, step_mm, tile)
    check_size("footprint positions", count, MAX_MAP_POSITIONS, "step_mm")  # before the positions are made
    xs, ys = centres(width, config.width_mm, step_mm, tile), centres(height, config.width_mm, step_mm, tile)
    margin = 0 if tile else int(np.ceil(MARGIN_TISSUES * config.tissue_mm / pixel))
    ny, nx = heightmap.shape
    check_size("pixels of the map with its margins (resample it to a coarser pixel)",
               (ny + 2 * margin) * (nx + 2 * margin), MAX_MAP_PIXELS, "pixel_mm")
    domain = heightmap.heights if tile else padded(heightmap.heights, margin)
    grid = modes(GridKey(domain.shape, pixel, tissue_of(config), config.depth_mm))
    flat = block_flat_state(config)
    state = solve_contact(grid, domain, flat.pressure_mpa, config.contact == "frictionless")
    strain = grid.strain(state.face)[:, margin:margin + ny, margin:margin + nx]
    field = fluctuation(lambda3(strain, flat.strain), flat.strain)
    notes = [] if state.message == "full contact" else [
        f"partial contact ({100 * state.in_contact.mean():.1f}% of the map touches): the load is shared over the "
        f"whole map at {flat.pressure_mpa:.3g} MPa, not {config.force_n:g} N per footprint; {state.message}"]
    p1, p2 = PairSampling(config.window_mm, config.pair_distance_mm, config.disk_radius_mm, config.pairs,
                          config.seed).points()
    positions = np.array([(x, y) for y in ys for x in xs])
    values = np.empty(len(positions))
    mode = "grid-wrap" if tile else "nearest"
    for start in range(0, len(positions), BATCH_POSITIONS):
        batch = positions[start:start + BATCH_POSITIONS]

        def at(points: np.ndarray) -> np.ndarray:
            where = batch[:, None, :] + points[None]  # (positions, pairs, 2) in mm
            coords = [where[..., 1].ravel() / pixel - 0.5, where[..., 0].ravel() / pixel - 0.5]
            return map_coordinates(field, coords, order=1, mode=mode).reshape(len(batch), -1)

        values[start:start + len(batch)] = np.abs(at(p1) - at(p2)).mean(axis=1)
        if progress:
            progress(start + len(batch), len(positions))
    shape = (len(ys), len(xs))
    return RoughnessMap(xs, ys, values.reshape(shape), np.ones(shape, bool)), notes

"""Roughness maps of whole objects: the surrogate at every footprint position on a grid.

The 10 mm footprint slides over the heightmap in steps of ``step_mm``; each position gets V, its
domain flag and, for an ensemble model, the spread of V. Positions are footprint centres from half a
footprint inside one edge to half a footprint inside the other (the whole map, wrapping, if ``tile``).
Footprints are cut out in batches sharing their row and column averaging (patch.footprint_patches);
batches run side by side, one more than the model's threads, each cut out, described and passed through
a one-thread onnxruntime session by one Python thread, so that the cores stay busy while one thread is in
Python (benchmarks/surrogate_map.py). The network is the cost that remains.
"""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.core.figures import new_figure, save_figure
from roughness.core.files import atomic_write, check_output
from roughness.core.limits import MAX_BATCH, MAX_MAP_POSITIONS, check_size
from roughness.simulate.footprints import RoughnessMap, centre_count, centres
from roughness.surface.heightmap import Heightmap

from .patch import batch_descriptors, footprint_patches

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .predictor import Estimate, SurrogateModel


MAP_SUFFIXES = (".npy", ".png")


def check_map_path(path: str | Path, overwrite: bool = False) -> Path:
    """``path`` if a map may be written there (.npy or .png, folder writable, not existing unless ``overwrite``)."""
    path = check_output(path, overwrite, "map")
    if path.suffix.lower() not in MAP_SUFFIXES:
        raise InputError(f"cannot write {path}: a roughness map is saved as .npy or .png", parameter="map")
    return path


def roughness_map(model: SurrogateModel, heightmap: Heightmap, step_mm: float = 1.0, tile: bool = False,
                  batch_size: int = 256, progress: Callable[[int, int], None] | None = None) -> RoughnessMap:
    """V at footprint centres ``step_mm`` apart over the whole map; ``progress(done, total)`` after each batch."""
    step_mm = positive("step_mm", step_mm)
    check_size("footprints per batch", batch_size, MAX_BATCH, "batch_size")
    heightmap.require_footprint(model.footprint_mm, None, tile)
    width, height = heightmap.size_mm
    footprint = model.footprint_mm
    check_size(f"footprint positions on a {width:g} mm x {height:g} mm map in steps of {step_mm:g} mm",
               centre_count(width, footprint, step_mm, tile) * centre_count(height, footprint, step_mm, tile),
               MAX_MAP_POSITIONS, "step_mm")
    xs, ys = centres(width, footprint, step_mm, tile), centres(height, footprint, step_mm, tile)
    grid = [(x, y) for y in ys for x in xs]
    values, spreads, flags = [], [], []

    def batch(start: int) -> Estimate:
        """The estimate of the footprints from ``start`` on: cut out, described, then the network."""
        patches = footprint_patches(heightmap, np.array(grid[start:start + batch_size]), tile, model.pixel_mm,
                                    model.footprint_mm)
        return runner.evaluate(patches, batch_descriptors(patches, model.pixel_mm))

    from concurrent.futures import ThreadPoolExecutor  # here: its import costs ~10 ms of every predict's start-up

    runner = model.single_threaded()
    with ThreadPoolExecutor(max_workers=model.threads + 1) as workers:  # batches side by side, in order
        for estimate in workers.map(batch, range(0, len(grid), batch_size)):
            values.append(estimate.roughness)
            spreads.append(estimate.roughness_std)
            flags += [not r for r in estimate.reasons]
            if progress:
                progress(len(flags), len(grid))
    shape = (len(ys), len(xs))
    spread = None if spreads[0] is None else np.concatenate(spreads).reshape(shape)
    return RoughnessMap(xs, ys, np.concatenate(values).reshape(shape), np.array(flags).reshape(shape), spread)


def save_map(result: RoughnessMap, path: str | Path, overwrite: bool = True) -> Figure | None:
    """.npy: the V array (rows = y); .png: ``map_figure`` (returned)."""
    path = Path(path)
    if path.suffix.lower() not in MAP_SUFFIXES:
        raise InputError(f"cannot write {path}: a roughness map is saved as .npy or .png", parameter="map")
    if path.suffix.lower() == ".npy":
        atomic_write(path, lambda tmp: np.save(tmp, result.roughness), overwrite)
        return None
    return save_figure(map_figure(result), path, 110, overwrite)


def map_figure(result: RoughnessMap) -> Figure:
    """V per footprint centre with axes in mm, out-of-domain positions hatched (beside the ensemble's spread).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (no pyplot: the backend is left as it was).
    """
    x, y = result.x_mm, result.y_mm
    half = (x[1] - x[0]) / 2 if len(x) > 1 else 0.5
    extent = (x[0] - half, x[-1] + half, y[-1] + half, y[0] - half)
    panels = [("V", result.roughness)] + ([("spread of V (ensemble std)", result.roughness_std)]
                                         if result.roughness_std is not None else [])
    fig = new_figure(figsize=(6 * len(panels), 5))
    axes = fig.subplots(1, len(panels), squeeze=False)
    for ax, (label, values) in zip(axes[0], panels):
        image = ax.imshow(values, extent=extent, cmap="magma")
        if not result.in_domain.all():
            ax.contourf(x, y, (~result.in_domain).astype(float), levels=[0.5, 1.5], hatches=["//"], colors="none")
        ax.set(xlabel="x (mm)", ylabel="y (mm)", title=f"{label} per footprint centre (hatched: out of domain)")
        fig.colorbar(image, ax=ax, label=label)
    fig.tight_layout()
    return fig

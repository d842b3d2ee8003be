"""Roughness maps of whole objects from Python and ``roughness predict --map``: the footprint slid over a map.

``predict_map`` answers with the surrogate (``surrogate.roughness_map``; ``auto`` is the surrogate too: a map
has thousands of footprints) or the spectral engine (``simulate.spectral.maps``: one solve over the whole map,
or, above ``MAX_MAP_PIXELS``, overlapping windows). A windowed spectral map runs on Dask as the dataset build
does: ``workers`` local processes by default, or the running cluster named by ``scheduler``, ``scheduler_file``
or ``client``. The surrogate's map stays in this process: its network already keeps a machine's cores busy
(benchmarks/results/surrogate_map.md: 2,870 footprints/s with 2 threads on 2 cores, CPU time twice the wall
time), and one thread does 0.62 ms of CPU per footprint (measured in this issue), so chunks on two
single-threaded local workers would be at most 12% faster, before starting them and loading the model in each.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.provenance import Provenance
from roughness.core.reprs import short_repr
from roughness.surface.heightmap import Heightmap, as_heightmap

if TYPE_CHECKING:
    from dask.distributed import Client

    from roughness.simulate.footprints import RoughnessMap
    from roughness.surrogate.predictor import SurrogateModel

MAP_ENGINES = ("surrogate", "spectral", "auto")
WORKERS = 2  # local Dask worker processes for a windowed spectral map


@dataclass
class MapPrediction:
    """A roughness map (``map``: V per footprint centre) and how it was made."""

    map: RoughnessMap
    engine: str  # "surrogate" or "spectral"
    notes: list[str]
    provenance: Provenance

    def __repr__(self) -> str:
        return short_repr(self, repr(self.map), self.engine, f"{len(self.notes)} note(s)" if self.notes else "")


def predict_map(heightmap: Heightmap | np.ndarray, engine: str = "surrogate", step_mm: float = 1.0,
                tile: bool = False, model: SurrogateModel | str | Path | None = None, batch_size: int = 256,
                pixel_mm: float | None = None, progress: Callable[[int, int], None] | None = None,
                workers: int | None = None, scheduler: str | None = None, scheduler_file: str | None = None,
                client: Client | None = None, quiet: bool = True) -> MapPrediction:
    """The roughness map of a whole object: V at footprint centres ``step_mm`` apart.

    Parameters
    ----------
    heightmap : Heightmap or 2-D array of heights (mm)
        The object's texture; an array needs ``pixel_mm``.
    engine : {"surrogate", "spectral", "auto"}
        ``auto`` is the surrogate. ``spectral``: one solve, or overlapping windows above ``MAX_MAP_PIXELS``.
    step_mm : float
        Distance between footprint centres (mm).
    tile : bool
        The map is one period of a periodic texture.
    model : SurrogateModel or path, optional
        The surrogate (default: the shipped one).
    batch_size : int
        Surrogate footprints per network call.
    pixel_mm : float, optional
        Pixel size (mm) of an array input.
    progress : callable, optional
        ``progress(done, total)`` in footprint positions.
    workers : int, optional
        Spectral windows: local Dask worker processes, one thread each (default 2; 1: here, one after the
        other, without Dask).
    scheduler, scheduler_file, client : optional
        Spectral windows on a running Dask cluster: its scheduler's address, the file ``dask scheduler
        --scheduler-file`` wrote, or a connected ``dask.distributed.Client`` (left open). Its workers must run
        this roughness version (checked).
    quiet : bool
        No Dask messages (dashboard, workers) on stderr.

    Returns
    -------
    MapPrediction
        The map, its engine, notes (windows, partial contact) and provenance.
    """
    from roughness.cluster import ClusterChoice
    from roughness.engines import model_provenance, spectral_provenance

    if engine not in MAP_ENGINES:
        raise InputError(f"a map's engine is one of {', '.join(MAP_ENGINES)} (the FEM would take hours), got "
                         f"{engine!r}", parameter="engine")
    where = ClusterChoice.of(scheduler, scheduler_file, client)
    if workers is not None:
        integer("workers", workers, minimum=1)
    heightmap = as_heightmap(heightmap, pixel_mm)
    if engine != "spectral":
        given = [name for name, value in (("workers", workers), ("scheduler", scheduler),
                                          ("scheduler_file", scheduler_file), ("client", client)) if value is not None]
        if given:
            raise InputError("only a spectral map's windows run on Dask; the surrogate's map runs in this process "
                             "(its network keeps the machine's cores busy)", parameter=given[0])
        from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel
        from roughness.surrogate.roughness_map import roughness_map

        model = model if isinstance(model, SurrogateModel) else SurrogateModel(model or DEFAULT_MODEL)
        result = roughness_map(model, heightmap, step_mm, tile, batch_size, progress=progress)
        return MapPrediction(result, "surrogate", [], model_provenance(model))
    from roughness.simulate.spectral.maps import spectral_map

    runner = None
    if not where.local or (workers or WORKERS) > 1:
        from roughness.simulate.spectral.distributed import dask_runner

        runner = dask_runner(where, workers or WORKERS, quiet)
    result, notes = spectral_map(heightmap, step_mm, tile, progress=progress, runner=runner)
    return MapPrediction(result, "spectral", notes, spectral_provenance())

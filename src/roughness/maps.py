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

from roughness.cluster import ClusterChoice
from roughness.core.checks import flag, function, integer, positive
from roughness.core.errors import InputError
from roughness.core.limits import MAX_BATCH, MAX_PARALLEL, check_size
from roughness.core.provenance import Provenance
from roughness.core.reprs import short_repr
from roughness.simulate.footprints import map_positions
from roughness.surface.arguments import heightmap_argument
from roughness.surface.heightmap import Heightmap
from roughness.surface.tiling import check_tile

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
                client: Client | None = None, quiet: bool = True, units_ok: bool = False) -> MapPrediction:
    """The roughness map of a whole object: V at footprint centres ``step_mm`` apart.

    Parameters
    ----------
    heightmap : Heightmap or 2-D array of heights (mm)
        The object's texture; an array (or nested list of rows) needs ``pixel_mm``.
    engine : {"surrogate", "spectral", "auto"}
        ``auto`` is the surrogate. ``spectral``: one solve, or overlapping windows above ``MAX_MAP_PIXELS``.
    step_mm : float
        Distance between footprint centres (mm); at most ``MAX_MAP_POSITIONS`` positions.
    tile : bool
        The map is one period of a periodic texture.
    model : SurrogateModel or path, optional
        The surrogate (default: the shipped one).
    batch_size : int
        Surrogate footprints per network call (at most ``MAX_BATCH``).
    pixel_mm : float, optional
        Pixel size (mm) of an array input.
    progress : callable, optional
        ``progress(done, total)`` in footprint positions.
    workers : int, optional
        Spectral windows: local Dask worker processes, one thread each (default 2; 1: here, one after the
        other, without Dask; at most ``MAX_PARALLEL``).
    scheduler, scheduler_file, client : optional
        Spectral windows on a running Dask cluster: its scheduler's address, the file ``dask scheduler
        --scheduler-file`` wrote, or a connected ``dask.distributed.Client`` (left open). Its workers must run
        this roughness version (checked).
    quiet : bool
        No Dask messages (dashboard, workers) on stderr.
    units_ok : bool
        The map's numbers are mm even though they look like metres or micrometres (default: refuse them).

    Returns
    -------
    MapPrediction
        The map, its engine, notes (windows, partial contact) and provenance.

    Raises
    ------
    InputError
        A bad argument, named by its ``parameter``; all are checked before any engine runs or any Dask worker starts.
    """
    from roughness.engines import model_provenance, spectral_provenance

    request = _MapRequest.of(heightmap, engine, step_mm, tile, batch_size, pixel_mm, progress, workers, quiet,
                             units_ok)
    where = ClusterChoice.of(scheduler, scheduler_file, client)
    if request.engine != "spectral":
        given = [name for name, value in (("workers", workers), ("scheduler", scheduler),
                                          ("scheduler_file", scheduler_file), ("client", client)) if value is not None]
        if given:
            raise InputError("only a spectral map's windows run on Dask; the surrogate's map runs in this process "
                             "(its network keeps the machine's cores busy)", parameter=given[0])
        from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel
        from roughness.surrogate.roughness_map import roughness_map

        model = model if isinstance(model, SurrogateModel) else SurrogateModel(model or DEFAULT_MODEL)
        request.check_positions(model.footprint_mm)
        result = roughness_map(model, request.heightmap, step_mm, tile, batch_size, progress=progress)
        return MapPrediction(result, "surrogate", [], model_provenance(model))
    from roughness.simulate.config import SimConfig
    from roughness.simulate.spectral.maps import spectral_map

    if model is not None:
        raise InputError("the spectral engine uses no surrogate model; model is for engine='surrogate'",
                         parameter="model")
    request.check_positions(SimConfig().width_mm)
    runner = None
    if not where.local or (workers or WORKERS) > 1:
        from roughness.simulate.spectral.distributed import dask_runner

        runner = dask_runner(where, workers or WORKERS, quiet)
    result, notes = spectral_map(request.heightmap, step_mm, tile, progress=progress, runner=runner)
    return MapPrediction(result, "spectral", notes, spectral_provenance())


@dataclass(frozen=True)
class _MapRequest:
    """``predict_map``'s arguments, checked as ``roughness predict --map`` checks its options and file."""

    heightmap: Heightmap
    engine: str
    step_mm: float
    tile: bool

    @classmethod
    def of(cls, heightmap: object, engine: object, step_mm: object, tile: object, batch_size: object,
           pixel_mm: float | None, progress: object, workers: object, quiet: object, units_ok: bool) -> _MapRequest:
        if engine not in MAP_ENGINES:
            raise InputError(f"a map's engine is one of {', '.join(MAP_ENGINES)} (the FEM would take hours), got "
                             f"{engine!r}", parameter="engine")
        step_mm, tile = positive("step_mm", step_mm), flag("tile", tile)
        check_size("footprints per batch", integer("batch_size", batch_size, minimum=1), MAX_BATCH, "batch_size")
        if workers is not None:
            check_size("Dask workers", integer("workers", workers, minimum=1), MAX_PARALLEL, "workers")
        function("progress", progress)
        flag("quiet", quiet)
        return cls(heightmap_argument(heightmap, pixel_mm, "heightmap", units_ok), str(engine), step_mm, tile)

    def check_positions(self, footprint_mm: float) -> None:
        """InputError unless the footprint fits on the map (or it is tiled) and the positions are few enough."""
        self.heightmap.require_footprint(footprint_mm, None, self.tile)
        if self.tile:
            check_tile(self.heightmap, "heightmap", footprint_mm)
        map_positions(self.heightmap.size_mm, footprint_mm, self.step_mm, self.tile)

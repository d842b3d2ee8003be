"""What a Dask worker of the dataset build runs: one ``Job`` in, one ``Outcome`` out (failures are data).

Each worker process runs one BLAS/OpenMP thread and keeps one prepared ``Simulator`` per configuration, so
the block is meshed and assembled once per worker; the threads of a worker (a cluster's workers may run
several) share it, and get the answers of a sequential run bit for bit (``Simulator`` is thread-safe and
history-free).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from roughness.simulate.config import SimConfig

from .schema import result_fields

if TYPE_CHECKING:
    from .labels import Label



@dataclass(frozen=True)
class Job:
    """One sample to make: its texture record (``recipe.sample_record``) and its label, if a labels file has one."""

    texture_record: dict
    label: Label | None = None


@dataclass(frozen=True)
class Outcome:
    """A worker's answer for one job: what the writer stores with every kind of outcome."""

    texture_record: dict
    heights: np.ndarray | None  # float32 heights (mm) of the texture made; None if it could not be made
    pixel_mm: float  # its pixel size (the record's if it was not made)


@dataclass(frozen=True)
class Simulated(Outcome):
    """Simulated: ``fields`` as ``schema.result_fields`` makes them, and the strain fluctuation map (float32)."""

    fields: dict
    fluctuation: np.ndarray


@dataclass(frozen=True)
class Failed(Outcome):
    """The texture or its simulation failed: ``error`` says why ("ExceptionType: message")."""

    error: str


@dataclass(frozen=True)
class Restored(Outcome):
    """The job's label taken instead of simulating: the texture made matches it (or was not made, nor labelled)."""

    label: Label


@dataclass(frozen=True)
class OtherVersions(Outcome):
    """Nothing done: the worker runs ``versions`` (its ``cluster.versions()``), not the build's."""

    versions: dict


def simulate(config: dict, heightmap):
    """The shared simulator's result (``simulate.prepared``) for a ``build.simulation_config`` record."""
    from roughness.simulate import prepared

    engine = config.get("engine", "fem")
    fields = {k: v for k, v in config.items() if k not in ("engine", "engine_version")}
    return prepared.simulate(SimConfig(**fields), heightmap, engine=engine)


@functools.cache
def worker_versions() -> dict:
    """``cluster.versions()`` of this process, read once."""
    from roughness.cluster import versions

    return versions()


def simulate_sample(job: Job, config: dict, expected: dict | None = None) -> Outcome:
    """Make the job's texture and simulate it with ``config`` (a ``build.simulation_config`` record), or take the
    job's label if its heightmap digest matches the texture made (``Restored``); failures come back as ``Failed``.
    With ``expected`` (the caller's ``cluster.versions()``), a worker of other versions simulates nothing
    (``OtherVersions``): workers that join a cluster after the build's check are checked too."""
    from .labels import heights_digest
    from .recipe import realise

    record, label = job.texture_record, job.label
    if expected is not None and (mine := worker_versions()) != expected:
        return OtherVersions(record, None, record["pixel_mm"], mine)
    try:  # a failure is recorded with its reason, never stops the run
        hm = realise(record)
    except Exception as err:
        if label is not None and not label.heights:  # the labelled run could not make this texture either
            return Restored(record, None, record["pixel_mm"], label)
        return Failed(record, None, record["pixel_mm"], f"{type(err).__name__}: {err}")
    heights = hm.heights.astype(np.float32)
    if label is not None and label.heights == heights_digest(heights, hm.pixel_mm):
        return Restored(record, heights, hm.pixel_mm, label)
    try:
        result = simulate(config, hm)
    except Exception as err:
        return Failed(record, heights, hm.pixel_mm, f"{type(err).__name__}: {err}")
    return Simulated(record, heights, hm.pixel_mm, result_fields(result), result.fluctuation.astype(np.float32))

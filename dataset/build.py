"""Parallel dataset generation on Dask: workers simulate, this process writes (one writer).

Samples already in the file are skipped, so an interrupted build resumes where it
stopped. With a labels file (``labels``), a sample whose remade heightmap matches its label
takes the stored result instead of the FEM. Each worker process runs one BLAS/OpenMP thread and keeps one prepared
``Simulator`` per configuration, so the block is meshed and assembled once per worker; the threads of a
worker (a cluster's workers may run several) share it, and get the answers of a sequential run bit for bit
(``Simulator`` is thread-safe and history-free).

Ctrl-C, which a terminal sends to every process of its foreground group, stops only the calling
process: the local workers are started ignoring SIGINT, and are closed by it (``Interrupted``).

A cluster of others is reached by ``scheduler`` (its address), ``scheduler_file`` (the file ``dask scheduler
--scheduler-file`` writes) or ``client`` (a connected ``dask.distributed.Client``, left open). Before any work is
submitted, every worker is asked for its roughness and engine versions, which must equal this process's. A task
whose worker dies is run again by the scheduler, up to its ``distributed.scheduler.allowed-failures`` times
(``cluster.ALLOWED_FAILURES`` on the local cluster); the build reports that number and the dashboard's address.
Tasks are submitted as earlier ones finish, IN_FLIGHT_PER_THREAD per worker thread ahead, so a build of 100,000
samples starts at once and the scheduler holds a few hundred tasks, not all of them.
"""
from __future__ import annotations

import contextlib
import functools
import json
import sys
import threading
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

import numpy as np

from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.limits import MAX_DATASET_SAMPLES, check_size
from roughness.core.provenance import Provenance, make_provenance
from roughness.core.version import package_version
from roughness.simulate.config import SimConfig

from .cluster import ClusterChoice
from .schema import DatasetConfig, result_fields, sample_id

if TYPE_CHECKING:  # the texture generators load on first use (the CLI reads this module's defaults)
    from dask.distributed import Client

    from .labels import Label, LabelSet
    from .recipe import Recipe
    from .writer import DatasetWriter

BUILD_CONFIG = SimConfig(fidelity="coarse")  # how the project's training sets are simulated
ENGINES = ("fem", "spectral")
MESH_FIELDS = ("fidelity", "tolerance", "element", "h_contact_mm", "max_rounds")  # not in a spectral configuration
WORKERS = 2  # local Dask worker processes
_SIMULATORS: dict = {}  # per worker process: one prepared Simulator per configuration, shared by its threads
_SIMULATORS_LOCK = threading.Lock()
PREPARATION_PROGRESS_SECONDS = 5.0  # a line on stderr this often while records are made
IN_FLIGHT_PER_THREAD = 8  # tasks submitted ahead per worker thread: workers never wait, the scheduler holds few
MIN_IN_FLIGHT = 64  # (workers that join later still find work)
T = TypeVar("T")


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during ``build``: ``counts`` so far (what was written is kept; the same build resumes)."""

    def __init__(self, counts: dict) -> None:
        super().__init__()
        self.counts = counts

    @property
    def stored(self) -> int:
        """Samples in the dataset now."""
        return sum(self.counts[k] for k in ("already_done", "written", "failed", "restored"))


def simulation_config(config: SimConfig, engine: str = "fem") -> dict:
    """A dataset's ``simulation`` record: the FEM's ``SimConfig.as_dict()``; for the spectral engine the
    fields it uses (no mesh fields) with ``engine`` and ``engine_version``."""
    if engine not in ENGINES:
        raise InputError(f"engine must be one of {', '.join(ENGINES)}, got {engine!r}", parameter="engine")
    if engine == "fem":
        return config.as_dict()
    from roughness.simulate.spectral.engine import ENGINE_VERSION

    fields = {k: v for k, v in config.as_dict().items() if k not in MESH_FIELDS}
    return {**fields, "engine": "spectral", "engine_version": ENGINE_VERSION}


def simulator(config: dict):
    """This process's prepared simulator for a ``simulation_config`` record, made once."""
    key = json.dumps(config, sort_keys=True)
    with _SIMULATORS_LOCK:
        if key not in _SIMULATORS:
            if config.get("engine") == "spectral":
                from roughness.simulate.spectral.engine import SpectralSimulator

                fields = {k: v for k, v in config.items() if k not in ("engine", "engine_version")}
                _SIMULATORS[key] = SpectralSimulator(SimConfig(**fields))
            else:
                from roughness.simulate.model import Simulator

                _SIMULATORS[key] = Simulator(SimConfig(**config))
        return _SIMULATORS[key]


@functools.cache
def worker_versions() -> dict:
    """``cluster.versions()`` of this process, read once."""
    from .cluster import versions

    return versions()


def simulate_record(record: dict, config: dict, label: Label | None = None, expected: dict | None = None) -> dict:
    """Run the FEM for one sample record (on a worker), or take ``label`` if its heightmap digest matches
    the remade texture's (result key "label"); failures come back as data. With ``expected`` (the caller's
    ``cluster.versions()``), a worker of other versions simulates nothing and returns its own ("versions"):
    workers that join a cluster after the build's check are checked too."""
    from .labels import heights_digest
    from .recipe import realise

    out: dict = {"record": record, "heights": None, "pixel_mm": record["pixel_mm"]}
    if expected is not None and (mine := worker_versions()) != expected:
        return {**out, "versions": mine}
    try:  # a failure is recorded with its reason, never stops the run
        hm = realise(record)
        out.update(heights=hm.heights.astype(np.float32), pixel_mm=hm.pixel_mm)
    except Exception as err:
        if label is not None and not label.heights:  # the labelled run could not make this texture either
            return {**out, "label": label}
        return {**out, "error": f"{type(err).__name__}: {err}"}
    if label is not None and label.heights == heights_digest(out["heights"], hm.pixel_mm):
        return {**out, "label": label}
    try:
        result = simulator(config).run(hm)
    except Exception as err:
        return {**out, "error": f"{type(err).__name__}: {err}"}
    return {**out, "fields": result_fields(result), "fluctuation": result.fluctuation.astype(np.float32)}


@dataclass
class Progress:
    """Progress line on stderr: done/total, rate, ETA, failures."""

    total: int
    start: float
    done: int = 0
    failed: int = 0
    restored: int = 0

    def update(self, failed: bool, restored: bool = False) -> None:
        self.done += 1
        self.failed += failed
        self.restored += restored
        elapsed = time.perf_counter() - self.start
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("inf")
        end = "\n" if self.done == self.total or not sys.stderr.isatty() else "\r"
        restored = f"  restored {self.restored}" if self.restored else ""
        print(f"  {self.done}/{self.total} samples  {3600 * rate:.0f}/h  ETA {_duration(eta)}  "
              f"failed {self.failed}{restored}", end=end, file=sys.stderr, flush=True)


def _preparing(items: Iterable[T], total: int, what: str, quiet: bool) -> Iterator[T]:
    """``items``, with a line "done/total what" on stderr every PREPARATION_PROGRESS_SECONDS (unless quiet)."""
    last = time.perf_counter()
    for done, item in enumerate(items):
        if not quiet and time.perf_counter() - last >= PREPARATION_PROGRESS_SECONDS:
            last = time.perf_counter()
            print(f"  {done}/{total} {what}", file=sys.stderr, flush=True)
        yield item


def _duration(seconds: float) -> str:
    if not np.isfinite(seconds):
        return "?"
    m, s = divmod(int(seconds), 60)
    h, m = divmod(m, 60)
    return f"{h}h{m:02d}m" if h else f"{m}m{s:02d}s"


def build_provenance(config: SimConfig, engine: str) -> Provenance:
    """The provenance of a build's labels: its engine and the configuration digest the result cache uses."""
    return make_provenance(engine, config.fidelity if engine == "fem" else "spectral", config.identity(engine))


def build(out: str, n: int, recipe: Recipe, config: SimConfig = BUILD_CONFIG, workers: int = WORKERS,
          scheduler: str | None = None, quiet: bool = False, labels: LabelSet | None = None,
          engine: str = "fem", scheduler_file: str | None = None, client: Client | None = None) -> dict:
    """Simulate the first ``n`` samples of ``recipe`` into ``out`` with ``engine`` (``fem``, or ``spectral``:
    the spectral skin engine, which ignores the mesh fields of ``config``); returns counts.

    ``out`` is created, or added to if it is a dataset of the same configuration (resume).
    ``labels``: results of an earlier build of the same configuration (``labels.load_labels``),
    taken for the samples whose remade heightmap matches ("restored" in the counts).
    ``Interrupted`` (a KeyboardInterrupt) on Ctrl-C, with the counts so far.
    Where it runs: ``workers`` local processes (default), or a running cluster given by at most one of
    ``scheduler`` (address, e.g. ``tcp://host:8786``), ``scheduler_file`` (JSON written by ``dask scheduler
    --scheduler-file``) or ``client`` (a ``dask.distributed.Client``; not closed). Workers whose roughness or
    engine version differs from this process's are refused (``InputError``) before anything is submitted.
    """
    from .recipe import sample_record
    from .writer import DatasetWriter

    n = check_size("samples of one build", integer("n", n, minimum=1), MAX_DATASET_SAMPLES, "n")
    integer("workers", workers, minimum=1)
    cluster = ClusterChoice.of(scheduler, scheduler_file, client)
    records = [sample_record(recipe, i) for i in _preparing(range(n), n, "sample records made", quiet)]
    ids = [sample_id(r) for r in records]
    if len(set(ids)) != len(ids):
        raise InputError("the recipe produced duplicate samples; change its seed or ranges")
    file_config = DatasetConfig(simulation_config(config, engine), json.loads(recipe.to_json()))
    if labels is not None and labels.config != file_config:
        raise InputError(f"the labels were made with another configuration ({labels.config.differences(file_config)})",
                         parameter="labels")
    known = {} if labels is None else labels.labels
    with DatasetWriter(out, file_config, package_version(), build_provenance(config, engine)) as writer:
        pending = [(r, known.get(i)) for r, i in zip(records, ids) if i not in writer.ids]  # (record, label or None)
        counts = {"requested": n, "already_done": n - len(pending), "written": 0, "failed": 0, "restored": 0}
        labelled = sum(label is not None for _, label in pending)
        if not quiet:
            print(f"{out}: {counts['already_done']} of {n} samples present; "
                  f"{f'{labelled} labelled (restored if their textures match), ' if labels is not None else ''}"
                  f"simulating {len(pending) - labelled} on {cluster.describe(workers)}",
                  file=sys.stderr, flush=True)
        if pending:
            try:
                _run(writer, pending, file_config.simulation, workers, cluster, counts, quiet)
            except KeyboardInterrupt:
                if not quiet and sys.stderr.isatty():
                    print(file=sys.stderr)  # end the progress line
                raise Interrupted(counts) from None
    return counts


def _run(writer: DatasetWriter, pending: list[tuple[dict, Label | None]], config: dict, workers: int,
         where: ClusterChoice, counts: dict, quiet: bool) -> None:
    from distributed import KilledWorker

    from .cluster import as_finished, session, versions, worker_threads

    progress = Progress(total=len(pending), start=time.perf_counter())
    with session(where, workers, quiet) as client:
        expected = versions()
        ahead = max(MIN_IN_FLIGHT, IN_FLIGHT_PER_THREAD * sum(worker_threads(client).values()))

        def submit(item: tuple[dict, Label | None]):
            return client.submit(simulate_record, item[0], config, item[1], expected, pure=False)

        with contextlib.closing(as_finished(client, pending, submit, ahead)) as finished:  # the rest cancelled on exit
            for (record, _), future in finished:
                try:
                    res = future.result()
                except KilledWorker as err:  # the sample's workers died more often than the scheduler allows
                    res = {"record": record, "heights": None, "pixel_mm": record["pixel_mm"],
                           "error": f"KilledWorker: the {err.allowed_failures + 1} workers that ran it all died "
                                    "(out of memory, or killed?)"}
                if "versions" in res:
                    raise InputError(f"a Dask worker that joined during the build runs other versions "
                                     f"({res['versions']}) than this process ({expected}); start the workers from the "
                                     "same installation (the samples written so far are kept)")
                if "label" in res:
                    writer.write_labelled(res["record"], res["heights"], res["pixel_mm"], res["label"].values)
                    counts["restored"] += 1
                elif "error" in res:
                    writer.write_failure(res["record"], res["heights"], res["pixel_mm"], res["error"])
                    counts["failed"] += 1
                else:
                    writer.write_result(res["record"], res["heights"], res["pixel_mm"], res["fields"],
                                        res["fluctuation"])
                    counts["written"] += 1
                if not quiet:
                    progress.update("error" in res, "label" in res)

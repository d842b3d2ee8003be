"""Parallel dataset generation on Dask: workers simulate, this process writes (one writer).

Samples already in the file are skipped, so an interrupted build resumes where it
stopped. With a labels file (``labels``), a sample whose remade heightmap matches its label
takes the stored result instead of the FEM. What a worker runs is in ``worker``: one ``Job`` (a sample's texture
record and label) in, one ``Outcome`` out, which this process writes.

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
import json
import sys
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

import numpy as np

from roughness.cluster import ClusterChoice
from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.limits import MAX_DATASET_SAMPLES, check_size
from roughness.core.provenance import Provenance, make_provenance
from roughness.core.version import package_version
from roughness.simulate.config import SimConfig

from .schema import DatasetConfig, sample_id
from .worker import Failed, Job, OtherVersions, Outcome, Restored, Simulated, simulate_sample

if TYPE_CHECKING:  # the texture generators load on first use (the CLI reads this module's defaults)
    from dask.distributed import Client

    from .labels import LabelSet
    from .recipe import Recipe
    from .writer import DatasetWriter

BUILD_CONFIG = SimConfig(fidelity="coarse")  # how the project's training sets are simulated
ENGINES = ("fem", "spectral")
MESH_FIELDS = ("fidelity", "tolerance", "element", "h_contact_mm", "max_rounds")  # not in a spectral configuration
WORKERS = 2  # local Dask worker processes
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
    if engine == "fem":
        return make_provenance(engine, config.fidelity, config.identity())
    from roughness.simulate.spectral.engine import identity

    return make_provenance(engine, "spectral", identity(config))


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
        pending = [Job(r, known.get(i)) for r, i in zip(records, ids) if i not in writer.ids]
        counts = {"requested": n, "already_done": n - len(pending), "written": 0, "failed": 0, "restored": 0}
        labelled = sum(job.label is not None for job in pending)
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


def _run(writer: DatasetWriter, pending: list[Job], config: dict, workers: int, where: ClusterChoice,
         counts: dict, quiet: bool) -> None:
    from distributed import KilledWorker

    from roughness.cluster import as_finished, session, versions, worker_threads

    progress = Progress(total=len(pending), start=time.perf_counter())
    with session(where, workers, quiet) as client:
        expected = versions()
        ahead = max(MIN_IN_FLIGHT, IN_FLIGHT_PER_THREAD * sum(worker_threads(client).values()))

        def submit(job: Job):
            return client.submit(simulate_sample, job, config, expected, pure=False)

        with contextlib.closing(as_finished(client, pending, submit, ahead)) as finished:  # the rest cancelled on exit
            for job, future in finished:
                try:
                    outcome = future.result()
                except KilledWorker as err:  # the sample's workers died more often than the scheduler allows
                    record = job.texture_record
                    outcome = Failed(record, None, record["pixel_mm"],
                                     f"KilledWorker: the {err.allowed_failures + 1} workers that ran it all died "
                                     "(out of memory, or killed?)")
                if isinstance(outcome, OtherVersions):
                    raise InputError(f"a Dask worker that joined during the build runs other versions "
                                     f"({outcome.versions}) than this process ({expected}); start the workers from "
                                     "the same installation (the samples written so far are kept)")
                counts[_store(writer, outcome)] += 1
                if not quiet:
                    progress.update(isinstance(outcome, Failed), isinstance(outcome, Restored))


def _store(writer: DatasetWriter, outcome: Outcome) -> str:
    """Write a worker's ``outcome``; the count it adds to ("written", "failed" or "restored")."""
    if isinstance(outcome, Restored):
        writer.write_labelled(outcome.texture_record, outcome.heights, outcome.pixel_mm, outcome.label.values)
        return "restored"
    if isinstance(outcome, Failed):
        writer.write_failure(outcome.texture_record, outcome.heights, outcome.pixel_mm, outcome.error)
        return "failed"
    if isinstance(outcome, Simulated):
        writer.write_result(outcome.texture_record, outcome.heights, outcome.pixel_mm, outcome.fields,
                            outcome.fluctuation)
        return "written"
    raise TypeError(f"no way to store a {type(outcome).__name__}")

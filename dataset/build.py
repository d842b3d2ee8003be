"""Parallel dataset generation on Dask: workers simulate, this process writes (one writer).

Samples already in the file are skipped, so an interrupted build resumes where it
stopped. With a labels file (``labels``), a sample whose remade heightmap matches its label
takes the stored result instead of the FEM. Each worker process runs one BLAS/OpenMP thread and keeps one prepared
``Simulator`` per configuration, so the block is meshed and assembled once per worker.
"""
from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

import numpy as np

from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.limits import MAX_DATASET_SAMPLES, check_size
from roughness.core.version import package_version
from roughness.simulate.config import SimConfig

from .schema import DatasetConfig, result_fields, sample_id

if TYPE_CHECKING:  # the texture generators load on first use (the CLI reads this module's defaults)
    from .labels import Label, LabelSet
    from .recipe import Recipe
    from .store import DatasetWriter

BUILD_CONFIG = SimConfig(fidelity="coarse")  # how the project's training sets are simulated
WORKERS = 2  # local Dask worker processes
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
_SIMULATORS: dict = {}  # per worker process: one prepared Simulator per configuration
PREPARATION_PROGRESS_SECONDS = 5.0  # a line on stderr this often while records are made and submitted
T = TypeVar("T")


def simulate_record(record: dict, config: dict, label: Label | None = None) -> dict:
    """Run the FEM for one sample record (on a worker), or take ``label`` if its heightmap digest matches
    the remade texture's (result key "label"); failures come back as data."""
    from roughness.simulate.model import Simulator

    from .labels import heights_digest
    from .recipe import realise

    out: dict = {"record": record, "heights": None, "pixel_mm": record["pixel_mm"]}
    try:  # a failure is recorded with its reason, never stops the run
        hm = realise(record)
        out.update(heights=hm.heights.astype(np.float32), pixel_mm=hm.pixel_mm)
    except Exception as err:
        if label is not None and not label.heights:  # the labelled run could not make this texture either
            return {**out, "label": label}
        return {**out, "error": f"{type(err).__name__}: {err}"}
    if label is not None and label.heights == heights_digest(out["heights"], hm.pixel_mm):
        return {**out, "label": label}
    key = json.dumps(config, sort_keys=True)
    if key not in _SIMULATORS:
        _SIMULATORS[key] = Simulator(SimConfig(**config))
    try:
        result = _SIMULATORS[key].run(hm)
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


def build(out: str, n: int, recipe: Recipe, config: SimConfig = BUILD_CONFIG, workers: int = WORKERS,
          scheduler: str | None = None, quiet: bool = False, labels: LabelSet | None = None) -> dict:
    """Simulate the first ``n`` samples of ``recipe`` into ``out``; returns counts.

    ``out`` is created, or added to if it is a dataset of the same configuration (resume).
    ``labels``: results of an earlier build of the same configuration (``labels.load_labels``),
    taken for the samples whose remade heightmap matches ("restored" in the counts).
    """
    from .recipe import sample_record
    from .store import DatasetWriter

    n = check_size("samples of one build", integer("n", n, minimum=1), MAX_DATASET_SAMPLES, "n")
    integer("workers", workers, minimum=1)
    records = [sample_record(recipe, i) for i in _preparing(range(n), n, "sample records made", quiet)]
    ids = [sample_id(r) for r in records]
    if len(set(ids)) != len(ids):
        raise InputError("the recipe produced duplicate samples; change its seed or ranges")
    file_config = DatasetConfig(config.as_dict(), json.loads(recipe.to_json()))
    if labels is not None and labels.config != file_config:
        raise InputError(f"the labels were made with another configuration ({labels.config.differences(file_config)})",
                         parameter="labels")
    known = {} if labels is None else labels.labels
    with DatasetWriter(out, file_config, package_version()) as writer:
        pending = [(r, known.get(i)) for r, i in zip(records, ids) if i not in writer.ids]  # (record, label or None)
        counts = {"requested": n, "already_done": n - len(pending), "written": 0, "failed": 0, "restored": 0}
        labelled = sum(label is not None for _, label in pending)
        if not quiet:
            print(f"{out}: {counts['already_done']} of {n} samples present; "
                  f"{f'{labelled} labelled (restored if their textures match), ' if labels is not None else ''}"
                  f"simulating {len(pending) - labelled} on {scheduler or f'{workers} local workers'}",
                  file=sys.stderr, flush=True)
        if pending:
            _run(writer, pending, config.as_dict(), workers, scheduler, counts, quiet)
    return counts


def _run(writer: DatasetWriter, pending: list[tuple[dict, Label | None]], config: dict, workers: int,
         scheduler: str | None, counts: dict, quiet: bool) -> None:
    from dask.distributed import Client, LocalCluster, as_completed

    for name in THREAD_VARIABLES:  # inherited by the worker processes
        os.environ[name] = "1"
    cluster = None if scheduler else LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                                  dashboard_address=":0")
    client = Client(scheduler or cluster)
    progress = Progress(total=len(pending), start=time.perf_counter())
    try:
        futures = [client.submit(simulate_record, r, config, label, pure=False)
                   for r, label in _preparing(pending, len(pending), "samples submitted to the workers", quiet)]
        for future in as_completed(futures):
            res = future.result()
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
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


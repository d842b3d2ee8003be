"""Many solves of one triplet SDP (cross-validation folds, bootstrap resamples), over processes.

Each worker process compiles the SDP once and solves the tasks it is given; BLAS and OpenMP are
limited to one thread per worker so that ``workers`` processes use ``workers`` cores.
"""
from __future__ import annotations

import os
import signal
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing import get_all_start_methods, get_context

import numpy as np

from .embed import EmbedResult, TripletSDP

THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")


@dataclass(frozen=True)
class SolveTask:
    weights: np.ndarray  # per distinct triplet
    lam: float


_SDP: TripletSDP | None = None


def _start_worker(n: int, triplets: np.ndarray) -> None:
    global _SDP
    from threadpoolctl import threadpool_limits

    # Ctrl-C reaches every process of the terminal's group: the parent handles it (stops the pool, says
    # "interrupted"); a worker that raised KeyboardInterrupt itself would print its own traceback
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threadpool_limits(1)
    _SDP = TripletSDP(n, triplets)


def _solve(task: SolveTask) -> EmbedResult:
    return _SDP.solve(task.weights, task.lam)


def solve_tasks(n: int, triplets: np.ndarray, tasks: Sequence[SolveTask], workers: int = 1,
                progress: Callable[[int, int], None] | None = None) -> list[EmbedResult]:
    """Results of all tasks in order; ``progress(done, total)`` after each one."""
    results: list[EmbedResult | None] = [None] * len(tasks)
    if workers <= 1 or len(tasks) <= 1:
        sdp = TripletSDP(n, triplets)
        for i, task in enumerate(tasks):
            results[i] = sdp.solve(task.weights, task.lam)
            if progress:
                progress(i + 1, len(tasks))
        return results
    pool = ProcessPoolExecutor(min(workers, len(tasks)), mp_context=_context(), initializer=_start_worker,
                               initargs=(n, triplets))
    try:
        with _one_thread_each():  # the workers start as tasks are submitted
            futures = {pool.submit(_solve, task): i for i, task in enumerate(tasks)}
        for done, future in enumerate(as_completed(futures), 1):
            results[futures[future]] = future.result()
            if progress:
                progress(done, len(tasks))
    except BaseException:  # Ctrl-C or a failed solve: stop the workers now, not after the solves under way
        _stop(pool)
        raise
    pool.shutdown()
    return results


def _stop(pool: ProcessPoolExecutor) -> None:
    """Cancel the pool's queued tasks and end its workers at once (they ignore Ctrl-C)."""
    workers = list((getattr(pool, "_processes", None) or {}).values())  # the executor's record (shutdown clears it)
    for process in workers:
        process.terminate()
    pool.shutdown(wait=False, cancel_futures=True)


def _context():
    """fork where available (no re-import of the caller's main script, no __main__ guard needed)."""
    return get_context("fork" if "fork" in get_all_start_methods() else "spawn")


@contextmanager
def _one_thread_each():
    """Worker processes start with one BLAS/OpenMP thread (they inherit the environment)."""
    saved = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    os.environ.update({k: "1" for k in THREAD_VARIABLES})
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def stderr_progress(what: str, quiet: bool = False) -> Callable[[int, int], None] | None:
    """A progress callback printing about 20 lines to stderr: done/total, elapsed and remaining time."""
    if quiet:
        return None
    start = time.monotonic()

    def show(done: int, total: int) -> None:
        if done == total or done % max(1, total // 20) == 0:
            elapsed = time.monotonic() - start
            eta = elapsed / done * (total - done)
            print(f"{what}: {done}/{total} solves, {elapsed:.0f} s elapsed, about {eta:.0f} s left",
                  file=sys.stderr, flush=True)

    return show

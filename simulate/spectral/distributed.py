"""A spectral map's windows solved on Dask, the way the dataset build runs its samples (``dataset.cluster``).

Where: a local cluster of ``workers`` processes, one thread and one BLAS thread each (default), or a running
cluster named by its scheduler's address, its scheduler file or a connected ``Client``. Its workers must run
this process's roughness and engine versions (checked before anything is sent, and by each task, for workers
that join later); a window whose worker dies is solved again, up to the scheduler's allowed failures. Windows
are sent as earlier ones finish, ``IN_FLIGHT_PER_THREAD`` per worker thread ahead, so the scheduler holds a few
windows' heights at a time. The heights travel inside the task (128 MB at the limit), not scattered to a
worker: scattered data dies with its worker, and the window could not be solved again on another.
"""
from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import TYPE_CHECKING

from roughness.core.errors import InputError, SimulationError

from .maps import MapAnswer, MapTask, Runner, solve

if TYPE_CHECKING:
    from roughness.cluster import ClusterChoice

IN_FLIGHT_PER_THREAD = 2  # windows sent ahead per worker thread: none waits, and few heights are held
LARGE_TASK_BYTES = "1GiB"  # a window's task carries its heights: distributed's warning about large graphs is not news


def dask_runner(where: ClusterChoice, workers: int, quiet: bool = False) -> Runner:
    """A ``maps.Runner`` that solves the windows on the Dask cluster ``where`` (``workers``: of a local one)."""

    def run(tasks: list[MapTask], report: Callable[[int, MapAnswer], None]) -> None:
        import dask
        from distributed import KilledWorker

        from roughness.cluster import as_finished, session, versions, worker_threads

        with session(where, workers, quiet) as client:
            expected = versions()

            def submit(item: tuple[int, MapTask]):
                with dask.config.set({"distributed.admin.large-graph-warning-threshold": LARGE_TASK_BYTES}):
                    return client.submit(solve_on_worker, item[1], expected, pure=False)

            ahead = IN_FLIGHT_PER_THREAD * sum(worker_threads(client).values())
            with contextlib.closing(as_finished(client, enumerate(tasks), submit, ahead)) as finished:
                for (index, _), future in finished:
                    try:
                        answer = future.result()
                    except KilledWorker as err:  # its workers died more often than the scheduler allows
                        raise SimulationError(f"window {index + 1} of {len(tasks)} of the map: the "
                                              f"{err.allowed_failures + 1} workers that solved it all died (out of "
                                              "memory, or killed?)") from None
                    report(index, answer)

    return run


def solve_on_worker(task: MapTask, expected: dict) -> MapAnswer:
    """``maps.solve`` on a worker, which must run the ``expected`` versions (``cluster.versions()``)."""
    from roughness.cluster import versions

    mine = versions()
    if mine != expected:
        raise InputError(f"a Dask worker that joined during the map runs other versions ({mine}) than this process "
                         f"({expected}); start the workers from the same installation")
    return solve(task)

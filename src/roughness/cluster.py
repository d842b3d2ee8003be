"""Reaching a running Dask cluster the way Dask users do (or starting a local one), and checking its workers
before work is sent: ``session``, used by the dataset build and the spectral maps' windows.

A cluster is named by its scheduler's address, by the file ``dask scheduler --scheduler-file FILE`` writes,
or by a connected ``dask.distributed.Client``. Its workers must run this process's roughness and engine
versions: a dataset records one configuration and one package version, so samples made by other code
would be mislabelled.
"""
from __future__ import annotations

import contextlib
import json
import logging
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from roughness.core.checks import file_path
from roughness.core.errors import InputError

if TYPE_CHECKING:
    from dask.distributed import Client, Future

T = TypeVar("T")

CONNECT_TIMEOUT_S = 30  # to reach a scheduler and read its scheduler file
BLAS_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")  # one BLAS thread per task thread
ALLOWED_FAILURES = 3  # local cluster: worker deaths a task survives before it is reported as killing workers


@dataclass(frozen=True)
class ClusterChoice:
    """Where a build runs: a local cluster (all None), or one running cluster."""

    scheduler: str | None = None
    scheduler_file: str | None = None
    client: Client | None = None

    @classmethod
    def of(cls, scheduler: str | None, scheduler_file: str | None, client: Client | None) -> ClusterChoice:
        """Checked: at most one of the three; a scheduler file that exists; a Client that is one."""
        given = [name for name, value in (("scheduler", scheduler), ("scheduler_file", scheduler_file),
                                          ("client", client)) if value is not None]
        if len(given) > 1:
            raise InputError(f"give one of {' and '.join(given)}: each names the cluster to use", parameter=given[1])
        if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
            raise InputError(f"scheduler must be a scheduler's address such as tcp://host:8786, got {scheduler!r}",
                             parameter="scheduler")
        if scheduler_file is not None:
            scheduler_address(file_path("scheduler_file", scheduler_file))
        if client is not None:
            from dask.distributed import Client

            if not isinstance(client, Client):
                raise InputError(f"client must be a dask.distributed.Client, got {type(client).__name__}",
                                 parameter="client")
        return cls(scheduler, None if scheduler_file is None else str(scheduler_file), client)

    @property
    def local(self) -> bool:
        return self.scheduler is None and self.scheduler_file is None and self.client is None

    def describe(self, workers: int) -> str:
        """For the build's first line: where the samples are simulated."""
        if self.client is not None:
            return f"the cluster of {self.client.scheduler.address}"
        if self.scheduler_file is not None:
            return f"the cluster of {self.scheduler_file}"
        return self.scheduler or f"{workers} local workers"

    def connect(self) -> Client:
        """A new Client of the running cluster (not for ``client``, which is used as given)."""
        from dask.distributed import Client

        parameter = "scheduler" if self.scheduler is not None else "scheduler_file"
        address = self.scheduler if self.scheduler is not None else scheduler_address(self.scheduler_file)
        try:
            return Client(address, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError, KeyError) as err:  # unreachable, refused, or not a scheduler file
            where = self.scheduler or f"the address in {self.scheduler_file}"
            raise InputError(f"cannot reach a Dask scheduler at {where} ({type(err).__name__}: {err})",
                             parameter=parameter) from None


MAX_SCHEDULER_FILE_BYTES = 1 << 20  # a scheduler file is a few hundred bytes of JSON


def scheduler_address(path: str | os.PathLike) -> str:
    """The scheduler's address in the file ``dask scheduler --scheduler-file FILE`` writes (a JSON object whose
    ``address`` is text such as tcp://host:8786); InputError for ``scheduler_file`` naming what is wrong."""
    path = Path(path)
    written = f"(it is written by `dask scheduler --scheduler-file {path}`)"
    if not path.is_file():
        raise InputError(f"scheduler file {path} does not exist {written}" if not path.exists() else
                         f"scheduler file {path} is not a regular file {written}", parameter="scheduler_file")
    try:
        if path.stat().st_size > MAX_SCHEDULER_FILE_BYTES:
            raise ValueError(f"{path.stat().st_size:,} bytes, above {MAX_SCHEDULER_FILE_BYTES:,}")
        record = json.loads(path.read_text())
    except (OSError, ValueError) as err:  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        raise InputError(f"cannot read {path} as a Dask scheduler file {written}: {err}",
                         parameter="scheduler_file") from None
    address = record.get("address") if isinstance(record, dict) else None
    if not isinstance(address, str) or not address.strip():
        shown = repr(address) if len(repr(address)) <= 60 else repr(address)[:57] + "..."
        raise InputError(f"{path} is not a Dask scheduler file {written}: expected a JSON object whose \"address\" is "
                         f"the scheduler's address such as tcp://host:8786, got {shown}", parameter="scheduler_file")
    return address.strip()


def versions() -> dict[str, Any]:
    """This process's versions that decide a sample's result: the package and the spectral engine's."""
    from roughness.core import version
    from roughness.simulate.spectral import engine

    return {"roughness": version.package_version(), "spectral engine": engine.ENGINE_VERSION}


def worker_report() -> dict[str, Any]:
    """Run on a worker: its ``versions()`` and its BLAS thread variables."""
    return {"versions": versions(), "blas": {name: os.environ.get(name) for name in BLAS_VARIABLES}}


def check_workers(client: Client) -> dict[str, dict[str, Any]]:
    """Each worker's ``worker_report()``; InputError if the cluster has no worker, or one that cannot import
    roughness or runs other versions than this process."""
    try:
        if not client.scheduler_info()["workers"]:
            client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
        found = client.run(worker_report)
    except TimeoutError:
        raise InputError(f"the Dask cluster has no worker (waited {CONNECT_TIMEOUT_S} s); start some with "
                         "dask worker --scheduler-file FILE --nthreads 1") from None
    except Exception as err:  # distributed relays a worker's ImportError as a plain Exception with its text
        raise InputError(f"a Dask worker cannot run roughness ({err}); install the same roughness on every "
                         "worker") from None
    mine = versions()
    other = {worker: report["versions"] for worker, report in found.items() if report["versions"] != mine}
    if other:
        worker, theirs = min(other.items())
        diff = ", ".join(f"{k} {theirs.get(k)!r} (here {mine[k]!r})" for k in mine if theirs.get(k) != mine[k])
        raise InputError(f"{len(other)} of {len(found)} Dask workers run other versions than this process, "
                         f"e.g. {worker}: {diff}; start the workers from the same installation")
    return found


def worker_threads(client: Client) -> dict[str, int]:
    """Each worker's number of task threads."""
    return {w: info["nthreads"] for w, info in client.scheduler_info()["workers"].items()}


def as_finished(client: Client, tasks: Iterable[T], submit: Callable[[T], Future], ahead: int
                ) -> Iterator[tuple[T, Future]]:
    """(task, its finished future) for every task, in the order they finish; ``submit(task)`` is called as earlier
    ones finish, with ``ahead`` tasks (or at least one per worker thread) submitted and unfinished at a time, so the
    scheduler holds few tasks however many there are. The tasks still unfinished when the caller stops (an error,
    a break) are cancelled."""
    from dask.distributed import as_completed

    queue, unfinished = iter(tasks), {}

    def submit_next() -> Future | None:
        for task in queue:  # at most one
            future = submit(task)
            unfinished[future] = task
            return future
        return None

    ahead = max(ahead, sum(worker_threads(client).values()), 1)
    completed = as_completed([f for f in (submit_next() for _ in range(ahead)) if f is not None])
    try:
        for future in completed:
            task = unfinished.pop(future)
            following = submit_next()
            if following is not None:
                completed.add(following)
            yield task, future
    finally:
        if unfinished:
            client.cancel(list(unfinished))


def allowed_failures(client: Client) -> int:
    """How often the scheduler runs a task again after the worker running it died."""
    def read(dask_scheduler) -> int:
        return dask_scheduler.allowed_failures

    return int(client.run_on_scheduler(read))


def announce(client: Client, workers: dict[str, dict[str, Any]]) -> None:
    """Lines on stderr: the dashboard (if the scheduler serves one), the workers, the retries on worker loss,
    and a note if workers may run several BLAS threads per task."""
    link = client.dashboard_link if "dashboard" in client.scheduler_info().get("services", {}) else None
    threads = worker_threads(client)
    print(f"Dask dashboard: {link or 'none (the scheduler serves none)'}", file=sys.stderr, flush=True)
    print(f"Dask workers: {len(workers)} ({sum(threads.values())} threads), roughness "
          f"{versions()['roughness']} on each; a task whose worker dies is run again up to "
          f"{allowed_failures(client)} times", file=sys.stderr, flush=True)
    loose = [w for w, report in workers.items() if not one_blas_thread(report["blas"])]
    if loose:
        found = ", ".join(f"{k}={v}" for k, v in workers[loose[0]]["blas"].items() if v) or "none of them"
        print(f"note: {len(loose)} of {len(workers)} Dask workers may run several BLAS threads per task thread "
              f"(they set {found}), which then compete for the cores; start workers with "
              f"{' '.join(f'{v}=1' for v in BLAS_VARIABLES)} (a nanny sets them: dask worker without --no-nanny)",
              file=sys.stderr, flush=True)


def one_blas_thread(variables: dict[str, str | None]) -> bool:
    """Whether OpenMP, OpenBLAS and MKL each run one thread with these variables (the library's own variable,
    else OMP_NUM_THREADS)."""
    return all((variables.get(name) or variables.get("OMP_NUM_THREADS")) == "1" for name in BLAS_VARIABLES)


@contextlib.contextmanager
def session(where: ClusterChoice, workers: int, quiet: bool) -> Iterator[Client]:
    """A Client of ``where`` whose workers were checked (``check_workers``) and, unless ``quiet``, announced: a
    local cluster of ``workers`` processes (``local_cluster``), closed after; a running cluster's new Client,
    closed after; or the caller's ``client``, left open. On Ctrl-C, distributed's expected warnings about the
    tasks cancelled and the local workers closed mid-task are silenced (a cluster of others is left alone)."""
    from dask.distributed import Client

    cluster = client = None
    try:
        if where.local:
            cluster = local_cluster(workers)
            client = Client(cluster)
        else:
            client = where.client or where.connect()
        found = check_workers(client)
        if not quiet:
            announce(client, found)
        yield client
    except KeyboardInterrupt:
        quiet_distributed()
        if cluster is not None and client is not None:
            with contextlib.suppress(Exception):  # quieter if it works; the interrupt goes on either way
                client.run(quiet_distributed, on_error="ignore")
        raise
    finally:
        if client is not None and client is not where.client:
            client.close()
        if cluster is not None:
            cluster.close()


def quiet_distributed() -> None:
    """Only errors from distributed's loggers in this process."""
    logging.getLogger("distributed").setLevel(logging.ERROR)


def local_cluster(workers: int):
    """A local Dask cluster of ``workers`` processes, one thread and one BLAS thread each (the
    environment, inherited), started ignoring SIGINT (also inherited), so that a Ctrl-C interrupts
    only this process, which closes them; from a thread other than the main one, signals stay as they are."""
    import dask
    from dask.distributed import LocalCluster

    for name in BLAS_VARIABLES:
        os.environ[name] = "1"
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:
        with dask.config.set({"distributed.scheduler.allowed-failures": ALLOWED_FAILURES}):
            return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)

"""Dask the way its users run it: a scheduler and a worker started as docs/how-to/dask.md says (`dask scheduler
--scheduler-file`, `dask worker --scheduler-file --nthreads 1`), `roughness dataset build --scheduler-file`
against them, the worker version check, a `client=` from Python, and threaded workers."""
from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from roughness.cluster import ClusterChoice, versions
from roughness.core.errors import InputError
from roughness.dataset import build, worker
from roughness.dataset.inspection import verify
from roughness.dataset.reader import open_dataset
from roughness.dataset.recipe import Recipe, expand, realise
from roughness.dataset.schema import sample_id
from test_build_distributed import start, wait_for

ROOT = Path(__file__).parents[1]
SEED = 3  # the CLI's default recipe (bump textures) with this seed
N = 3  # spectral: tens of ms per sample
DEADLINE_S = 120  # a bound on every wait; the cluster test takes about 10 s on an idle 2-core machine
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
       "MKL_NUM_THREADS": "1"}


def roughness_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "roughness.cli", *args], check=False, env=ENV,
                          capture_output=True, text=True, timeout=DEADLINE_S)


@contextlib.contextmanager
def by_value():
    """Functions of this module pickled by value for the workers, which cannot import it."""
    import cloudpickle

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        yield
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])


def _die_on_the_next_sample() -> None:
    """Run on a worker: its next sample kills it (as the kernel's OOM killer would); the nanny starts a new one."""
    from roughness.dataset import worker

    def die(*_):
        os._exit(1)

    worker.simulate_sample = die


def _allowing(n: int):
    """A function to run on the scheduler: a task is retried after ``n`` worker deaths."""
    def set_allowed_failures(dask_scheduler) -> None:
        dask_scheduler.allowed_failures = n

    return set_allowed_failures


def _pretend_another_version() -> None:
    """Run on a worker: its roughness now reports another version (as a worker of another installation)."""
    from roughness.core import version

    version.package_version = lambda: "0.0.0-other"


@contextlib.contextmanager
def documented_cluster(folder: Path, workers: int):
    """The scheduler file of a ``dask scheduler`` and ``dask worker --nthreads 1 --nworkers N`` started as
    docs/how-to/dask.md says (logs in ``folder``), once all workers have joined; every process is killed on exit."""
    from distributed import Client

    scheduler_file = folder / "scheduler.json"
    deadline = time.monotonic() + DEADLINE_S
    processes = [start([sys.executable, "-m", "dask", "scheduler", "--scheduler-file", str(scheduler_file),
                        "--host", "127.0.0.1", "--port", "0", "--dashboard-address", "127.0.0.1:0"],
                       ENV, folder / "scheduler.log")]
    try:
        wait_for(lambda: scheduler_file.exists() and scheduler_file.stat().st_size > 0, "the scheduler file",
                 deadline)
        processes.append(start([sys.executable, "-m", "dask", "worker", "--scheduler-file", str(scheduler_file),
                                "--nthreads", "1", "--nworkers", str(workers), "--host", "127.0.0.1",
                                "--no-dashboard"], ENV, folder / "worker.log"))
        with Client(scheduler_file=str(scheduler_file), timeout=30) as client:
            client.wait_for_workers(workers, timeout=DEADLINE_S)
        yield scheduler_file
    finally:
        for proc in processes:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=30)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """The scheduler file of a scheduler and one single-threaded worker, started as docs/how-to/dask.md says."""
    with documented_cluster(tmp_path_factory.mktemp("cluster"), 1) as scheduler_file:
        yield scheduler_file


def test_a_build_on_a_cluster_started_the_documented_way(cluster, tmp_path):
    out = tmp_path / "d.h5"
    run = roughness_cli("dataset", "build", "--engine", "spectral", "--n", str(N), "--seed", str(SEED),
                        "--out", str(out), "--scheduler-file", str(cluster))
    assert run.returncode == 0, run.stderr
    counts = json.loads(run.stdout)
    assert counts.pop("provenance")["engine"] == "spectral"
    assert counts == {"requested": N, "already_done": 0, "written": N, "failed": 0, "restored": 0}
    address = json.loads(cluster.read_text())["address"]
    assert f"simulating {N} on the cluster of {cluster}" in run.stderr
    dashboard = [line for line in run.stderr.splitlines() if line.startswith("Dask dashboard: ")]
    assert len(dashboard) == 1 and dashboard[0].startswith("Dask dashboard: http://127.0.0.1:"), run.stderr
    assert dashboard[0].endswith("/status")
    assert "Dask workers: 1 (1 threads)" in run.stderr and "run again up to 3 times" in run.stderr
    assert "note:" not in run.stderr  # the documented worker runs one BLAS thread
    with open_dataset(out) as ds:
        assert sorted(ds.ids) == sorted(sample_id(r) for r in expand(Recipe(seed=SEED), N))
        assert (ds.table()["status"] == "ok").all() and np.isfinite(ds.table()["V"]).all()
    assert verify(out) == []
    # the same build by address resumes: nothing left to simulate
    again = roughness_cli("dataset", "build", "--engine", "spectral", "--n", str(N), "--seed", str(SEED),
                          "--out", str(out), "--scheduler", address, "--quiet")
    assert again.returncode == 0 and json.loads(again.stdout)["already_done"] == N, again.stderr


def test_a_client_from_python_is_used_and_left_open(cluster, tmp_path):
    from distributed import Client

    out = tmp_path / "c.h5"
    with Client(scheduler_file=str(cluster), timeout=30) as client:
        counts = build.build(str(out), N, Recipe(seed=SEED), engine="spectral", client=client, quiet=True)
        assert counts["written"] == N
        assert client.status == "running"  # the caller's client is not closed by the build
        with pytest.raises(InputError, match="give one of scheduler and client"):
            build.build(str(out), N, Recipe(seed=SEED), engine="spectral", client=client, scheduler="tcp://x:1")


def test_a_sample_whose_worker_dies_runs_again_and_one_that_kills_every_worker_is_recorded(cluster, tmp_path):
    """The worker dies on its next sample and its nanny restarts it: with the scheduler's default retries the
    build completes; with none, the samples on the dead worker are recorded as failed (KilledWorker) and the
    build goes on."""
    from distributed import Client

    with by_value(), Client(scheduler_file=str(cluster), timeout=30) as client:
        before = set(client.run(os.getpid).values())
        client.run(_die_on_the_next_sample)
        counts = build.build(str(tmp_path / "retried.h5"), N, Recipe(seed=SEED), engine="spectral", client=client,
                             quiet=True)
        assert counts["written"] == N and counts["failed"] == 0
        assert not before & set(client.run(os.getpid).values())  # the worker that ran the first sample died
        client.wait_for_workers(1, timeout=DEADLINE_S)
        client.run(_die_on_the_next_sample)
        client.run_on_scheduler(_allowing(0))
        try:
            counts = build.build(str(tmp_path / "killed.h5"), N, Recipe(seed=SEED), engine="spectral",
                                 client=client, quiet=True)
        finally:
            client.run_on_scheduler(_allowing(3))
    # the scheduler sends a worker one task more than its threads (worker-saturation): one or two die with it
    assert 1 <= counts["failed"] <= 2 and counts["written"] + counts["failed"] == N
    with open_dataset(tmp_path / "killed.h5") as ds:
        errors = [error for _, _, error in ds.failures()]
    assert len(errors) == counts["failed"]
    assert all(e == "KilledWorker: the 1 workers that ran it all died (out of memory, or killed?)" for e in errors)


def test_a_worker_of_other_versions_simulates_nothing():
    """Each task checks its worker (workers may join after the build's check)."""
    record = expand(Recipe(seed=SEED), 1)[0]
    config = build.simulation_config(build.BUILD_CONFIG, "spectral")
    res = worker.simulate_sample(worker.Job(record), config, {**versions(), "roughness": "0.0.0-other"})
    assert isinstance(res, worker.OtherVersions) and res.versions == versions()
    assert isinstance(worker.simulate_sample(worker.Job(record), config, versions()), worker.Simulated)


def test_workers_of_another_version_are_refused_before_any_work(cluster, tmp_path):
    """Last in this module: it changes the worker's version for the rest of its life."""
    from distributed import Client

    out = tmp_path / "v.h5"
    with by_value(), Client(scheduler_file=str(cluster), timeout=30) as client:
        client.run(_pretend_another_version)
    run = roughness_cli("dataset", "build", "--engine", "spectral", "--n", str(N), "--seed", str(SEED),
                        "--out", str(out), "--scheduler-file", str(cluster))
    assert run.returncode == 2, run.stderr
    here = versions()["roughness"]
    assert ("1 of 1 Dask workers run other versions than this process" in run.stderr
            and f"roughness '0.0.0-other' (here '{here}')" in run.stderr), run.stderr
    assert "Traceback" not in run.stderr
    assert list(tmp_path.iterdir()) == []  # nothing simulated, no dataset file left behind


@pytest.mark.parametrize("options, message", [
    (["--scheduler-file", "missing.json"], ("error: scheduler file missing.json does not exist (it is written by "
                                           "`dask scheduler --scheduler-file missing.json`)")),
    (["--scheduler", "tcp://127.0.0.1:1"], "--scheduler: cannot reach a Dask scheduler at tcp://127.0.0.1:1"),
    (["--scheduler", "tcp://127.0.0.1:1", "--scheduler-file", "s.json"],
     "argument --scheduler-file: not allowed with argument --scheduler"),
])
def test_a_cluster_that_cannot_be_used_is_a_clear_input_error(tmp_path, options, message, monkeypatch, capsys):
    from roughness import cluster as cluster_module

    monkeypatch.setattr(cluster_module, "CONNECT_TIMEOUT_S", 2)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.json").write_text("{}")
    from roughness.cli import main

    code = main(["dataset", "build", "--engine", "spectral", "--n", "2", "--out", "x.h5", *options])
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err, err


def test_cluster_choice_checks():
    assert ClusterChoice.of(None, None, None).local
    with pytest.raises(InputError, match="client must be a dask.distributed.Client"):
        ClusterChoice.of(None, None, "tcp://host:8786")


def test_a_spectral_build_on_a_worker_with_two_threads_equals_the_sequential_answers(tmp_path, monkeypatch):
    """The issue's drift (threads sharing one simulator): a worker with two threads builds, twice, the values
    one simulator gives sample after sample, bit for bit."""
    from dask.distributed import LocalCluster

    from roughness.simulate import prepared

    recipe = Recipe(name="threads", seed=7, families={"bumps": 1.0, "grating": 1.0, "dots": 1.0})
    config = build.BUILD_CONFIG
    records = expand(recipe, 8)
    from roughness.simulate.spectral.engine import SpectralSimulator

    sim = SpectralSimulator(config)
    sequential = [sim.run(realise(r)) for r in records]
    for attempt in range(2):
        monkeypatch.setattr(prepared, "_SPECTRAL", {})
        out = tmp_path / f"t{attempt}.h5"
        with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0") as local:
            counts = build.build(str(out), len(records), recipe, config, scheduler=local.scheduler_address,
                                 quiet=True, engine="spectral")
        assert counts["written"] == len(records)
        with open_dataset(out) as data:
            stored = dict(zip(data.table()["id"], data.table()["V"]))
            fluctuations = [data.fluctuation(sample_id(r)) for r in records]
        assert [stored[sample_id(r)] for r in records] == [r.roughness for r in sequential]
        for got, expected in zip(fluctuations, sequential):
            assert np.array_equal(got, expected.fluctuation.astype(np.float32))


def test_workers_that_may_run_several_blas_threads_are_noted(tmp_path, monkeypatch, capfd):
    """An in-process worker sees this process's environment: OMP_NUM_THREADS=4 and no OpenBLAS variable."""
    from dask.distributed import LocalCluster

    from roughness.cluster import one_blas_thread

    assert one_blas_thread({"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": None, "MKL_NUM_THREADS": None})
    assert not one_blas_thread({"OMP_NUM_THREADS": None, "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"})
    assert not one_blas_thread({"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "2", "MKL_NUM_THREADS": None})
    monkeypatch.setenv("OMP_NUM_THREADS", "4")
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    monkeypatch.delenv("MKL_NUM_THREADS", raising=False)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0") as local:
        counts = build.build(str(tmp_path / "b.h5"), 1, Recipe(seed=SEED), engine="spectral",
                             scheduler=local.scheduler_address)
    assert counts["written"] == 1
    err = capfd.readouterr().err
    assert ("note: 1 of 1 Dask workers may run several BLAS threads per task thread (they set OMP_NUM_THREADS=4)"
            in err), err
    assert "Dask dashboard: http://" in err

"""Dataset generation on a real distributed Dask deployment: a scheduler and two worker processes
started with the `dask` command line of the running interpreter (python -m dask) on the loopback
interface, one worker killed mid-build."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.dataset.inspection import verify
from roughness.dataset.reader import open_dataset
from roughness.dataset.recipe import Recipe, expand
from roughness.dataset.schema import sample_id

ROOT = Path(__file__).parents[1]
N = 4
SEED = 3  # the CLI's default recipe (bump textures) with this seed
DEADLINE_S = 240  # a bound on every wait; the test takes well under a minute on an idle 2-core machine


def start(args: list[str], env: dict, log: Path) -> subprocess.Popen:
    """A process in its own session (killed as a group), its output in ``log``."""
    with open(log, "wb") as out:
        return subprocess.Popen(args, env=env, stdout=out, stderr=subprocess.STDOUT, start_new_session=True)


def wait_for(condition, what: str, deadline: float) -> None:
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.2)


def stored(path: Path) -> list[str]:
    try:
        with open_dataset(path) as ds:
            return ds.ids
    except InputError:  # not created yet
        return []


def test_build_survives_a_killed_worker(tmp_path):
    from distributed import Client

    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    deadline = time.monotonic() + DEADLINE_S
    scheduler_file, out = tmp_path / "scheduler.json", tmp_path / "d.h5"
    processes: list[subprocess.Popen] = []
    client = None
    try:
        processes.append(start([sys.executable, "-m", "dask", "scheduler", "--host", "127.0.0.1", "--port", "0",
                                "--no-dashboard", "--scheduler-file", str(scheduler_file)], env,
                               tmp_path / "scheduler.log"))
        wait_for(lambda: scheduler_file.exists() and scheduler_file.stat().st_size > 0, "the scheduler file", deadline)
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        workers = {f"w{i}": start([sys.executable, "-m", "dask", "worker", address, "--nthreads", "1", "--no-nanny",
                                   "--no-dashboard", "--host", "127.0.0.1", "--name", f"w{i}"], env,
                                  tmp_path / f"w{i}.log")
                   for i in range(2)}
        processes += workers.values()
        client = Client(address, timeout=30)
        wait_for(lambda: len(client.scheduler_info()["workers"]) == 2, "two workers", deadline)

        build = start([sys.executable, "-m", "roughness.cli", "dataset", "build", "--scheduler", address,
                       "--out", str(out), "--n", str(N), "--fidelity", "coarse", "--seed", str(SEED), "--quiet"],
                      env, tmp_path / "build.log")
        processes.append(build)
        wait_for(lambda: len(stored(out)) >= 1 or build.poll() is not None, "the first sample", deadline)
        busy = {client.scheduler_info()["workers"][w]["name"] for w, tasks in client.processing().items() if tasks}
        assert build.poll() is None and busy, "the kill should land mid-build, on a worker with a task"
        victim = min(busy)
        os.killpg(workers[victim].pid, signal.SIGKILL)
        assert workers[victim].wait(timeout=30) == -signal.SIGKILL

        wait_for(lambda: build.poll() is not None, "the build", deadline)
        log = (tmp_path / "build.log").read_text()
        assert build.returncode == 0, log
        assert [w["name"] for w in client.scheduler_info()["workers"].values()] == sorted(set(workers) - {victim})
        assert json.loads(log.splitlines()[-1])["requested"] == N
        expected = sorted(sample_id(r) for r in expand(Recipe(seed=SEED), N))
        assert stored(out) == expected  # exactly the N samples, each once
        assert verify(out) == []
        with open_dataset(out) as ds:
            assert (ds.table()["status"] == "ok").all() and np.isfinite(ds.table()["V"]).all()
    finally:
        if client is not None:
            client.close()
        for proc in processes:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=30)

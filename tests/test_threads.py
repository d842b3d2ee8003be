"""Determinism under threads: threads sharing one prepared FEM simulator (as the threads of a Dask worker
share the build's) give the sequential answers bit for bit, in every run, whatever was solved before."""
from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from roughness.dataset import build, worker
from roughness.dataset.recipe import Recipe, expand, realise
from roughness.simulate.config import SimConfig
from roughness.simulate.model import Simulator

# A 6 mm block (as tests/test_build.py's) at coarse fidelity: about 0.2 s per texture with its error estimate.
CONFIG = SimConfig(width_mm=6.0, window_mm=4.0, pairs=2000, force_n=3.6, fidelity="coarse")
RECIPE = Recipe(name="threads", seed=7, families={"bumps": 1.0, "grating": 1.0, "dots": 1.0}, size_mm=7.0)
THREADS = 4
REPEATS = 2  # each texture is submitted this often, so that threads solve the same and different textures at once


@pytest.fixture(scope="module")
def records():
    return expand(RECIPE, 3)


@pytest.fixture(scope="module")
def sequential(records):
    """V and the strain fluctuation of each texture, one after the other on one simulator."""
    sim = Simulator(CONFIG)
    return [(r.roughness, r.fluctuation) for r in (sim.run(realise(record)) for record in records)]


def threaded(records) -> list[tuple[float, np.ndarray]]:
    """The same textures from THREADS threads sharing a new simulator, every texture REPEATS times."""
    sim = Simulator(CONFIG)
    heightmaps = [realise(record) for record in records] * REPEATS
    with ThreadPoolExecutor(THREADS) as pool:
        results = list(pool.map(sim.run, heightmaps))
    return [(r.roughness, r.fluctuation) for r in results]


def test_threads_sharing_a_simulator_give_the_sequential_answers_bit_for_bit(records, sequential):
    first, second = threaded(records), threaded(records)
    for run in (first, second):
        for (v, fluctuation), (v_seq, fluctuation_seq) in zip(run, sequential * REPEATS):
            assert v == v_seq
            assert np.array_equal(fluctuation, fluctuation_seq)
    assert [v for v, _ in first] == [v for v, _ in second]


def test_an_answer_does_not_depend_on_what_was_solved_before(records, sequential):
    """The reverse order on one simulator: each texture's solve starts from the same solver state."""
    sim = Simulator(CONFIG)
    backwards = [sim.run(realise(record)).roughness for record in reversed(records)]
    assert backwards[::-1] == [v for v, _ in sequential]


def test_the_build_workers_function_from_threads_equals_the_sequential_build(records, sequential, monkeypatch):
    """``simulate_sample``, what the Dask workers run, from threads sharing the process's simulator."""
    from roughness.simulate import prepared

    monkeypatch.setattr(prepared, "SHARED", Simulator())
    config = CONFIG.as_dict()
    with ThreadPoolExecutor(THREADS) as pool:
        results = list(pool.map(lambda record: worker.simulate_sample(worker.Job(record), config),
                                records * REPEATS))
    alone = Simulator(CONFIG)
    alone.run(realise(records[0]))
    assert list(prepared.SHARED._blocks) == list(alone._blocks)  # the blocks of one run, shared by the threads
    for res, (v, fluctuation) in zip(results, sequential * REPEATS):
        assert isinstance(res, worker.Simulated)
        assert res.fields["roughness"] == v
        assert np.array_equal(res.fluctuation, fluctuation.astype(np.float32))


def test_a_dask_worker_with_several_threads_builds_the_sequential_dataset(records, sequential, tmp_path, monkeypatch):
    """``build`` on a cluster whose one worker runs THREADS threads (in this process, sharing its simulators)."""
    from dask.distributed import LocalCluster

    from roughness.dataset.reader import open_dataset
    from roughness.dataset.schema import sample_id
    from roughness.simulate import prepared

    monkeypatch.setattr(prepared, "SHARED", Simulator())
    out = tmp_path / "threads.h5"
    with LocalCluster(n_workers=1, threads_per_worker=THREADS, processes=False, dashboard_address=":0") as cluster:
        counts = build.build(str(out), len(records), RECIPE, CONFIG, scheduler=cluster.scheduler_address,
                             quiet=True)
    assert counts["written"] == len(records)
    with open_dataset(out) as data:
        table = data.table()
        stored = dict(zip(table["id"], table["V"]))
        fluctuations = [data.fluctuation(sample_id(record)) for record in records]
    assert [stored[sample_id(record)] for record in records] == [v for v, _ in sequential]
    for fluctuation, (_, expected) in zip(fluctuations, sequential):
        assert np.array_equal(fluctuation, expected.astype(np.float32))


def test_threads_sharing_a_fem_engine_prepare_it_once_and_give_the_sequential_answers(records, sequential,
                                                                                      monkeypatch):
    """The FEM engine of ``predict`` and ``compare``, prepared by whichever thread comes first."""
    from roughness.engines import FemEngine
    from roughness.simulate import prepared

    monkeypatch.setattr(prepared, "SHARED", Simulator())
    engine = FemEngine.of("coarse", CONFIG.as_dict())
    with ThreadPoolExecutor(THREADS) as pool:
        values = list(pool.map(lambda record: engine.measure(realise(record)).value, records * REPEATS))
    assert values == [v for v, _ in sequential] * REPEATS
    assert engine.setup_seconds > 0 and len(prepared.SHARED._blocks) == 2  # the level and its coarser one

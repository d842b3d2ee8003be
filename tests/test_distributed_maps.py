"""Spectral maps larger than one solve: overlapping windows stitched (simulate/spectral/windows.py), run here or
on Dask as the dataset build runs (simulate/spectral/distributed.py), from Python (``roughness.predict_map``)
and ``roughness predict --map``. MAX_MAP_PIXELS is lowered so that small maps take several windows."""
from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from roughness.core.errors import InputError
from roughness.core.limits import Limit
from roughness.simulate.config import SimConfig
from roughness.simulate.spectral import maps
from roughness.simulate.spectral.windows import plan_windows
from test_dask_cluster import documented_cluster

ROOT = Path(__file__).parents[1]
DEADLINE_S = 120  # a bound on every wait; the cluster test takes a few seconds on an idle 2-core machine
WINDOW = Limit(300 * 300, "MAX_MAP_PIXELS")  # 30 mm windows of a 34 mm map at 0.1 mm: 2 x 2 of them
PERIODIC_WINDOW = Limit(330 * 330, "MAX_MAP_PIXELS")  # a periodic map's windows have guard bands on every side: 4 x 4
# studies/results/map_windows.md: 7.5 mm beyond the sampled strain (the guard band) and further from a window's
# edge, V differs from the whole map's by at most 3.0e-4 (fBm rms 0.15 mm, whose long wavelengths reach the
# map's size; printed bumps: 2e-6). Here up to four edges cut a window: three times the largest one edge made.
WINDOWED_RTOL = 1e-3


def _die_on_the_next_window() -> None:
    """Run on a worker: its next window kills it (as the kernel's OOM killer would); the nanny starts a new one."""
    from roughness.simulate.spectral import distributed

    def die(*_):
        os._exit(1)

    distributed.solve = die


@pytest.fixture(scope="module")
def rough():
    """A 34 mm fBm map at 0.1 mm (periodic, as spectral synthesis makes it): in full contact at 10 N."""
    from roughness.dataset.fractal import fbm_surface

    return fbm_surface(34, 0.1, rms_mm=0.15, seed=2)


@pytest.fixture()
def small_windows(monkeypatch):
    """MAX_MAP_PIXELS lowered, and the shapes of the grids solved recorded."""
    shapes = []
    real = maps.modes

    def recording(key):
        shapes.append(key.shape)
        return real(key)

    monkeypatch.setattr(maps, "MAX_MAP_PIXELS", WINDOW)
    monkeypatch.setattr(maps, "modes", recording)
    return shapes


@pytest.mark.parametrize("shape, tile", [((400, 400), False), ((400, 400), True), ((120, 900), False),
                                         ((700, 130), True), ((333, 517), False)])
def test_windows_answer_every_position_once_from_inside_their_guard_bands(shape, tile):
    from roughness.simulate.footprints import centres

    pixel, step, margin = 0.1, 0.7, maps.guard_mm(SimConfig(), 0.1)
    ny, nx = shape
    xs, ys = centres(nx * pixel, 10.0, step, tile), centres(ny * pixel, 10.0, step, tile)
    windows = plan_windows(shape, pixel, xs, ys, margin, WINDOW, tile)
    count = np.zeros((len(ys), len(xs)), int)
    for w in windows:
        assert w.rows.size * w.cols.size <= WINDOW
        count[w.rows.first:w.rows.stop, w.cols.first:w.cols.stop] += 1
        for span, at, n in ((w.rows, ys, ny), (w.cols, xs, nx)):
            kept = at[span.first:span.stop]
            low, high = span.start * pixel, (span.start + span.size) * pixel
            if tile or span.start > 0:  # a window's edge that cuts the map
                assert kept.min() - low >= margin - 1e-9
            if tile or span.start + span.size < n:
                assert high - kept.max() >= margin - 1e-9
            if not tile:
                assert 0 <= span.start and span.start + span.size <= n
    assert (count == 1).all()


def test_a_map_larger_than_one_solve_equals_the_one_solve_within_the_guard_bands_error(rough, small_windows):
    """In full contact: each window's answers are the whole map's within the error the guard band leaves,
    and no solve is larger than MAX_MAP_PIXELS."""
    for tile, limit in ((False, WINDOW), (True, PERIODIC_WINDOW)):
        with pytest.MonkeyPatch.context() as undo:
            undo.setattr(maps, "MAX_MAP_PIXELS", Limit(10**9, "MAX_MAP_PIXELS"))
            whole, notes = maps.spectral_map(rough, step_mm=2.0, tile=tile)
        assert notes == [] and small_windows == [rough.shape]
        small_windows.clear()
        with pytest.MonkeyPatch.context() as undo:
            undo.setattr(maps, "MAX_MAP_PIXELS", limit)
            windowed, notes = maps.spectral_map(rough, step_mm=2.0, tile=tile)
        assert small_windows == [(math.isqrt(limit),) * 2] * (16 if tile else 4)
        assert len(notes) == 1 and f"in {len(small_windows)} overlapping windows" in notes[0], notes
        np.testing.assert_allclose(windowed.roughness, whole.roughness, rtol=WINDOWED_RTOL, atol=0)
        assert not np.array_equal(windowed.roughness, whole.roughness)  # the windows were solved apart
        small_windows.clear()


def test_partial_contact_in_windows_says_the_load_is_shared_per_window(small_windows):
    from roughness.dataset.fractal import fbm_surface

    rough = fbm_surface(34, 0.1, rms_mm=1.0, hurst=0.5, cutoff_mm=1.0, seed=4)  # tall: it lifts off in places
    windowed, notes = maps.spectral_map(rough, step_mm=6.0)
    assert np.isfinite(windowed.roughness).all()
    [_, contact] = notes
    assert "partial contact" in contact and "the load is shared over each window" in contact, notes


def test_the_windows_of_a_map_on_a_two_worker_cluster_equal_the_map_solved_here(rough, small_windows, tmp_path,
                                                                                 capsys, monkeypatch):
    """A scheduler and two single-threaded workers started as docs/how-to/dask.md says; the map from Python (client=),
    again after the workers die on their next window (solved again by the restarted ones), and from the CLI
    (--scheduler-file) equals the windows solved one after the other here, bit for bit."""
    from distributed import Client

    import roughness
    from roughness.cli import main

    here = roughness.predict_map(rough, "spectral", step_mm=2.0, workers=1)
    assert len(small_windows) == 4
    with documented_cluster(tmp_path, 2) as scheduler_file:
        with Client(scheduler_file=str(scheduler_file), timeout=30) as client:
            there = roughness.predict_map(rough, "spectral", step_mm=2.0, client=client)
            assert client.status == "running"  # the caller's client is left open
            import cloudpickle

            cloudpickle.register_pickle_by_value(sys.modules[__name__])  # the workers cannot import this module
            try:
                before = set(client.run(os.getpid).values())
                client.run(_die_on_the_next_window)
            finally:
                cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
            retried = roughness.predict_map(rough, "spectral", step_mm=2.0, client=client)
            assert before - set(client.run(os.getpid).values())  # a worker died and its window was solved again
            np.testing.assert_array_equal(retried.map.roughness, here.map.roughness)
            client.wait_for_workers(2, timeout=DEADLINE_S)
        np.testing.assert_array_equal(there.map.roughness, here.map.roughness)
        assert there.notes == here.notes and there.provenance == here.provenance
        monkeypatch.chdir(tmp_path)
        np.save("rough.npy", np.asarray(rough.heights))
        code = main(["predict", "rough.npy", "--pixel-mm", "0.1", "--engine", "spectral", "--map", "v.npy",
                     "--step-mm", "2", "--scheduler-file", str(scheduler_file), "--json"])
        out, err = capsys.readouterr()
        assert code == 0, err
        np.testing.assert_array_equal(np.load("v.npy"), here.map.roughness)
        summary = json.loads(out)
        assert summary["notes"] == here.notes and summary["positions"] == here.map.roughness.size
        assert "Dask workers: 2 (2 threads)" in err and "Dask dashboard: http://127.0.0.1:" in err


def test_a_worker_of_other_versions_solves_no_window(rough):
    from roughness.cluster import versions
    from roughness.simulate.spectral.distributed import solve_on_worker

    task = maps.MapTask(np.asarray(rough.heights), rough.pixel_mm, np.array([20.0]), np.array([20.0]), False,
                        SimConfig())
    with pytest.raises(InputError, match="runs other versions"):
        solve_on_worker(task, {**versions(), "roughness": "0.0.0-other"})
    assert solve_on_worker(task, versions()).sums.shape == (1, 1)


@pytest.mark.parametrize("options, message", [
    (["--workers", "2"], "--workers: Dask solves the windows of a spectral --map; without --map there are none"),
    (["--map", "v.npy", "--scheduler", "tcp://127.0.0.1:1"],
     "--scheduler: only a spectral map's windows run on Dask; the surrogate's map runs in this process"),
    (["--map", "v.npy", "--engine", "spectral", "--scheduler-file", "missing.json"],
     "scheduler file missing.json does not exist (it is written by `dask scheduler --scheduler-file missing.json`)"),
    (["--map", "v.npy", "--engine", "spectral", "--scheduler", "tcp://127.0.0.1:1", "--scheduler-file", "s.json"],
     "argument --scheduler-file: not allowed with argument --scheduler"),
    (["--map", "v.npy", "--engine", "spectral", "--workers", "0"], "argument --workers: expected an integer >= 1"),
    (["--map", "s.json", "--engine", "spectral", "--scheduler-file", "s.json"], "s.json"),
])
def test_bad_cluster_options_of_a_map_exit_2(tmp_path, monkeypatch, capsys, options, message):
    from roughness.cli import main

    monkeypatch.chdir(tmp_path)
    np.save("map.npy", np.zeros((240, 240)))
    (tmp_path / "s.json").write_text("{}")
    code = main(["predict", "map.npy", "--pixel-mm", "0.1", "--engine", "surrogate", *options])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.npy", "s.json"]


def test_predict_map_checks_its_arguments(rough):
    import roughness

    with pytest.raises(InputError, match="a map's engine is one of") as err:
        roughness.predict_map(rough, "fem")
    assert err.value.parameter == "engine"
    with pytest.raises(InputError, match="give one of scheduler and client"):
        roughness.predict_map(rough, "spectral", scheduler="tcp://127.0.0.1:1", client=object())
    with pytest.raises(InputError, match="client must be a dask.distributed.Client"):
        roughness.predict_map(rough, "spectral", client="tcp://127.0.0.1:1")
    with pytest.raises(InputError, match="pixel_mm"):
        roughness.predict_map(np.zeros((200, 200)), "spectral")


def test_windows_too_narrow_for_their_guard_bands_are_a_clear_input_error():
    """At the finest pixel the footprint allows (1,024 across), a 2048-pixel window is 20 mm: less than its two
    guard bands of 11.5 mm."""
    from roughness.simulate.footprints import centres

    pixel = 10.0 / 1024
    xs = centres(6000 * pixel, 10.0, 1.0, False)
    with pytest.raises(InputError, match="answers no footprint position beyond its guard bands") as err:
        plan_windows((6000, 6000), pixel, xs, xs, maps.guard_mm(SimConfig(), pixel), 2048 * 2048, False)
    assert err.value.parameter == "pixel_mm"

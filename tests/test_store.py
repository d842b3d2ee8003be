"""The HDF5 training-set store: round trips, idempotent appends, checks, and crash safety."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pytest

from roughness.core.errors import InputError
from roughness.dataset import store
from roughness.dataset.store import (
    DatasetWriter,
    info,
    journal_path,
    open_dataset,
    result_fields,
    sample_id,
    verify,
)

ROOT = Path(__file__).parents[1]
CONFIG = {"force_n": 10.0, "fidelity": "coarse", "h_contact_mm": None, "seed": 0}
N = 12


def recipe(i: int) -> dict:
    return {"family": "fbm" if i % 3 else "woven", "params": {"hurst": 0.5 + i / 100}, "seed": i,
            "perturbation": {"tilt_deg": 0.0}}


def fields(i: int) -> dict:
    return {"roughness": 0.1 + i / 100, "roughness_stderr": 0.002, "contact_fraction": 0.5 + i / 100,
            "indentation_mm": 0.6, "converged": i % 2 == 0, "iterations": 3 + i, "unresolved_nodes": i % 2,
            "cycled": False, "seconds": 1.5, "contact_history": [10, 12, 12], "grid_axis_mm": np.linspace(-1, 1, 40)}


def sample(i: int) -> tuple:
    """write_result arguments of test sample ``i``: 40x40 maps (ok samples' heights differ in shape)."""
    rng = np.random.default_rng(i)
    return recipe(i), rng.random((40, 40 + i % 2)), 0.05, fields(i), rng.normal(size=(40, 40))


def fill(path: Path, indices) -> list[bool]:
    with DatasetWriter(path, CONFIG, "test") as writer:
        return [writer.write_result(*sample(i)) for i in indices]


def test_round_trip_of_results_and_failures(tmp_path):
    path = tmp_path / "d.h5"
    with DatasetWriter(path, CONFIG, "1.2.3") as writer:
        for i in range(3):
            assert writer.write_result(*sample(i))
        bad = {"family": "cellular", "seed": 7, "params": {}}
        assert writer.write_failure(bad, np.ones((40, 40)), 0.05, "contact did not converge")
        assert writer.write_failure({"family": "woven", "seed": 8}, None, 0.05, "generator raised")
    assert not journal_path(path).exists()
    with open_dataset(path) as ds:
        assert len(ds) == 5 and ds.ids == sorted(ds.ids)
        assert sorted(ds.ids) == sorted([sample_id(recipe(i)) for i in range(3)]
                                        + [sample_id(bad), sample_id({"family": "woven", "seed": 8})])
        assert recipe(1) in ds.recipes and bad in ds.recipes
        assert ds.config == CONFIG and ds.attrs["roughness_version"] == "1.2.3" and ds.attrs["schema_version"] == 1
        rec, heights, pixel, values, strain = sample(1)
        sid = sample_id(rec)
        hm = ds.heightmap(sid)
        assert hm.pixel_mm == pixel and np.array_equal(hm.heights, heights.astype(np.float32))
        assert np.array_equal(ds.fluctuation(sid), strain.astype(np.float32))
        table = ds.table()
        row = list(table["id"]).index(sid)
        assert table["V"][row] == values["roughness"] and table["family"][row] == "fbm"
        assert table["iterations"][row] == 4 and not table["converged"][row] and table["status"][row] == "ok"
        failed = table["status"] == "failed"
        assert failed.sum() == 2 and np.isnan(table["V"][failed]).all()
        assert sorted(ds.failures(), key=lambda f: f[2]) == [
            (sample_id(bad), bad, "contact did not converge"),
            (sample_id({"family": "woven", "seed": 8}), {"family": "woven", "seed": 8}, "generator raised")]
        ok = list(ds.iter_samples())
        assert len(ok) == 3 and all(s.status == "ok" and s.fluctuation.shape == (40, 40) for s in ok)
        one = next(s for s in ok if s.id == sid)
        assert one.values["contact_history"] == [10, 12, 12] and one.values["V_stderr"] == 0.002
        assert np.allclose(one.grid_axis_mm, np.linspace(-1, 1, 40))
        assert {s.heightmap is None for s in ds.iter_samples("failed")} == {True, False}
        with pytest.raises(KeyError, match="no fluctuation"):
            ds.fluctuation(sample_id(bad))
        with pytest.raises(KeyError, match="no sample"):
            ds.heightmap("0" * 16)
    assert verify(path) == []


def test_result_fields_from_a_result():
    result = SimpleNamespace(**fields(0), nodes=100, warnings=[])
    extracted = result_fields(result)
    assert extracted.keys() == fields(0).keys() and extracted["roughness"] == 0.1


def test_writes_are_idempotent(tmp_path):
    path = tmp_path / "d.h5"
    with DatasetWriter(path, CONFIG, "test") as writer:
        assert writer.write_result(*sample(0))
        shuffled = dict(reversed(list(recipe(0).items())))
        assert not writer.write_result(shuffled, *sample(0)[1:])
        assert not writer.write_failure(recipe(0), None, 0.05, "late failure")
        assert writer.write_failure(recipe(1), None, 0.05, "failed")
        assert not writer.write_result(*sample(1))
        assert writer.ids == {sample_id(recipe(0)), sample_id(recipe(1))}
    with open_dataset(path) as ds:
        assert len(ds) == 2 and ds.table()["status"].tolist().count("ok") == 1


def test_reopen_appends_with_same_config_and_rejects_another(tmp_path):
    path = tmp_path / "d.h5"
    assert fill(path, range(3)) == [True] * 3
    assert fill(path, range(5)) == [False] * 3 + [True] * 2
    with pytest.raises(InputError, match="force_n: file 10.0, given 5.0"):
        DatasetWriter(path, {**CONFIG, "force_n": 5.0}, "test")
    with pytest.raises(InputError, match="another configuration"):
        DatasetWriter(path, {**CONFIG, "extra": 1}, "test")
    with open_dataset(path) as ds:
        assert len(ds) == 5
    assert not journal_path(path).exists()


def test_one_writer_at_a_time(tmp_path):
    path = tmp_path / "d.h5"
    with DatasetWriter(path, CONFIG, "test"):
        with pytest.raises(InputError, match="another DatasetWriter"):
            DatasetWriter(path, CONFIG, "test")


def test_sample_ids_are_deterministic_and_ignore_key_order():
    a = {"family": "fbm", "seed": 3, "params": {"hurst": 0.8, "rms_mm": 0.1}, "perturbation": None}
    b = {"perturbation": None, "params": {"rms_mm": 0.1, "hurst": 0.8}, "seed": np.int64(3), "family": "fbm"}
    assert sample_id(a) == sample_id(b) == sample_id(dict(a))
    assert len(sample_id(a)) == 16 and int(sample_id(a), 16) >= 0
    assert sample_id({**a, "seed": 4}) != sample_id(a)
    assert sample_id(a) == "c38b15f633f72e4a"  # stable across processes and versions


def test_reading_while_the_writer_appends(tmp_path):
    path = tmp_path / "d.h5"
    with DatasetWriter(path, CONFIG, "test") as writer:
        writer.write_result(*sample(0))
        with open_dataset(path) as ds:
            assert len(ds) == 1
            for i in range(1, 4):
                writer.write_result(*sample(i))
            assert ds.heightmap(sample_id(recipe(0))).shape == (40, 40)
        with open_dataset(path) as ds:
            assert len(ds) == 4


def test_an_exception_mid_sample_rolls_back(tmp_path, monkeypatch):
    path = tmp_path / "d.h5"
    with DatasetWriter(path, CONFIG, "test") as writer:
        writer.write_result(*sample(0))
        real = store._put_map

        def broken(group, name, values):
            if name == "fluctuation":
                raise KeyboardInterrupt
            return real(group, name, values)

        monkeypatch.setattr(store, "_put_map", broken)
        with pytest.raises(KeyboardInterrupt):
            writer.write_result(*sample(1))
        monkeypatch.setattr(store, "_put_map", real)
        assert writer.ids == {sample_id(recipe(0))}
        assert writer.write_result(*sample(1))
    assert verify(path) == []
    with h5py.File(path, "r") as f:
        assert sorted(f["samples"]) == sorted(sample_id(recipe(i)) for i in range(2))


def test_invalid_samples_are_refused_before_writing(tmp_path):
    with DatasetWriter(tmp_path / "d.h5", CONFIG, "test") as writer:
        rec, heights, pixel, values, strain = sample(0)
        with pytest.raises(ValueError, match="family"):
            writer.write_result({"seed": 1}, heights, pixel, values, strain)
        with pytest.raises(ValueError, match="roughness is nan"):
            writer.write_result(rec, heights, pixel, {**values, "roughness": float("nan")}, strain)
        with pytest.raises(ValueError, match="missing"):
            writer.write_result(rec, heights, pixel, {"roughness": 0.1}, strain)
        with pytest.raises(ValueError, match="2-D"):
            writer.write_result(rec, heights[0], pixel, values, strain)
        assert writer.ids == frozenset()


def test_verify_catches_tampering(tmp_path):
    path = tmp_path / "d.h5"
    fill(path, range(3))
    first, second = sample_id(recipe(0)), sample_id(recipe(1))
    with h5py.File(path, "r+") as f:
        f["samples"][first].attrs["V"] = np.nan
        f["samples"].move(second, "0123456789abcdef")
        f["samples"].create_group(".tmp-feedfeedfeedfeed")
    problems = verify(path)
    assert len(problems) == 3
    assert f"samples/{first}: V is nan" in problems
    assert f"samples/0123456789abcdef: id does not match its recipe (expected {second})" in problems
    assert "samples/.tmp-feedfeedfeedfeed: unfinished sample left behind" in problems
    with h5py.File(path, "r+") as f:
        del f.attrs["created"]
    assert "root attribute 'created' is missing" in verify(path)


def test_info_counts(tmp_path):
    path = tmp_path / "d.h5"
    fill(path, range(6))
    with DatasetWriter(path, CONFIG, "test") as writer:
        writer.write_failure({"family": "fbm", "seed": 99}, None, 0.05, "solver diverged")
        writer.write_failure({"family": "woven", "seed": 99}, None, 0.05, "solver diverged")
    summary = info(path)
    assert (summary["samples"], summary["ok"], summary["failed"], summary["converged"]) == (8, 6, 2, 3)
    assert summary["families"] == {"fbm": {"ok": 4, "failed": 1}, "woven": {"ok": 2, "failed": 1}}
    assert summary["V"] == pytest.approx([0.1, 0.15]) and summary["contact_fraction"] == pytest.approx([0.5, 0.55])
    assert summary["failure_reasons"] == {"solver diverged": 2}
    assert summary["roughness_version"] == "test"


def test_bad_files_raise_input_errors(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("not HDF5")
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["heightmap"] = np.zeros((4, 4))
    for func in (open_dataset, info, verify):
        with pytest.raises(InputError, match="no dataset file"):
            func(tmp_path / "missing.h5")
        with pytest.raises(InputError, match="not an HDF5 file"):
            func(text)
    for func in (open_dataset, info):
        with pytest.raises(InputError, match="not a roughness dataset"):
            func(other)
    assert "root attribute 'schema' is missing" in verify(other)
    with pytest.raises(InputError, match="not an HDF5 file"):
        DatasetWriter(text, CONFIG, "test")
    with pytest.raises(InputError, match="not a roughness dataset"):
        DatasetWriter(other, CONFIG, "test")
    assert text.read_text() == "not HDF5" and not journal_path(text).exists()
    with h5py.File(other, "r") as f:
        assert list(f) == ["heightmap"]


# --- crash safety: writer processes that die ------------------------------------------------------

CHILD = """
import os, sys
sys.path[:0] = [{root!r}, {tests!r}]
import test_store as t
from roughness.dataset.store import DatasetWriter
path, n, trap_at, crash_write = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
with DatasetWriter(path, t.CONFIG, "test") as writer:
    for i in range(n):
        if i == trap_at:
            t.die_at_file_write(crash_write)
        if writer.write_result(*t.sample(i)):
            print(i, flush=True)
"""


def die_at_file_write(k: int) -> None:
    """Make the process exit abruptly at its k-th write into the dataset file (os.pwrite)."""
    real, calls = os.pwrite, [0]

    def pwrite(fd: int, data: bytes, offset: int) -> int:
        calls[0] += 1
        if calls[0] == k:
            os._exit(9)
        return real(fd, data, offset)

    os.pwrite = pwrite


def writer_process(tmp_path: Path, path: Path, n: int = N, trap_at: int = -1, crash_write: int = 0):
    script = tmp_path / "child.py"
    script.write_text(CHILD.format(root=str(ROOT), tests=str(Path(__file__).parent)))
    return subprocess.Popen([sys.executable, str(script), str(path), str(n), str(trap_at), str(crash_write)],
                            stdout=subprocess.PIPE, text=True)


def written_after(child: subprocess.Popen, lines: int, sig: int) -> list[int]:
    """Indices the child reported before it got ``sig`` after ``lines`` reports."""
    done = [int(child.stdout.readline()) for _ in range(lines)]
    child.send_signal(sig)
    child.wait(timeout=30)
    return done + [int(line) for line in child.stdout.read().split()]


def stored_indices(path: Path) -> list[int]:
    """Indices of the test samples in the file, checked to be intact; the file has no other samples."""
    assert verify(path) == []
    with open_dataset(path) as ds:
        by_id = {sample_id(recipe(i)): i for i in range(N)}
        assert set(ds.ids) <= set(by_id)
        for sid in ds.ids:
            rec, heights, pixel, values, strain = sample(by_id[sid])
            assert np.array_equal(ds.heightmap(sid).heights, heights.astype(np.float32))
            assert np.array_equal(ds.fluctuation(sid), strain.astype(np.float32))
        return sorted(by_id[sid] for sid in ds.ids)


def test_killed_writers_lose_and_duplicate_nothing(tmp_path):
    path = tmp_path / "d.h5"
    reported = written_after(writer_process(tmp_path, path), 3, signal.SIGKILL)
    stored = stored_indices(path)
    assert stored == list(range(len(stored))) and len(stored) - len(reported) in (0, 1)
    reported = written_after(writer_process(tmp_path, path), 2, signal.SIGINT)
    again = stored_indices(path)
    assert again[:len(stored)] == stored and again == list(range(len(again))) and set(reported) <= set(again)
    assert not journal_path(path).exists()  # the interrupted writer closed cleanly
    with h5py.File(path, "r") as f:  # so plain h5py reads it too
        assert len(f["samples"]) == len(again)
    assert fill(path, range(N)).count(True) == N - len(again)
    assert stored_indices(path) == list(range(N))


def test_writer_killed_while_copying_a_commit(tmp_path):
    path = tmp_path / "d.h5"
    child = writer_process(tmp_path, path, trap_at=4, crash_write=2)
    assert child.wait(timeout=30) == 9 and child.stdout.read().split() == ["0", "1", "2", "3"]
    assert journal_path(path).stat().st_size > 0
    assert stored_indices(path) == [0, 1, 2, 3, 4]  # sample 4's record was complete: readers replay it
    assert fill(path, range(6)) == [False] * 5 + [True]  # the writer repairs the file and goes on
    with h5py.File(path, "r") as f:
        assert len(f["samples"]) == 6
    assert not journal_path(path).exists()


def test_torn_journal_record_is_ignored(tmp_path):
    path = tmp_path / "d.h5"
    child = writer_process(tmp_path, path, trap_at=3, crash_write=1)
    assert child.wait(timeout=30) == 9
    journal = journal_path(path)
    journal.write_bytes(journal.read_bytes()[:-100])  # as if killed while writing the journal
    assert stored_indices(path) == [0, 1, 2]
    assert fill(path, range(5)) == [False] * 3 + [True] * 2
    assert stored_indices(path) == [0, 1, 2, 3, 4]


def test_commits_wait_for_plain_h5py_readers(tmp_path, monkeypatch):
    path = tmp_path / "d.h5"
    fill(path, range(1))
    monkeypatch.setattr(store, "LOCK_PATIENCE_S", 0.05)
    plain = h5py.File(path, "r")  # HDF5 holds a shared flock until closed
    closer = threading.Timer(0.5, plain.close)
    closer.start()
    with pytest.warns(UserWarning, match="an open h5py.File"):
        assert fill(path, range(2)) == [False, True]
    closer.join()
    assert stored_indices(path) == [0, 1]

"""The HDF5 training-set store: round trips, idempotent appends, checks, old files, and crash safety."""
from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pytest

from roughness.core.errors import InputError
from roughness.dataset import writer as dataset_writer
from roughness.dataset.digest import inputs_sha256
from roughness.dataset.inspection import info, verify
from roughness.dataset.layout import parts_folder
from roughness.dataset.reader import open_dataset
from roughness.dataset.schema import DatasetConfig, result_fields, sample_id
from roughness.dataset.writer import DatasetWriter

ROOT = Path(__file__).parents[1]
CONFIG = {"simulation": {"force_n": 10.0, "fidelity": "coarse", "h_contact_mm": None}, "recipe": {"seed": 0}}
N = 12


def texture_record(i: int) -> dict:
    return {"family": "fbm" if i % 3 else "woven", "params": {"hurst": 0.5 + i / 100}, "seed": i,
            "perturbation": {"tilt_deg": 0.0}}


def fields(i: int) -> dict:
    return {"roughness": 0.1 + i / 100, "roughness_stderr": 0.002, "contact_fraction": 0.5 + i / 100,
            "indentation_mm": 0.6, "converged": i % 2 == 0, "iterations": 3 + i, "unresolved_nodes": i % 2,
            "cycled": False, "seconds": 1.5, "contact_history": [10, 12, 12], "grid_axis_mm": np.linspace(-1, 1, 40),
            "discretization_error": None if i % 3 == 0 else 0.012,
            "ladder": [{"h_contact_mm": 0.3, "roughness": 0.09}, {"h_contact_mm": 0.2, "roughness": 0.1 + i / 100}]}


def sample(i: int) -> tuple:
    """write_result arguments of test sample ``i``: 40x40 maps (ok samples' heights differ in shape)."""
    rng = np.random.default_rng(i)
    return texture_record(i), rng.random((40, 40 + i % 2)), 0.05, fields(i), rng.normal(size=(40, 40))


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
    assert not parts_folder(path).exists()
    with open_dataset(path) as ds:
        assert len(ds) == 5 and ds.ids == sorted(ds.ids)
        assert sorted(ds.ids) == sorted([sample_id(texture_record(i)) for i in range(3)]
                                        + [sample_id(bad), sample_id({"family": "woven", "seed": 8})])
        assert texture_record(1) in ds.texture_records and bad in ds.texture_records
        assert ds.config == DatasetConfig(**CONFIG) and ds.header.roughness_version == "1.2.3"
        assert ds.header.schema_version == 2
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
        assert one.values["ladder_h_mm"] == [0.3, 0.2] and one.values["ladder_V"] == [0.09, values["roughness"]]
        assert one.values["discretization_error"] == 0.012
        estimates = {s.id: s.values["discretization_error"] for s in ok}
        assert np.isnan(estimates[sample_id(sample(0)[0])])  # not estimated: stored as nan, still ok
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
        shuffled = dict(reversed(list(texture_record(0).items())))
        assert not writer.write_result(shuffled, *sample(0)[1:])
        assert not writer.write_failure(texture_record(0), None, 0.05, "late failure")
        assert writer.write_failure(texture_record(1), None, 0.05, "failed")
        assert not writer.write_result(*sample(1))
        assert writer.ids == {sample_id(texture_record(0)), sample_id(texture_record(1))}
    with open_dataset(path) as ds:
        assert len(ds) == 2 and ds.table()["status"].tolist().count("ok") == 1


def test_reopen_appends_with_same_config_and_rejects_another(tmp_path):
    path = tmp_path / "d.h5"
    assert fill(path, range(3)) == [True] * 3
    assert fill(path, range(5)) == [False] * 3 + [True] * 2
    other = {**CONFIG, "simulation": {**CONFIG["simulation"], "force_n": 5.0}}
    with pytest.raises(InputError, match="simulation.force_n: file 10.0, given 5.0"):
        DatasetWriter(path, other, "test")
    with pytest.raises(InputError, match="another configuration"):
        DatasetWriter(path, {**CONFIG, "recipe": {"seed": 1}}, "test")
    with pytest.raises(InputError, match="'simulation' and 'recipe'"):
        DatasetWriter(path, {"force_n": 10.0}, "test")
    with open_dataset(path) as ds:
        assert len(ds) == 5
    assert not parts_folder(path).exists()


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
            assert ds.heightmap(sample_id(texture_record(0))).shape == (40, 40)
        with open_dataset(path) as ds:
            assert len(ds) == 4


def test_an_exception_mid_sample_rolls_back(tmp_path, monkeypatch):
    path = tmp_path / "d.h5"
    with DatasetWriter(path, CONFIG, "test") as writer:
        writer.write_result(*sample(0))
        real = np.savez_compressed

        def broken(file, **arrays):
            Path(file).write_bytes(b"half a sample")
            raise KeyboardInterrupt

        monkeypatch.setattr(np, "savez_compressed", broken)
        with pytest.raises(KeyboardInterrupt):
            writer.write_result(*sample(1))
        monkeypatch.setattr(np, "savez_compressed", real)
        assert writer.ids == {sample_id(texture_record(0))}
        assert os.listdir(parts_folder(path)) == [f"{sample_id(texture_record(0))}.npz"]
        assert writer.write_result(*sample(1))
    assert verify(path) == []
    with h5py.File(path, "r") as f:
        assert sorted(f["samples"]) == sorted(f["index"]["id"].asstr()[()]) == sorted(sample_id(texture_record(i))
                                                                                        for i in range(2))


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
    ids = sorted(sample_id(texture_record(i)) for i in range(3))
    with h5py.File(path, "r+") as f:
        f["index"]["V"][0] = np.nan
        f["index"]["status"][1] = "maybe"
        f["samples"].create_group("feedfeedfeedfeed")
        del f["samples"][ids[2]]["fluctuation"]
    problems = verify(path)
    assert sorted(problems) == sorted([f"samples/{ids[0]}: V is nan",
                                       f"samples/{ids[1]}: status 'maybe' is neither 'ok' nor 'failed'",
                                       "samples/feedfeedfeedfeed: not in the index (an unfinished sample)",
                                       f"samples/{ids[2]}: fluctuation is missing or not 2-D"])
    with h5py.File(path, "r+") as f:
        f["index"]["id"][0] = "0123456789abcdef"
    assert any("0123456789abcdef: id does not match its recipe" in p for p in verify(path))
    parts_folder(path).mkdir()
    (parts_folder(path) / "00000000000000aa.npz").write_bytes(b"torn")
    assert any("00000000000000aa.npz: unreadable" in p for p in verify(path))
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
    assert text.read_text() == "not HDF5" and not parts_folder(text).exists()
    with h5py.File(other, "r") as f:
        assert list(f) == ["heightmap"]


def test_version_1_files_are_read_and_converted_by_the_next_writer(tmp_path):
    """A file of the old layout (one group per sample with its values as attributes, no index)."""
    path = tmp_path / "old.h5"
    with h5py.File(path, "w") as f:
        f.attrs.update(schema="roughness.dataset", schema_version=1, config=json.dumps(CONFIG),
                       roughness_version="0.0.0", created="2026-01-01T00:00:00+00:00")
        for i in range(3):
            rec, heights, pixel, values, strain = sample(i)
            group = f.create_group(f"samples/{sample_id(rec)}")
            group["heightmap"], group["fluctuation"] = heights.astype(np.float32), strain.astype(np.float32)
            group["fluctuation"].attrs["grid_axis_mm"] = values["grid_axis_mm"]
            group.attrs.update(recipe=json.dumps(rec), status="ok", pixel_mm=pixel, written="then",
                               roughness_version="0.0.0", V=values["roughness"], V_stderr=0.002,
                               contact_fraction=0.5, indentation_mm=0.6, converged=True, iterations=3,
                               unresolved_nodes=0, cycled=False, seconds=1.5, contact_history=[10, 12])
        f.create_group("samples/.tmp-feedfeedfeedfeed")  # an unfinished sample of the old writer
    with open_dataset(path) as ds:
        assert ds.header.schema_version == 1 and len(ds) == 3
        assert ds.table()["V"].tolist() == [values_of(sid) for sid in ds.ids]
    assert stored_indices(path, unfinished_ok=True) == [0, 1, 2]
    checksum = inputs_sha256(path)
    assert fill(path, range(3)) == [False] * 3  # nothing to add: the writer converts the file
    with open_dataset(path) as ds:
        assert ds.header.schema_version == 2 and ds.header.created == "2026-01-01T00:00:00+00:00"
    assert stored_indices(path) == [0, 1, 2] and inputs_sha256(path) == checksum
    assert fill(path, range(5)) == [False] * 3 + [True] * 2
    assert stored_indices(path) == [0, 1, 2, 3, 4]
    new = tmp_path / "new.h5"
    fill(new, range(3))
    assert inputs_sha256(new) == checksum  # ids, texture records and heightmaps read alike from both layouts


def values_of(sid: str) -> float:
    return next(fields(i)["roughness"] for i in range(N) if sample_id(texture_record(i)) == sid)


def test_opening_reads_the_index_not_the_sample_groups(tmp_path, monkeypatch):
    path = tmp_path / "d.h5"
    fill(path, range(4))

    def walked(*args, **kwargs):
        raise AssertionError("a sample group was opened")

    monkeypatch.setattr(h5py.Group, "items", walked)
    with open_dataset(path) as ds:
        assert len(ds) == 4 and len(ds.table()["V"]) == 4 and len(ds.texture_records) == 4


def test_reading_while_the_writer_packs(tmp_path):
    path = tmp_path / "d.h5"
    fill(path, range(2))
    with open_dataset(path) as before:
        with DatasetWriter(path, CONFIG, "test") as writer:
            writer.write_result(*sample(2))
            during = open_dataset(path)  # one packed file, one part
        with during:
            assert len(during) == 3 and len(before) == 2
            maps = [s.fluctuation.shape for s in during.iter_samples()]  # the part is packed by now
            assert maps == [(40, 40)] * 3
        assert before.heightmap(sample_id(texture_record(0))).shape == (40, 40)  # the replaced file stays readable


# --- crash safety: writer processes that die ------------------------------------------------------

# The child pauses after each sample it reports, so a signal sent after a report lands while it writes, never
# after its last sample (a SIGINT during the closing pack leaves the parts for the next writer: nothing is lost,
# but the test would not see the interrupted writer pack; with 12 small samples that happened on an idle machine).
CHILD = """
import sys, time
sys.path[:0] = [{root!r}, {tests!r}]
import test_store as t
from roughness.dataset.writer import DatasetWriter
path, n = sys.argv[1], int(sys.argv[2])
with DatasetWriter(path, t.CONFIG, "test") as writer:
    for i in range(n):
        if writer.write_result(*t.sample(i)):
            print(i, flush=True)
            time.sleep(0.5)
"""


def writer_process(tmp_path: Path, path: Path, n: int = N) -> subprocess.Popen:
    script = tmp_path / "child.py"
    script.write_text(CHILD.format(root=str(ROOT), tests=str(Path(__file__).parent)))
    return subprocess.Popen([sys.executable, str(script), str(path), str(n)], stdout=subprocess.PIPE, text=True)


def written_after(child: subprocess.Popen, lines: int, sig: int) -> list[int]:
    """Indices the child reported before it got ``sig`` after ``lines`` reports."""
    done = [int(child.stdout.readline()) for _ in range(lines)]
    child.send_signal(sig)
    child.wait(timeout=30)
    return done + [int(line) for line in child.stdout.read().split()]


def stored_indices(path: Path, unfinished_ok: bool = False) -> list[int]:
    """Indices of the test samples in the dataset, checked to be intact; it has no other samples."""
    problems = verify(path)
    assert problems == [] or (unfinished_ok and all("unfinished" in p for p in problems)), problems
    with open_dataset(path) as ds:
        by_id = {sample_id(texture_record(i)): i for i in range(N)}
        assert set(ds.ids) <= set(by_id) and len(set(ds.ids)) == len(ds)
        for s in ds.iter_samples(None):
            rec, heights, _, values, strain = sample(by_id[s.id])
            assert s.texture_record == rec and s.values["V"] == values["roughness"]
            assert np.array_equal(s.heightmap.heights, heights.astype(np.float32))
            assert np.array_equal(s.fluctuation, strain.astype(np.float32))
        return sorted(by_id[sid] for sid in ds.ids)


def test_killed_writers_lose_and_duplicate_nothing(tmp_path):
    path = tmp_path / "d.h5"
    reported = written_after(writer_process(tmp_path, path), 3, signal.SIGKILL)
    stored = stored_indices(path)
    assert stored == list(range(len(stored))) and len(stored) - len(reported) in (0, 1)
    assert parts_folder(path).exists()  # killed before packing: its samples are parts, read from there
    reported = written_after(writer_process(tmp_path, path), 2, signal.SIGINT)
    again = stored_indices(path)
    assert again[:len(stored)] == stored and again == list(range(len(again))) and set(reported) <= set(again)
    assert not parts_folder(path).exists()  # the interrupted writer packed everything on its way out
    with h5py.File(path, "r") as f:  # so plain h5py reads it all
        assert len(f["samples"]) == len(f["index"]["id"]) == len(again)
    assert fill(path, range(N)).count(True) == N - len(again)
    assert stored_indices(path) == list(range(N))


STEPS = [(os, "replace"), (os, "unlink"), (os, "rmdir"), (shutil, "copyfile"), (np, "savez_compressed"),
         (dataset_writer, "_put_maps"), (dataset_writer, "_write_index")]


def run_until_step(path: Path, k: int, indices: range) -> tuple[int, list[int]]:
    """Fork a writer of ``indices`` that dies (exit 9) at its k-th file operation (STEPS); its exit
    status and the indices whose write returned."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: count the operations, die at the k-th
        os.close(read)
        calls = [0]

        def dying(real):
            def step(*args, **kwargs):
                calls[0] += 1
                if calls[0] == k:
                    os._exit(9)
                return real(*args, **kwargs)
            return step

        for module, name in STEPS:
            setattr(module, name, dying(getattr(module, name)))
        try:
            with DatasetWriter(path, CONFIG, "test") as writer:
                for i in indices:
                    writer.write_result(*sample(i))
                    os.write(write, bytes([i]))
        finally:
            os._exit(0)
    os.close(write)
    _, status = os.waitpid(pid, 0)
    with os.fdopen(read, "rb") as pipe:
        return os.waitstatus_to_exitcode(status), list(pipe.read())


def test_writer_killed_at_every_file_operation(tmp_path):
    """Kill a writer that adds three samples to a file of three at each of its file operations in
    turn (parts, the pack's copy, maps, index and rename, the parts' removal): each time the dataset
    holds exactly the samples whose write returned (and perhaps the one being written), all intact,
    and the next writer completes it."""
    base = tmp_path / "base.h5"
    fill(base, range(3))
    k, code = 0, 9
    while code == 9:
        k += 1
        assert k < 40, "the writer should finish within 40 file operations"
        path = tmp_path / f"k{k}" / "d.h5"
        path.parent.mkdir()
        shutil.copyfile(base, path)
        code, reported = run_until_step(path, k, range(3, 6))
        stored = stored_indices(path)
        assert set(range(3)) | set(reported) <= set(stored) <= set(range(3)) | set(reported) | {3 + len(reported)}
        assert fill(path, range(6)).count(True) == 6 - len(stored)
        assert stored_indices(path) == list(range(6))
        assert os.listdir(path.parent) == ["d.h5"]  # no temporary files or parts left
    assert code == 0 and k > 12  # the last run finished: every step before it was a crash point


def test_index_written_before_the_discretization_columns_reads_with_their_defaults(tmp_path):
    """Version-2 files from before discretization_error and the ladder were stored stay readable."""
    path = tmp_path / "older.h5"
    fill(path, range(2))
    with h5py.File(path, "a") as f:
        for name in ("discretization_error", "ladder_h_mm", "ladder_V"):
            del f["index"][name]
    with open_dataset(path) as ds:
        assert len(ds) == 2 and np.isfinite(ds.table()["V"]).all()
        assert np.isnan(ds.table()["discretization_error"]).all()
        assert all(s.values["ladder_V"] == [] for s in ds.iter_samples())
    assert verify(path) == []


def test_labels_round_trip_every_entry_value_and_restore_into_a_new_file(tmp_path):
    """Labels keep each entry's values exactly (nan discretization errors, ladders, failures with and without a
    heightmap); write_labelled stores them with their original time and version, marked restored, no fluctuation."""
    from dataclasses import asdict

    from roughness.dataset.labels import export_labels, heights_digest, load_labels

    path = tmp_path / "d.h5"
    with DatasetWriter(path, CONFIG, "1.2.3") as writer:
        for i in range(4):
            writer.write_result(*sample(i))
        writer.write_failure({"family": "cellular", "seed": 7}, np.ones((40, 40)), 0.05, "contact did not converge")
        writer.write_failure({"family": "woven", "seed": 8}, None, 0.05, "generator raised")
    export_labels(path, tmp_path / "l.jsonl.gz")
    labels = load_labels(tmp_path / "l.jsonl.gz")
    assert labels.config == DatasetConfig(**CONFIG) and len(labels) == 6
    copy = tmp_path / "copy.h5"
    with open_dataset(path) as ds, DatasetWriter(copy, CONFIG, "9.9.9") as writer:
        for sid, entry in ds.entries().items():
            label = labels.labels[sid]
            heights = ds.heightmap(sid) if label.heights else None
            if heights is not None:
                assert label.heights == heights_digest(heights.heights, heights.pixel_mm)
            assert writer.write_labelled(json.loads(entry.recipe), None if heights is None else heights.heights,
                                         entry.pixel_mm, label.values)
    with open_dataset(path) as a, open_dataset(copy) as b:
        for sid, entry in a.entries().items():
            restored = b.entries()[sid]
            assert restored.restored and json.dumps(asdict(restored) | {"restored": False}) == json.dumps(asdict(entry))
    assert verify(copy) == [] and info(copy)["restored"] == 6

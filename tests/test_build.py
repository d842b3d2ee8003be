"""Parallel dataset generation: local Dask run, resume after a kill, failures recorded."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from roughness import dataset
from roughness.dataset.build import build
from roughness.dataset.inspection import verify
from roughness.dataset.reader import open_dataset
from roughness.dataset.recipe import Recipe, expand, realise
from roughness.dataset.schema import sample_id
from roughness.simulate.config import SimConfig

# A 6 mm block at the paper's contact pressure (10 N on 10 x 10 mm -> 3.6 N on 6 x 6 mm): at 10 N the
# sparse, tall bumps of this recipe push it beyond the 4 tissue thicknesses the FEM refuses.
SMALL = SimConfig(width_mm=6.0, window_mm=4.0, h_contact_mm=0.5, pairs=2000, force_n=3.6)
RECIPE = Recipe(name="test", seed=7, families={"bumps": 1.0, "grating": 1.0, "dots": 1.0}, size_mm=7.0)


def test_recipe_is_deterministic_and_prefix_stable():
    a, b = expand(RECIPE, 12), expand(RECIPE, 5)
    assert a[:5] == b
    assert len({sample_id(r) for r in a}) == 12
    assert np.array_equal(realise(a[3]).heights, realise(a[3]).heights)


def test_local_dask_run_with_two_workers(tmp_path):
    out = tmp_path / "d.h5"
    counts = build(str(out), 6, RECIPE, SMALL, workers=2, quiet=True)
    assert counts == {"requested": 6, "already_done": 0, "written": 6, "failed": 0, "restored": 0}
    with open_dataset(out) as ds:
        assert sorted(ds.ids) == sorted(sample_id(r) for r in expand(RECIPE, 6))
        assert np.all(np.isfinite(ds.table()["V"]))
        # every label carries its discretization-error estimate and the levels it came from
        assert np.all(np.isfinite(ds.table()["discretization_error"]))
        for s in ds.iter_samples():
            assert s.values["ladder_h_mm"] == [0.75, 0.5] and s.values["ladder_V"][-1] == s.values["V"]
    assert verify(out) == []
    again = build(str(out), 8, RECIPE, SMALL, workers=2, quiet=True)
    assert again["already_done"] == 6 and again["written"] == 2


def test_samples_beyond_the_submission_window_are_all_built(tmp_path, monkeypatch):
    """Tasks go out as earlier ones finish: with one in flight at a time, every sample still arrives once."""
    import roughness.dataset.build as build_module
    monkeypatch.setattr(build_module, "MIN_IN_FLIGHT", 1)
    monkeypatch.setattr(build_module, "IN_FLIGHT_PER_THREAD", 0)
    out = tmp_path / "w.h5"
    counts = build(str(out), 4, RECIPE, SMALL, workers=1, quiet=True)
    assert counts["written"] == 4 and counts["failed"] == 0, counts
    with open_dataset(out) as ds:
        assert sorted(ds.ids) == sorted(sample_id(r) for r in expand(RECIPE, 4))


def test_failed_samples_are_recorded_and_do_not_stop_the_run(tmp_path):
    out = tmp_path / "f.h5"
    too_small = Recipe(seed=1, families={"grating": 1.0}, size_mm=5.0)  # map smaller than the footprint
    counts = build(str(out), 3, too_small, SMALL, workers=1, quiet=True)
    assert counts["failed"] == 3
    with open_dataset(out) as ds:
        reasons = [err for _, _, err in ds.failures()]
    assert len(reasons) == 3 and all(r.startswith("InputError: ") for r in reasons)
    assert any("footprint" in r for r in reasons)  # texture made, simulation refused


# Samples of the kill test: a kill after the first two are stored lands mid-run even though coarse samples are fast.
KILL_N = 16


@pytest.mark.parametrize("sig", [signal.SIGKILL, pytest.param(signal.SIGINT, marks=pytest.mark.slow)],
                         ids=["SIGKILL", "SIGINT"])  # Ctrl-C takes the same resume path: opt-in (1 min)
def test_killed_build_resumes_to_exactly_n_distinct_samples(tmp_path, sig):
    out = tmp_path / "k.h5"
    cmd = [sys.executable, "-m", "roughness.cli", "dataset", "build", "--out", str(out), "--n", str(KILL_N),
           "--fidelity", "coarse", "--workers", "2", "--seed", "3", "--quiet"]
    # the build must see SIGINT as Ctrl-C even if something earlier in this pytest process ignored it (inherited)
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 240
    while time.time() < deadline and _count(out) < 2:
        time.sleep(0.5)
    os.killpg(proc.pid, sig)
    proc.wait(timeout=60)
    first = _count(out)
    assert 2 <= first < KILL_N, "the kill should land mid-run"
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    counts = json.loads(done.stdout)
    assert counts["already_done"] == first and counts["written"] + counts["failed"] == KILL_N - first
    with dataset.open(out) as ds:
        assert len(ds) == KILL_N and len(set(ds.ids)) == KILL_N
    assert verify(out) == []


def _count(path) -> int:
    """Samples stored: the reader's count (file and parts), or the parts alone before the first pack creates the file."""
    if not path.exists():
        parts = path.with_name(path.name + ".parts")
        return len(list(parts.glob("*.npz"))) if parts.is_dir() else 0
    try:
        with open_dataset(path) as ds:
            return len(ds)
    except Exception:
        return 0


def test_input_digest_is_reproducible_across_builds(tmp_path):
    from roughness.core.hashing import file_sha256
    from roughness.dataset.digest import inputs_sha256

    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    build(str(a), 3, RECIPE, SMALL, workers=1, quiet=True)
    build(str(b), 3, RECIPE, SMALL, workers=1, quiet=True)
    assert inputs_sha256(a) == inputs_sha256(b)
    assert len(file_sha256(a)) == 64


def test_labels_file_remakes_a_build_without_the_fem(tmp_path):
    """A labels file (FEM results and heightmap digests, no maps) restores a build; a sample whose texture
    no longer matches its label, or that has none, is simulated."""
    import gzip

    from roughness.core.errors import InputError
    from roughness.dataset.digest import inputs_sha256
    from roughness.dataset.labels import export_labels, load_labels

    first, labels = tmp_path / "first.h5", tmp_path / "first.labels.jsonl.gz"
    build(str(first), 4, RECIPE, SMALL, workers=1, quiet=True)
    exported = export_labels(first, labels)
    assert len(exported) == 4 and load_labels(labels) == exported
    again = tmp_path / "again.labels.jsonl.gz"
    export_labels(first, again)
    assert again.read_bytes() == labels.read_bytes()  # same labels, same bytes (committable)
    with pytest.raises(InputError, match="already exists"):
        export_labels(first, labels)

    remade = tmp_path / "remade.h5"
    counts = build(str(remade), 5, RECIPE, SMALL, workers=1, quiet=True, labels=load_labels(labels))
    assert counts["restored"] == 4 and counts["written"] == 1  # the fifth sample has no label
    with open_dataset(first) as a, open_dataset(remade) as b:
        ea, eb = a.entries(), b.entries()
        for sid in ea:
            assert eb[sid].restored and not ea[sid].restored
            assert (eb[sid].V, eb[sid].ladder_V, eb[sid].written) == (ea[sid].V, ea[sid].ladder_V, ea[sid].written)
            with pytest.raises(KeyError, match="restored from a labels file"):
                b.fluctuation(sid)
        assert sum(not e.restored for e in eb.values()) == 1
    assert verify(remade) == []
    four = tmp_path / "four.h5"
    build(str(four), 4, RECIPE, SMALL, workers=1, quiet=True, labels=load_labels(labels))
    assert inputs_sha256(four) == inputs_sha256(first)

    # a label whose heightmap digest no longer matches (the generator changed) is not taken
    lines = gzip.decompress(labels.read_bytes()).decode().splitlines()
    row = json.loads(lines[1])
    row["heights"] = "0" * 16
    stale = tmp_path / "stale.labels.jsonl.gz"
    stale.write_bytes(gzip.compress("\n".join([lines[0], json.dumps(row), *lines[2:]]).encode()))
    counts = build(str(tmp_path / "stale.h5"), 4, RECIPE, SMALL, workers=1, quiet=True, labels=load_labels(stale))
    assert counts["restored"] == 3 and counts["written"] == 1


def test_labels_of_another_configuration_or_damaged_are_refused(tmp_path):
    from dataclasses import replace

    from roughness.cli import main
    from roughness.core.errors import InputError
    from roughness.dataset.labels import export_labels, load_labels

    first, labels = tmp_path / "first.h5", tmp_path / "l.jsonl.gz"
    build(str(first), 1, RECIPE, SMALL, workers=1, quiet=True)
    export_labels(first, labels)
    with pytest.raises(InputError, match="another configuration.*force_n"):
        build(str(tmp_path / "other.h5"), 1, RECIPE, replace(SMALL, force_n=2.0), quiet=True, labels=load_labels(labels))
    truncated = tmp_path / "t.jsonl.gz"
    import gzip
    truncated.write_bytes(gzip.compress(gzip.decompress(labels.read_bytes()).splitlines()[0]))
    with pytest.raises(InputError, match="truncated"):
        load_labels(truncated)
    (tmp_path / "junk.gz").write_text("not gzip")
    with pytest.raises(InputError, match="not a gzip file"):
        load_labels(tmp_path / "junk.gz")
    assert main(["dataset", "build", "--n", "1", "--out", str(tmp_path / "x.h5"), "--labels",
                 str(tmp_path / "missing.gz")]) == 2
    assert main(["dataset", "labels", str(first), "--out", str(labels)]) == 2  # exists: --overwrite to replace
    assert main(["dataset", "labels", str(first), "--out", str(labels), "--overwrite"]) == 0


def test_a_texture_that_cannot_be_made_takes_a_label_only_if_its_labelled_run_could_not_make_it_either():
    from roughness.dataset.labels import Label
    from roughness.dataset.worker import Failed, Job, Restored, simulate_sample

    record = dict(expand(RECIPE, 1)[0], family="no-such-family")
    failed = Label("", {"status": "failed", "error": "InputError: no such family"})
    restored = simulate_sample(Job(record, failed), SMALL.as_dict())
    assert isinstance(restored, Restored) and restored.label is failed and restored.heights is None
    made = Label("0123456789abcdef", {"status": "ok"})  # labelled on a texture that was made: not this run's
    refused = simulate_sample(Job(record, made), SMALL.as_dict())
    assert isinstance(refused, Failed) and "no-such-family" in refused.error

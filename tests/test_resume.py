"""Resume as promised: an interrupted `compare` resumes with the same command (its manifest is written
before its first result); an interrupted `dataset build` says so in one line, exit 130, and its local
Dask workers neither see the Ctrl-C nor complain while they are closed."""
from __future__ import annotations

import logging
import signal
from pathlib import Path

import pytest

from roughness.cli import main
from roughness.cluster import local_cluster
from roughness.dataset import build
from roughness.dataset.reader import open_dataset
from roughness.dataset.recipe import Recipe
from roughness.engines import ClassicalEngine
from roughness.simulate.config import SimConfig

REPORT_FILES = ("compare.json", "table.csv", "table.md", "report.md")


def maps_folder(tmp_path: Path, n: int = 3) -> Path:
    from test_compare import maps_folder as random_maps

    return random_maps(tmp_path, n)


@pytest.fixture
def counted(monkeypatch):
    """The classical engines, counted, with a fixed time per result (so that reports compare byte for byte);
    ``interrupt_at`` makes that call (1-based) raise KeyboardInterrupt, as Ctrl-C would."""
    measure = ClassicalEngine.measure
    calls = {"n": 0, "interrupt_at": None}

    def fake(self, heightmap):
        calls["n"] += 1
        if calls["n"] == calls["interrupt_at"]:
            raise KeyboardInterrupt
        return measure(self, heightmap)[0], 0.001

    monkeypatch.setattr(ClassicalEngine, "measure", fake)
    return calls


def compare_args(folder: Path, out: Path, *engines: str) -> list[str]:
    return ["compare", str(folder), "--pixel-mm", "0.05", "--out", str(out), "--reference", "ra",
            "--engines", *(engines or ("p90",)), "--quiet"]


def test_an_interrupted_compare_resumes_with_the_same_command(tmp_path, counted, capsys):
    folder = maps_folder(tmp_path)
    whole, resumed = tmp_path / "whole", tmp_path / "resumed"
    assert main(compare_args(folder, whole)) == 0
    assert counted["n"] == 6  # 3 textures x (ra, p90)

    counted.update(n=0, interrupt_at=3)  # the first texture done (ra, p90), then Ctrl-C
    capsys.readouterr()
    assert main(compare_args(folder, resumed)) == 130
    err = capsys.readouterr().err
    assert "interrupted" in err and "run the same command again to resume" in err and "Traceback" not in err
    assert (resumed / "compare.json").read_text() == (whole / "compare.json").read_text()

    counted.update(n=0, interrupt_at=None)
    assert main(compare_args(folder, resumed)) == 0
    assert counted["n"] == 4  # the first texture's two results were reused, not recomputed
    for name in REPORT_FILES:
        assert (resumed / name).read_text() == (whole / name).read_text(), name


def test_another_comparison_in_an_interrupted_folder_is_refused(tmp_path, counted, capsys):
    folder = maps_folder(tmp_path)
    out = tmp_path / "o"
    counted["interrupt_at"] = 3
    assert main(compare_args(folder, out)) == 130
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()
    assert main(compare_args(folder, out, "glcm_sum_variance")) == 2
    assert "already exists; pass --overwrite" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    counted.update(n=0, interrupt_at=None)
    assert main([*compare_args(folder, out, "glcm_sum_variance"), "--overwrite"]) == 0
    assert counted["n"] == 5  # ra of the first texture reused (same content, same engine), the rest computed


def test_a_compare_interrupted_before_its_first_result_leaves_nothing(tmp_path, counted, capsys):
    folder = maps_folder(tmp_path)
    out = tmp_path / "o"
    counted["interrupt_at"] = 1
    assert main(compare_args(folder, out)) == 130
    assert not out.exists() or not any(out.iterdir())
    counted["interrupt_at"] = None
    assert main(compare_args(folder, out)) == 0


def fake_run(stop_after: int):
    """A stand-in for the Dask part of ``build``: records ``stop_after`` samples (as failures: no FEM),
    then Ctrl-C."""

    def run(writer, pending, config, workers, scheduler, counts, quiet):
        for job in pending[:stop_after]:
            writer.write_failure(job.texture_record, None, job.texture_record["pixel_mm"], "stand-in")
            counts["failed"] += 1
        raise KeyboardInterrupt

    return run


def test_an_interrupted_dataset_build_says_so_in_one_line(tmp_path, monkeypatch, capfd):
    out = tmp_path / "d.h5"
    args = ["dataset", "build", "--out", str(out), "--n", "5", "--fidelity", "coarse", "--quiet"]
    monkeypatch.setattr(build, "_run", fake_run(2))
    assert main(args) == 130
    assert capfd.readouterr().err.splitlines() == [
        f"roughness: interrupted; 2 of 5 samples written to {out}; run the same command again to resume"]
    monkeypatch.setattr(build, "_run", fake_run(1))
    assert main(args) == 130  # the same command resumes: the two written are kept, one more
    assert capfd.readouterr().err.splitlines() == [
        f"roughness: interrupted; 3 of 5 samples written to {out}; run the same command again to resume"]
    with open_dataset(out) as data:
        assert len(data) == 3


def test_local_workers_ignore_sigint_and_the_caller_keeps_its_handler():
    """A terminal's Ctrl-C reaches every process of its foreground group: the workers must leave it to the
    calling process (which closes them) instead of each dying with a traceback."""
    from dask.distributed import Client

    handler = signal.getsignal(signal.SIGINT)
    with local_cluster(1) as cluster, Client(cluster) as client:
        assert signal.getsignal(signal.SIGINT) is handler
        assert list(client.run(signal.getsignal, signal.SIGINT).values()) == [signal.SIG_IGN]


def test_workers_closed_mid_task_by_an_interrupt_are_quiet(tmp_path, monkeypatch, capfd):
    """Ctrl-C while the workers simulate: ``Interrupted`` with the counts, and no worker traceback or
    distributed warning about the tasks cancelled and the workers closed."""
    # A 6 mm block: a few tenths of a second per sample, so the workers are busy when the first one arrives.
    config = SimConfig(width_mm=6.0, window_mm=4.0, h_contact_mm=0.5, pairs=2000, force_n=3.6)
    recipe = Recipe(name="quiet", seed=7, families={"bumps": 1.0}, size_mm=7.0)

    def interrupt(*_):
        raise KeyboardInterrupt

    monkeypatch.setattr(build.Progress, "update", interrupt)
    level = logging.getLogger("distributed").level
    try:
        with pytest.raises(build.Interrupted) as stop:
            build.build(str(tmp_path / "q.h5"), 8, recipe, config, workers=2)
    finally:
        logging.getLogger("distributed").setLevel(level)
    assert stop.value.counts["written"] + stop.value.counts["failed"] == 1 and stop.value.stored == 1
    err = capfd.readouterr().err
    for noise in ("Traceback", "CancelledError", "still alive"):  # a busy worker is killed after a grace period
        assert noise not in err, err

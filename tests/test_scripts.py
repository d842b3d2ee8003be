"""Every benchmark and study script answers --help at once, without starting its run or writing."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted([*ROOT.glob("benchmarks/*.py"), *ROOT.glob("studies/*.py")])


def _results(folder: Path) -> dict[Path, int]:
    return {p: p.stat().st_mtime_ns for p in (folder / "results").rglob("*")}


def test_there_are_scripts():
    assert len(SCRIPTS) >= 5


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_help_does_not_run(script, tmp_path):
    before = _results(script.parent)
    out = subprocess.run([sys.executable, str(script), "--help"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=60, env=os.environ | {"PYTHONPATH": str(ROOT)})
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.startswith("usage:"), out.stdout[:500]
    assert _results(script.parent) == before  # nothing written


def _surrogate_report(monkeypatch):
    """benchmarks/surrogate_report.py as a module."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("surrogate_report", ROOT / "benchmarks" / "surrogate_report.py")
    report = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, report)  # its dataclass looks its module up
    spec.loader.exec_module(report)
    return report


def test_surrogate_report_counts_coverage_and_what_auto_catches(monkeypatch):
    """The report's arithmetic on a hand-made case: 2-sigma coverage in log(V + offset), auto's routing
    (out of domain, or spread above max_std) and the share of >15% errors it catches."""
    import numpy as np

    report = _surrogate_report(monkeypatch)
    offset = 0.001
    reference = np.array([0.10, 0.10, 0.10, 0.10])
    predicted = np.array([0.101, 0.13, 0.08, 0.10])  # errors 1%, 30%, 20%, 0%
    spread = np.array([0.05, 0.30, 0.02, 0.05])  # relative spread of V + offset
    p = {"id": np.array(["a", "b", "c", "d"]), "family": np.array(["x"] * 4), "reference": reference,
         "predicted": predicted, "relative_std": spread, "in_domain": np.array([True, True, True, False]),
         "log_offset": offset, "max_std": 0.1}
    out = report.uncertainty(p)
    z = np.abs(np.log(reference + offset) - np.log(predicted + offset)) / spread
    assert out["coverage_2sigma"] == np.mean(z <= 2) == 0.75  # c: 20% off with a 2% spread
    assert out["sent"] == 0.5 and out["sent_out_of_domain"] == 0.25  # b (uncertain) and d (outside)
    assert out["large_errors"] == 2 and out["large_errors_caught"] == 0.5  # b caught, c missed
    assert [w["id"] for w in report.worst(p, 2)] == ["b", "c"]
    caught = [r["large_errors_caught"] for r in report.routing(p, np.ones(4, bool), (0.01, 0.1, 1.0))]
    assert caught == [1.0, 0.5, 0.0]  # every spread above 0.01; b above 0.1; none above 1 (c is in domain)


def test_surrogate_report_break_even_pays_the_training_back_per_engine(monkeypatch):
    """Break-even textures = cost (core-hours) / (engine's seconds - surrogate's seconds); none if not faster."""
    report = _surrogate_report(monkeypatch)
    rows = {"surrogate": {"kind": "surrogate", "median_s": "0.001"}, "fem:fine": {"kind": "fem", "median_s": "10.001"},
            "spectral": {"kind": "spectral", "median_s": "0.0005"}, "ra": {"kind": "classical", "median_s": "0.001"}}
    out = {b["engine"]: b["textures"] for b in report.break_even(2.0, rows, "surrogate")}
    assert out.keys() == {"fem:fine", "spectral"}
    assert abs(out["fem:fine"] - 2.0 * 3600 / 10.0) < 1e-6 and out["spectral"] is None


def test_textured_objects_example_writes_only_where_told(tmp_path):
    """examples/textured_objects.py writes into a folder the user names (default: a new one under the current
    directory), never over the committed examples/objects/, and refuses a folder holding files without --overwrite."""
    script = ROOT / "examples" / "textured_objects.py"
    committed = {p: p.stat().st_mtime_ns for p in (ROOT / "examples" / "objects").iterdir()}
    out = subprocess.run([sys.executable, str(script), "--help"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0 and "textured-objects" in " ".join(out.stdout.split())
    (tmp_path / "textured-objects").mkdir()
    (tmp_path / "textured-objects" / "results.md").write_text("mine")
    out = subprocess.run([sys.executable, str(script), "--case", "knob"], cwd=tmp_path, capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 2 and "--overwrite" in out.stderr, out.stderr[-2000:]
    assert (tmp_path / "textured-objects" / "results.md").read_text() == "mine"
    assert {p: p.stat().st_mtime_ns for p in (ROOT / "examples" / "objects").iterdir()} == committed


def test_perception_example_writes_only_where_told(tmp_path):
    """examples/perception/run.sh needs its output folder, writes there (the stimuli table copied), and refuses
    existing outputs without --overwrite: the committed examples/perception/ is written only when named."""
    script = ROOT / "examples" / "perception" / "run.sh"
    committed = {p: p.stat().st_mtime_ns for p in (ROOT / "examples" / "perception").rglob("*")}
    env = os.environ | {"PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    out = subprocess.run(["sh", str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=60, env=env)
    assert out.returncode == 2 and "usage" in out.stderr
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "design.csv").write_text("mine")
    out = subprocess.run(["sh", str(script), "out"], cwd=tmp_path, capture_output=True, text=True, timeout=60, env=env)
    assert out.returncode != 0 and "--overwrite" in out.stderr, out.stderr[-2000:]
    assert (tmp_path / "out" / "design.csv").read_text() == "mine"
    assert (tmp_path / "out" / "stimuli.csv").read_bytes() == (ROOT / "examples" / "perception" / "stimuli.csv").read_bytes()
    assert {p: p.stat().st_mtime_ns for p in (ROOT / "examples" / "perception").rglob("*")} == committed

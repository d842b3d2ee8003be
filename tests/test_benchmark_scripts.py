"""The benchmark scripts of the surrogate and the trade report answer --help without running."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]


@pytest.mark.parametrize("script", ["surrogate_latency.py", "trade_report.py", "sensitivity.py"])
def test_help_does_not_run_the_benchmark(script):
    results = ROOT / "benchmarks" / "results"
    before = {p: p.stat().st_mtime_ns for p in results.rglob("*")}
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), "--help"], capture_output=True,
                         text=True, timeout=60, cwd=ROOT, env=os.environ | {"PYTHONPATH": str(ROOT)})
    assert out.returncode == 0 and out.stdout.startswith("usage:") and not out.stderr
    assert {p: p.stat().st_mtime_ns for p in results.rglob("*")} == before  # nothing written

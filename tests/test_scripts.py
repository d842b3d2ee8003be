"""Every benchmark and study script answers --help at once, without starting its run."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted([*ROOT.glob("benchmarks/*.py"), *ROOT.glob("studies/*.py")])


def test_there_are_scripts():
    assert len(SCRIPTS) >= 5


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_help_does_not_run(script, tmp_path):
    before = sorted(p.name for p in (script.parent / "results").glob("*")) if (script.parent / "results").exists() else []
    out = subprocess.run([sys.executable, str(script), "--help"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.startswith("usage:"), out.stdout[:500]
    after = sorted(p.name for p in (script.parent / "results").glob("*")) if (script.parent / "results").exists() else []
    assert after == before

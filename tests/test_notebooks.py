"""The example notebooks run from top to bottom without an error (issue 31: they never rot)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import nbclient
import nbformat

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
KERNEL = "roughness-notebook-test"


def _text(cell) -> str:
    """All text a code cell produced (streams and the plain-text form of results)."""
    parts = []
    for out in cell.get("outputs", []):
        parts.append(out.get("text", ""))
        parts.append(out.get("data", {}).get("text/plain", ""))
    return "".join(parts)


def _run(name: str, tmp_path: Path, monkeypatch) -> list:
    """Execute examples/notebooks/NAME in TMP_PATH with a kernel of this interpreter; its code cells."""
    spec = tmp_path / "jupyter" / "kernels" / KERNEL
    spec.mkdir(parents=True)
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": KERNEL, "language": "python"}))
    monkeypatch.setenv("JUPYTER_PATH", str(tmp_path / "jupyter"))
    monkeypatch.setenv("ROUGHNESS_EXAMPLES", str(EXAMPLES))
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    work = tmp_path / "work"
    work.mkdir()
    nb = nbformat.read(EXAMPLES / "notebooks" / name, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), "stored outputs: clear them"
    nbclient.NotebookClient(nb, timeout=120, kernel_name=KERNEL,
                            resources={"metadata": {"path": str(work)}}).execute()  # raises on a cell error
    cells = [c for c in nb.cells if c.cell_type == "code"]
    for c in cells:
        assert not [o for o in c.outputs if o.output_type == "error"], c.source
    assert list(work.iterdir()) == []  # the notebook writes nothing into its working folder
    return cells


def _figures(cells) -> int:
    return sum("image/png" in o.get("data", {}) for c in cells for o in c.outputs)


def test_predict_and_design_notebook(tmp_path, monkeypatch):
    cells = _run("predict_and_design.ipynb", tmp_path, monkeypatch)
    text = [_text(c) for c in cells]
    assert any("surrogate" in t and "V =" in t and t.startswith("Prediction(") for t in text), text
    assert any("spectral, in domain" in t and "V =" in t for t in text), text
    tuned = next(t for t in text if t.startswith("TuneResult("))
    assert "+1 JND from the input" in tuned and "reached" in tuned, tuned
    assert any(t.startswith("height x ") and "reached: True" in t for t in text), text
    assert _figures(cells) == 1  # the roughness map, shown inline from the returned Figure


def test_perception_analysis_notebook(tmp_path, monkeypatch):
    cells = _run("perception_analysis.ipynb", tmp_path, monkeypatch)
    text = "\n".join(_text(c) for c in cells)
    assert "standard-0.625" in text
    line = next(t for t in text.splitlines() if t.startswith("V "))
    r = float(line.split("=")[1])
    assert 0.8 < r <= 1.0, line  # V tracks the simulated subject's scale (its truth is the surrogate's V)
    assert _figures(cells) == 2  # embedding and fit, shown inline from the returned Figures

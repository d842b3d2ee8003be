"""predict --json's look (roughness.cli.predict_look): each texture's rendered look over its footprint and, with
--printer, the print's look beside the digital texture's."""
from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from roughness.cli import main
from roughness.design.look import RENDERING, LookDifference

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = [str(ROOT / "examples" / "standard-1.0mm.png"), "--pixel-mm", "0.05", "--height-mm", "1"]


def _predict(capsys, *args: str) -> dict:
    assert main(["predict", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _finite(look: dict) -> bool:
    return all(math.isfinite(v) for v in look.values() if isinstance(v, float))


def test_the_bundled_example_carries_its_look(capsys):
    look = _predict(capsys, *EXAMPLE)["look"]
    assert _finite(look) and look["window_mm"] == pytest.approx(10.0) and look["pixels"] == 200 * 200
    assert 0 < look["mean_luminance"] < np.sin(np.radians(45))  # flanks and shadows: darker than a flat plate
    assert look["luminance_contrast"] > 0
    assert look["definition"].startswith(RENDERING)  # the same words as a look difference's definition
    assert LookDifference(0.0, 0.0, 0.5, 0.5, (0.1,), (0.1,)).as_dict()["definition"].startswith(RENDERING)


def test_a_flat_map_looks_uniform_at_the_lights_sine(tmp_path, capsys):
    np.save(tmp_path / "flat.npy", np.zeros((150, 150)))
    look = _predict(capsys, str(tmp_path / "flat.npy"), "--pixel-mm", "0.1", "--units-ok")["look"]
    assert look["mean_luminance"] == pytest.approx(np.sin(np.radians(45)), rel=1e-12)
    assert look["luminance_contrast"] == pytest.approx(0.0, abs=1e-12) and look["pixels"] == 100 * 100


def test_with_a_printer_the_print_looks_different_from_the_digital_texture(capsys):
    plain = _predict(capsys, *EXAMPLE)["look"]
    out = _predict(capsys, *EXAMPLE, "--printer", "fdm-0.4-0.2")
    digital, printed, diff = out["digital"]["look"], out["look"], out["print_look_difference"]
    assert digital == plain  # the same heights, the same look
    assert _finite(printed) and _finite(diff) and diff.keys() == LookDifference(0, 0, 1, 1, (0.1,), (0.1,)).as_dict().keys()
    assert diff["mean_luminance_a"] == printed["mean_luminance"]  # the print (a) beside the digital texture (b)
    assert diff["mean_luminance_b"] == digital["mean_luminance"]
    # 0.2 mm layers turn the 1 mm bumps into terraces: flat treads and steep risers, far more contrast
    assert printed["luminance_contrast"] > 2 * digital["luminance_contrast"]
    assert diff["difference_look_jnd"] >= 1 and diff["verdict"] == "visible"


def test_the_text_output_is_unchanged(capsys):
    assert main(["predict", *EXAMPLE]) == 0
    [line] = capsys.readouterr().out.splitlines()
    assert " V = " in line and "luminance" not in line


def test_predict_json_imports_neither_torch_nor_scipy():
    """The look costs milliseconds, not the 0.3-0.6 s of importing scipy.ndimage or scipy.stats."""
    code = ("import sys; from roughness.cli import main; main(['predict', *sys.argv[1:], '--json']); "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('torch', 'scipy', 'matplotlib')))")
    out = subprocess.run([sys.executable, "-c", code, *EXAMPLE], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[-1] == "[]"


def test_an_input_the_engine_refuses_gets_the_engines_message(tmp_path, capsys):
    """The look is made after the answer: a map too coarse for the footprint is refused by the engine, as without
    --json, not by the renderer of a one-pixel footprint."""
    np.save(tmp_path / "coarse.npy", np.random.default_rng(0).random((3, 3)))
    assert main(["predict", str(tmp_path / "coarse.npy"), "--pixel-mm", "8", "--units-ok", "--json"]) == 2
    assert "footprint spans only 1.25 pixels" in capsys.readouterr().err

"""`roughness tune`: scale a texture to a target roughness; the surrogate searches, the coarse FEM verifies."""
from __future__ import annotations

import json

import numpy as np
import pytest

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.dataset.natural import grating
from roughness.dataset.textures import standard_texture
from roughness.design.evaluation import Evaluator
from roughness.design.tune import scaled, target_of, tune
from roughness.surface.io import save_heightmap

EVALUATOR = Evaluator()


def test_height_scaling_multiplies_the_relief():
    hm = standard_texture(1.0, seed=0)
    out = scaled(hm, "height", 0.5)
    assert np.ptp(out.heights) == pytest.approx(0.5 * np.ptp(hm.heights))
    assert out.heights.min() == pytest.approx(hm.heights.min()) and out.shape == hm.shape


def test_lateral_scaling_stretches_the_period():
    hm = grating(size_mm=12.0, pixel_mm=0.05, period_mm=1.0, profile="sine")  # 12 periods across the map
    out = scaled(hm, "lateral", 1.5)
    spectrum = np.abs(np.fft.rfft(out.heights[0] - out.heights[0].mean()))
    assert out.shape == hm.shape
    assert np.argmax(spectrum) == 8  # 12 mm / 1.5 mm


def test_scale_inverse_round_trips():
    scale = EVALUATOR.scale
    for lam in (0.5, 0.7, 1.0, 1.6, 2.0):  # on the scale and extrapolated beyond both ends
        assert scale.equivalent_lambda(scale.roughness_at(lam))[0] == pytest.approx(lam, rel=1e-9)


def test_texture_tuned_like_itself_keeps_its_scale():
    """Target: the FEM's V of the texture itself. The verified factor must be ~1 (0.1 JND is ~4% in height here)."""
    hm = standard_texture(1.0, seed=4)
    target = target_of(EVALUATOR, like=hm)
    result = tune(hm, target, "height", EVALUATOR)
    assert result.reached and abs(result.jnd_error) <= 0.1
    assert result.factor == pytest.approx(1.0, abs=0.06)
    assert len(result.steps) <= 4 and result.achieved.roughness == pytest.approx(target.roughness, rel=0.04)


def test_unreachable_target_is_refused_with_the_reachable_range():
    with pytest.raises(InputError, match=r"out of reach .* reaches V .*lambda"):
        tune(standard_texture(1.0, seed=0), target_of(EVALUATOR, lambda_mm=6.0), "height", EVALUATOR)
    with pytest.raises(InputError, match="exactly one target"):
        target_of(EVALUATOR, lambda_mm=1.0, roughness=0.1)


@pytest.fixture()
def texture(tmp_path):
    path = tmp_path / "t.npz"
    save_heightmap(standard_texture(1.0, seed=6), path)
    return path


def test_cli_reaches_the_target_and_writes_a_watertight_plate(texture, tmp_path, capsys):
    trimesh = pytest.importorskip("trimesh")
    out = tmp_path / "tuned.stl"
    code = main(["tune", str(texture), "--target-lambda", "0.8", "--out", str(out), "--base-mm", "1.5", "--json",
                 "--quiet"])
    summary = json.loads(capsys.readouterr().out)
    assert code == 0 and summary["reached"] and abs(summary["jnd_error"]) <= 0.1
    assert summary["factor"] < 1 and summary["achieved_lambda_mm"] == pytest.approx(0.8, rel=0.02)
    mesh = trimesh.load(out)
    assert mesh.is_watertight and mesh.bounds[0][2] == pytest.approx(0)
    relief = summary["factor"] * np.ptp(standard_texture(1.0, seed=6).heights)
    assert mesh.bounds[1][2] == pytest.approx(1.5 + relief, abs=1e-4)  # float32 STL coordinates


def test_cli_refuses_before_any_work(texture, tmp_path, capsys):
    out = tmp_path / "tuned.npz"
    out.write_bytes(b"precious")
    assert main(["tune", str(texture), "--target-lambda", "0.8", "--out", str(out)]) == 2
    assert "already exists" in capsys.readouterr().err and out.read_bytes() == b"precious"
    fresh = tmp_path / "fresh.npz"
    assert main(["tune", str(texture), "--target-lambda", "9", "--out", str(fresh)]) == 2
    err = capsys.readouterr().err
    assert "--target-lambda" in err and "reaches V" in err and not fresh.exists()
    assert main(["tune", str(texture), "--target-lambda", "1", "--target-v", "0.1", "--out", str(fresh)]) == 2
    assert main(["tune", str(texture), "--target-v", "0.1", "--out", str(fresh), "--min-factor", "2",
                 "--max-factor", "1"]) == 2
    assert "--min-factor" in capsys.readouterr().err and not fresh.exists()

"""Fuzzy skin settings tuned to a target feel (roughness.fuzzy_tune, ``roughness fuzzy-skin --tune``)."""
from __future__ import annotations

import json
import math

import pytest

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.fuzzy_feel import fuzzy_skin_feel
from roughness.fuzzy_palette import fuzzy_palette
from roughness.fuzzy_tune import (
    equivalent_lambda,
    lambda_target,
    mean_stderr_jnd,
    relative_target,
    tune_fuzzy_skin,
)
from roughness.perceptual_scale import jnd
from roughness.surface.fuzzy_skin import FuzzySkin
from roughness.surface.printing import PROFILES

FDM = PROFILES["fdm-0.4-0.2"]


def test_thickness_tuned_to_a_wavelength_holds_on_new_walls():
    result = tune_fuzzy_skin(FuzzySkin(0.3, 0.8), lambda_target(0.7), "thickness", FDM, draws=3)
    assert result.reached and abs(jnd(equivalent_lambda(result.feel), 0.7)) <= 0.1
    assert result.skin.fuzzy_skin_point_distance == 0.8 and 0.05 < result.value_mm < 0.3  # 0.3 mm is ~0.76 mm
    # walls of other seeds at the tuned setting: the target within the tolerance and 3 standard errors of both means
    check = fuzzy_skin_feel(result.skin, FDM, "spectral", seed=100, draws=6)
    margin = 0.1 + 3 * math.hypot(result.jnd_stderr, mean_stderr_jnd(check))
    assert abs(jnd(equivalent_lambda(check), 0.7)) <= margin
    assert 0 < result.jnd_stderr < result.draw_jnd  # the mean of 3 walls is surer than one wall


def test_relative_target_and_reach():
    given = fuzzy_skin_feel(FuzzySkin(0.3, 0.8), FDM, "spectral", draws=3)
    smoother = relative_target(given, -1.0)
    assert jnd(smoother.lambda_mm, equivalent_lambda(given)) == pytest.approx(-1.0)
    result = tune_fuzzy_skin(FuzzySkin(0.3, 0.8), smoother, "thickness", FDM, draws=3)
    assert result.reached and result.value_mm < 0.3
    with pytest.raises(InputError, match="out of reach by point-distance"):  # V peaks near 1 mm point distance
        tune_fuzzy_skin(FuzzySkin(0.3, 0.8), lambda_target(1.2), "point-distance", FDM, draws=2)
    with pytest.raises(InputError, match="must rise"):
        tune_fuzzy_skin(FuzzySkin(), lambda_target(0.8), "thickness", FDM, (0.5, 0.2))


def test_command(tmp_path, capsys):
    out = tmp_path / "tuned.npz"
    args = ["fuzzy-skin", "--tune", "thickness", "--target-lambda", "0.7", "--draws", "2", "--quiet", "--json",
            "--out", str(out)]
    assert main(args) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["reached"] and result["feel"]["seeds"] == [0, 1] and out.is_file()
    assert abs(result["jnd_error"]) <= 0.1 and result["jnd_stderr"] > 0
    for bad, message in ((["--target-lambda", "0.7"], "go with --tune"), (["--tune", "thickness"], "needs a target"),
                         (["--tune", "thickness", "--target-jnd", "1", "--engine", "fem"], "--engine"),
                         (["--tune", "thickness", "--target-jnd", "1", "--draws", "1"], "at least 2"),
                         (["--tune", "thickness", "--target-jnd", "1", "--tune-range", "0.1"], "two values")):
        assert main(["fuzzy-skin", *bad]) == 2
        assert message in capsys.readouterr().err


def test_palette_of_settings_two_jnd_apart(capsys):
    palette = fuzzy_palette(3, FuzzySkin(0.3, 0.8), "thickness", 2.0, FDM, (0.1, 0.9), draws=2)
    thickness = [m.value_mm for m in palette.members]
    assert thickness == sorted(thickness) and palette.verified and palette.closest_jnd >= 2.0
    lam = palette.lambdas_mm
    assert all(jnd(b, a) >= 2.0 for a, b in zip(lam, lam[1:]))  # each neighbour pair, from the verified means
    assert all(m.reached for m in palette.members)
    with pytest.raises(InputError, match="room for 3"):  # 0.1-0.9 mm spans ~5 JND: 3 fit at 2.2 JND planned
        fuzzy_palette(5, FuzzySkin(0.3, 0.8), "thickness", 2.0, FDM, (0.1, 0.9), draws=2)
    assert main(["fuzzy-skin", "--palette", "3", "--target-lambda", "0.8"]) == 2
    assert "--palette" in capsys.readouterr().err

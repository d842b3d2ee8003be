"""`roughness jnd`: distances in JNDs of the equivalent wavelength, with the uncertainty of the engine."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from roughness.cli import main
from roughness.dataset.textures import standard_texture
from roughness.perceptual_scale import StandardScale, jnd_distance, load_scale
from roughness.surface.io import save_heightmap

SCALE = StandardScale((0.5, 1.0, 2.0), (0.025, 0.1, 0.4), "test")  # V = 0.1 lambda^2 exactly
STEP = math.log(1.19)


def test_distance_counts_jnds_on_lambda():
    d = jnd_distance(SCALE, 0.1 * 1.19**6, 0.1)  # lambda 1.19^3 against 1: three JNDs
    assert d.jnd == pytest.approx(3.0) and d.jnd_stderr is None and d.verdict == "tell apart"
    assert jnd_distance(SCALE, 0.1, 0.1 * 1.19**6).jnd == pytest.approx(-3.0)
    assert jnd_distance(SCALE, 0.1 * 1.19, 0.1).verdict == "too close"  # 19% in V is half a JND


def test_standard_errors_propagate_through_the_power_law():
    v_a, v_b, se = 0.1 * 1.19**2, 0.1, 0.002
    d = jnd_distance(SCALE, v_a, v_b, se, se)
    expected = math.hypot(se / v_a, se / v_b) / 2 / STEP  # ln lambda = (ln V - ln 0.1) / 2
    assert d.jnd == pytest.approx(1.0) and d.jnd_stderr == pytest.approx(expected)
    assert d.verdict == "borderline"  # 1 JND +- 2 standard errors straddles the threshold
    rng = np.random.default_rng(0)  # Monte Carlo check of the propagation
    draws = [jnd_distance(SCALE, v_a + se * rng.standard_normal(), v_b + se * rng.standard_normal()).jnd
             for _ in range(4000)]
    assert np.std(draws) == pytest.approx(expected, rel=0.05)  # 4000 draws: ~1.1% sampling error of a SD


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    folder = tmp_path_factory.mktemp("jnd")
    for name, lam in (("a.npz", 0.75), ("b.npz", 1.25)):
        save_heightmap(standard_texture(lam, seed=3), folder / name)
    return folder / "a.npz", folder / "b.npz"


def test_cli_tells_distant_standard_textures_apart(pair, capsys):
    a, b = pair
    assert main(["jnd", str(a), str(b), "--engine", "surrogate", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # lambda 0.75 vs 1.25: ln(0.75 / 1.25) / ln 1.19 = -2.9 JND; the surrogate places them within 0.5 JND of that
    assert out["jnd"] == pytest.approx(math.log(0.75 / 1.25) / STEP, abs=0.5)
    assert out["verdict"] == "tell apart" and out["a"]["engine"] == "surrogate" and out["a"]["roughness_stderr"] is None
    # the shipped ensemble's spreads propagate like Monte Carlo errors: d ln(lambda) = d ln(V) / b, in JNDs
    se = [out[k]["roughness_std"] / out[k]["roughness"] for k in ("a", "b")]
    assert out["jnd_stderr"] == pytest.approx(math.hypot(*se) / load_scale("fine").power_law[1] / STEP, rel=1e-9)


def test_cli_same_texture_is_too_close(pair, capsys):
    a, _ = pair
    assert main(["jnd", str(a), str(a), "--engine", "surrogate"]) == 0
    out = capsys.readouterr().out
    assert "0.00 JND" in out and "equally rough: TOO CLOSE" in out and "(2 sigma: ensemble spread)" in out

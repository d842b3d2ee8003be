"""Curved bases: geometry of the textured base, FEM limits and refusals, detrending, predict routing."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.core.hashing import file_sha256
from roughness.dataset.textures import standard_texture
from roughness.simulate.config import SimConfig
from roughness.simulate.curved import BaseShape, normal_relief, textured_surface
from roughness.simulate.model import Simulator
from roughness.surface.detrend import detrend, parse_detrend
from roughness.surface.heightmap import Heightmap, flat


@pytest.fixture(scope="module")
def sim():
    return Simulator(SimConfig(fidelity="coarse"))


@pytest.fixture(scope="module")
def texture():
    return standard_texture(1.0, seed=0)


@pytest.fixture(scope="module")
def flat_result(sim, texture):
    return sim.run(texture, tile=True)


# Geometry (no FEM)

def test_normal_offset_puts_a_ridge_on_the_circle_of_radius_r_plus_h():
    """A 0.5 mm ridge at arc length 3 mm on a convex R = 10 mm cylinder: its top lies on radius R + h."""
    p, r, h = 0.01, 10.0, 0.5
    y = (np.arange(1400) + 0.5) * p - 7.0
    heights = np.where(np.abs(y - 3.0) < 0.3, h, 0.0)[:, None] * np.ones((1, 20))
    hm = Heightmap(heights, p)
    shape = BaseShape("cylinder", r, "x")
    angle = 3.0 / r
    top_y = (r + h) * math.sin(angle)
    qy = np.array([0.0, top_y - 0.05, top_y, top_y + 0.05])  # a valley (on the base) and the ridge's top
    z = normal_relief(hm, hm.centre_mm, shape, np.zeros(4), qy, False)
    # The valley lies on the base; the ridge's top on the circle of radius R + h (up to the linear tracing).
    expected = np.sqrt(np.array([r, r + h, r + h, r + h]) ** 2 - qy**2) - r
    np.testing.assert_allclose(z, expected, atol=1e-4)
    # Along z the same ridge would sit at y = 3 mm, not at (R + h) sin(3/R) = 3.1 mm: the two choices differ.
    assert top_y - 3.0 > 0.1


def test_huge_radius_is_the_flat_texture_and_concave_radius_bounds(texture):
    x = np.linspace(-4, 4, 9)
    flat_surface = texture.sample(texture.centre_mm[0] + x, texture.centre_mm[1] + x) - texture.heights.min()
    for along in ("normal", "z"):
        surface, z0 = textured_surface(texture, texture.centre_mm, BaseShape("sphere", 1e6, "x"), along, 10.0, True)
        np.testing.assert_allclose(surface(x, x) + z0, flat_surface, atol=1e-4)  # sag of 1e6 mm over 8 mm: 3e-5 mm
    with pytest.raises(InputError, match="narrower than the 10 mm skin footprint") as err:
        SimConfig(curvature_mm=-5.0)
    assert err.value.parameter == "curvature_mm"
    with pytest.raises(InputError, match="sphere of radius 7 mm"):
        SimConfig(curvature_mm=-7.0, base="sphere")  # its corners lie 7.07 mm out
    SimConfig(curvature_mm=-7.0)  # a cylinder of the same radius holds the footprint
    with pytest.raises(InputError, match="0 is not a radius"):
        SimConfig(curvature_mm=0.0)


def test_normal_heights_need_the_unrolled_texture(texture):
    small = Heightmap(texture.heights[:200, :200], texture.pixel_mm)  # 10 mm: exactly the footprint
    with pytest.raises(InputError, match="pass tile=True") as err:
        textured_surface(small, small.centre_mm, BaseShape("cylinder", 10.0, "x"), "normal", 10.0, False)
    assert err.value.parameter == "curvature_mm" and "--" not in str(err.value)
    textured_surface(small, small.centre_mm, BaseShape("cylinder", 10.0, "x"), "z", 10.0, False)


# FEM at coarse fidelity

def test_large_radius_tends_to_the_flat_value(sim, texture, flat_result):
    for radius in (1000.0, -1000.0):
        curved = sim.run(texture, tile=True, curvature_mm=radius)
        assert curved.converged
        assert abs(curved.roughness / flat_result.roughness - 1) < 0.01, radius


def test_untextured_curved_base_is_at_noise_level_and_base_field_is_cached(sim, flat_result):
    smooth = flat(12.0, 0.05, height_mm=3.0)
    block = sim.block(sim.config.resolved(smooth))
    for radius, base in ((8.0, "cylinder"), (-12.0, "sphere")):
        before = len(block._base)
        r = sim.run(smooth, curvature_mm=radius, base=base, texture_along="normal")
        assert r.converged and r.roughness < 0.01 * flat_result.roughness, (radius, base)
        assert len(block._base) == before + 1  # one untextured field per base shape ...
        again = sim.run(smooth, curvature_mm=radius, base=base, texture_along="z")
        assert len(block._base) == before + 1  # ... shared by both ways of laying the texture on it
        assert again.roughness < 0.01 * flat_result.roughness


def test_convex_and_concave_bases_report_their_contact(sim, texture, flat_result):
    convex = sim.run(texture, tile=True, curvature_mm=4.0)
    concave = sim.run(texture, tile=True, curvature_mm=-8.0)
    for r in (convex, concave):
        assert r.converged and math.isfinite(r.roughness) and r.roughness > 0
        assert r.summary()["contact_fraction"] == r.contact_fraction
    # A 4 mm convex cylinder under a 10 mm footprint: the skin hangs free beyond its flanks.
    assert convex.contact_fraction < 0.8 * flat_result.contact_fraction
    # In a concave trough the skin is pushed deeper for the same force: it rests on the rims first.
    assert concave.indentation_mm > flat_result.indentation_mm


@pytest.mark.parametrize("args, message", [
    (["--curvature-mm", "0"], "--curvature-mm"),
    (["--curvature-mm", "-4"], "narrower than the 10 mm skin footprint"),
    (["--curvature-mm", "-6", "--base", "sphere"], "narrower than the 10 mm skin footprint"),
    (["--curvature-mm", "nan"], "--curvature-mm"),
    (["--curvature-mm", "5", "--base", "cone"], "--base"),
    (["--detrend", "lowpass:-1"], "--detrend"),
    (["--detrend", "highpass"], "--detrend"),
])
def test_bad_curvature_values_exit_2(tmp_path, capsys, args, message):
    path = tmp_path / "map.npy"
    np.save(path, np.zeros((240, 240)))
    try:
        code = main(["simulate", str(path), "--pixel-mm", "0.05", "--fidelity", "coarse", "--quiet", *args])
    except SystemExit as stop:  # argparse's own refusals
        code = stop.code
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


# Shape and texture of one height map

def _on_cylinder(hm: Heightmap, radius: float) -> Heightmap:
    """The texture draped along z on a cylinder straight along x (a scan of a curved object)."""
    y = (np.arange(hm.shape[0]) + 0.5) * hm.pixel_mm - hm.size_mm[1] / 2
    base = BaseShape("cylinder", radius, "x").height(np.zeros_like(y), y)
    return Heightmap(hm.heights + base[:, None], hm.pixel_mm)


def test_detrend_recovers_the_flat_texture(sim):
    hm = standard_texture(1.0, seed=3)
    reference = sim.run(hm)
    texture, separation = detrend(hm)
    assert separation.chosen and 1.0 < separation.texture_wavelength_mm < 1.5  # the spectral peak of lambda 1 mm
    unchanged = sim.run(texture)
    assert abs(unchanged.roughness / reference.roughness - 1) < 0.01  # a flat texture: (almost) nothing removed
    fine = standard_texture(0.75, seed=4)  # changed by 1.6% with the earlier cut-off of 8 wavelengths
    assert abs(sim.run(detrend(fine)[0]).roughness / sim.run(fine).roughness - 1) < 0.01
    for radius in (15.0, -15.0):
        scanned = _on_cylinder(hm, radius)
        recovered, separation = detrend(scanned)
        assert separation.shape_relief_mm > 1.0  # a 12 mm scan of a 15 mm cylinder sags 1.25 mm
        assert np.abs(recovered.heights - texture.heights).max() < 0.02  # the same texture as from the flat map
        assert abs(sim.run(recovered).roughness / reference.roughness - 1) < 0.05, radius


def test_detrend_spec_parsing():
    assert parse_detrend("lowpass").cutoff_mm is None
    assert parse_detrend("lowpass:2.5").cutoff_mm == 2.5
    for bad in ("lowpass:0", "lowpass:x", "lowpass:inf", "band"):
        with pytest.raises(InputError):
            parse_detrend(bad)


# The flat-trained surrogate on curved bases

def test_shipped_curvature_range_comes_from_the_committed_study():
    from roughness.prediction import CURVATURE_RANGE_PATH

    data = json.loads(CURVATURE_RANGE_PATH.read_text())
    assert "cylinder" in data["bases"]
    for base, entry in data["bases"].items():
        results = Path(__file__).resolve().parents[1] / entry["provenance"]["results"]
        assert file_sha256(results) == entry["provenance"]["results_sha256"], base
        study = json.loads(results.read_text())
        assert study["base"] == base and study["tolerance"] == data["tolerance"]
        assert study["limits"] == {k: entry[k] for k in ("min_convex_radius_mm", "min_concave_radius_mm")}


def test_predict_routes_curved_bases_by_the_range(tmp_path, monkeypatch):
    from roughness import curvature_correction as correction
    from roughness import prediction
    from roughness.prediction import CurvedBase, PredictOptions, predict

    def on(radius_mm: float, shape: str = "cylinder", tile: bool = False) -> PredictOptions:
        return PredictOptions(tile=tile, curved=CurvedBase(radius_mm, shape))

    path = tmp_path / "range.json"
    path.write_text(json.dumps({"tolerance": 0.19, "bases": {
        "cylinder": {"min_convex_radius_mm": 10.0, "min_concave_radius_mm": 20.0}}}))
    monkeypatch.setattr(prediction, "CURVATURE_RANGE_PATH", path)
    hm = standard_texture(1.0, seed=0)
    [flat_answer] = predict(hm, engine="surrogate")
    [inside] = predict(hm, engine="surrogate", options=on(40.0))
    # inside the range the flat answer is corrected by the study's measurement (roughness.curvature_correction)
    fix = correction.for_base(40.0, "cylinder")
    assert inside.engine == "surrogate" and inside.roughness == pytest.approx(flat_answer.roughness * fix.factor)
    assert inside.domain_notes == flat_answer.domain_notes + [fix.note] and inside.in_domain
    for radius, base in ((5.0, "cylinder"), (-15.0, "cylinder"), (40.0, "sphere")):
        [outside] = predict(hm, engine="surrogate", options=on(radius, base))
        assert outside.engine == "surrogate" and not outside.in_domain
        assert any(n.startswith("curved base") for n in outside.domain_notes), (radius, base)
    with pytest.raises(InputError, match="narrower"):
        predict(hm, engine="surrogate", options=on(-4.0))


@pytest.mark.slow  # a curved FEM solve, about 3 min on 2 cores
def test_auto_runs_the_curved_fem_outside_the_range(tmp_path, monkeypatch):
    from roughness import prediction
    from roughness.prediction import CurvedBase, PredictOptions, predict

    path = tmp_path / "range.json"
    path.write_text(json.dumps({"tolerance": 0.19, "bases": {
        "cylinder": {"min_convex_radius_mm": 10.0, "min_concave_radius_mm": 20.0}}}))
    monkeypatch.setattr(prediction, "CURVATURE_RANGE_PATH", path)
    options = PredictOptions(tile=True, curved=CurvedBase(5.0, "cylinder"))
    [fem] = predict(standard_texture(1.0, seed=0), engine="auto", options=options)  # outside: the curved FEM
    assert fem.engine == "fem" and not fem.in_domain and fem.roughness > 0
    assert any(n.startswith("curved base") for n in fem.domain_notes)


def test_simulate_cli_on_a_curved_base(tmp_path, capsys):
    path = tmp_path / "scan.npy"
    np.save(path, _on_cylinder(standard_texture(1.0, seed=0), -15.0).heights)
    code = main(["simulate", str(path), "--pixel-mm", "0.05", "--fidelity", "coarse", "--json",
                 "--detrend", "lowpass", "--curvature-mm", "20", "--base", "sphere", "--texture-along", "z"])
    assert code == 0
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert out["converged"] and 0 < out["roughness"] < 1 and 0 < out["contact_fraction"] <= 1
    assert "convex sphere of radius 20 mm" in captured.err and "removed the shape" in captured.err


def test_flat_records_are_unchanged_and_curved_ones_round_trip():
    flat_config = SimConfig(fidelity="coarse")
    assert not set(flat_config.as_dict()) & {"curvature_mm", "base", "curvature_axis", "texture_along"}
    assert SimConfig(**flat_config.as_dict()) == flat_config
    curved = SimConfig(fidelity="coarse", curvature_mm=-12.0, base="sphere", texture_along="z")
    assert curved.as_dict()["curvature_mm"] == -12.0 and SimConfig(**curved.as_dict()) == curved

"""Printing/scanning perturbations: neutral identities, geometry, spectra, pipelines, JSON and validation."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import ndimage

from roughness.core.errors import InputError
from roughness.dataset.natural import dots, grains, grating
from roughness.dataset.perturb import (
    LAYER_MM,
    RANDOM_ORDER,
    RANDOM_RANGES,
    Perturbation,
    Pipeline,
    blur,
    height_scale,
    inflate,
    lateral_scale,
    noise,
    quantise,
    random_pipeline,
    rotate,
    shift,
)
from roughness.surface.heightmap import Heightmap

GRAINS = grains(size_mm=6.0, seed=1)
RNG = np.random.default_rng(0)


def spectral_direction_deg(hm: Heightmap) -> float:
    """Direction (degrees in [0, 180)) of the strongest non-constant Fourier component."""
    power = np.abs(np.fft.fft2(hm.heights - hm.heights.mean())) ** 2
    i, j = np.unravel_index(np.argmax(power), power.shape)
    fy, fx = np.fft.fftfreq(hm.shape[0])[i], np.fft.fftfreq(hm.shape[1])[j]
    return float(np.degrees(np.arctan2(fy, fx)) % 180)


def angle_gap_deg(a: float, b: float) -> float:
    """Distance (degrees) between two undirected directions."""
    return abs((a - b + 90) % 180 - 90)


def plateau_diameter_mm(hm: Heightmap) -> float:
    """Median equivalent-circle diameter (mm) of the regions above half the maximum height."""
    labels, count = ndimage.label(hm.heights > hm.heights.max() / 2)
    areas = ndimage.sum_labels(np.ones_like(hm.heights), labels, np.arange(1, count + 1)) * hm.pixel_mm**2
    return float(np.median(2 * np.sqrt(areas / np.pi)))


@pytest.mark.parametrize("step", [
    blur(0.0), inflate(0.0), inflate(0.01), height_scale(1.0), lateral_scale(1.0), rotate(0.0), rotate(360.0),
    shift(0.0, 0.0), shift(6.0, -12.0), noise(0.0, 0.1),
], ids=lambda step: f"{step.name}{tuple(step.params.values())}")
def test_neutral_parameters_are_the_identity(step):
    out = step.apply(GRAINS, RNG)
    assert out.pixel_mm == GRAINS.pixel_mm
    np.testing.assert_array_equal(out.heights, GRAINS.heights)


def test_quantise_gives_whole_layers_within_half_a_layer():
    for step_mm in (LAYER_MM, 0.05):
        out = quantise(step_mm).apply(GRAINS, RNG).heights
        layers = out / step_mm
        np.testing.assert_allclose(layers, np.round(layers), atol=1e-9)
        assert np.abs(out - GRAINS.heights).max() <= step_mm / 2 + 1e-12
        assert len(np.unique(np.round(layers))) > 5
    assert quantise().params == {"step_mm": 0.03}


@pytest.mark.parametrize("factor", [0.7, 1.3])
def test_height_scale_scales_the_range(factor):
    out = height_scale(factor).apply(GRAINS, RNG).heights
    assert np.ptp(out) == pytest.approx(factor * np.ptp(GRAINS.heights))
    np.testing.assert_allclose(out, factor * GRAINS.heights)


@pytest.mark.parametrize("angle_deg", [90.0, 30.0, -45.0])
def test_rotation_moves_the_grating_spectrum(angle_deg):
    hm = grating(period_mm=1.0, profile="sine", angle_deg=0.0)
    assert angle_gap_deg(spectral_direction_deg(hm), 0.0) < 1e-9
    assert angle_gap_deg(spectral_direction_deg(rotate(angle_deg).apply(hm, RNG)), angle_deg) < 3.0


def test_quarter_turn_is_exact_and_counter_clockwise():
    spike = np.zeros((8, 8))
    spike[3, 7] = 1.0  # on the +x side of the centre (row and column 3.5)
    out = rotate(90.0).apply(Heightmap(spike, 0.5), RNG).heights
    expected = np.zeros((8, 8))
    expected[7, 4] = 1.0  # moved to the +y side
    np.testing.assert_array_equal(out, expected)


def test_shift_is_exact_for_whole_pixels_and_periodic():
    p = GRAINS.pixel_mm
    out = shift(3 * p, -5 * p).apply(GRAINS, RNG)
    np.testing.assert_array_equal(out.heights, np.roll(GRAINS.heights, (-5, 3), axis=(0, 1)))
    width, height = GRAINS.size_mm
    fractional = shift(0.123, 0.456).apply(GRAINS, RNG).heights
    wrapped = shift(0.123 + 2 * width, 0.456 - height).apply(GRAINS, RNG).heights
    np.testing.assert_allclose(wrapped, fractional, atol=1e-12)
    there_and_back = shift(-0.123, 0.0).apply(shift(0.123, 0.0).apply(GRAINS, RNG), RNG)
    assert 0 < np.abs(there_and_back.heights - GRAINS.heights).mean() < 0.02  # bilinear: slightly smoothed


@pytest.mark.parametrize("factor", [0.85, 1.2])
def test_lateral_scale_stretches_features_and_keeps_the_grid(factor):
    hm = grating(period_mm=1.0, profile="sine")
    out = lateral_scale(factor).apply(hm, RNG)
    assert out.shape == hm.shape and out.pixel_mm == hm.pixel_mm
    assert out.feature_size_mm() == pytest.approx(factor, rel=0.05)


def test_inflate_grows_and_erosion_shrinks_flat_dots():
    hm = dots(pitch_mm=1.5, diameter_mm=0.6, shape="flat", height_mm=0.5)
    assert plateau_diameter_mm(hm) == pytest.approx(0.6, abs=0.03)
    assert plateau_diameter_mm(inflate(0.1).apply(hm, RNG)) == pytest.approx(0.8, abs=0.04)
    assert plateau_diameter_mm(inflate(-0.1).apply(hm, RNG)) == pytest.approx(0.4, abs=0.04)
    assert inflate(0.1).apply(hm, RNG).heights.max() == hm.heights.max()


def test_blur_rounds_edges_and_keeps_the_mean():
    hm = grating(period_mm=1.0, profile="square")
    out = blur(0.1).apply(hm, RNG)
    assert out.heights.mean() == pytest.approx(hm.heights.mean())
    assert np.abs(np.diff(out.heights, axis=1)).max() < 0.5 * np.abs(np.diff(hm.heights, axis=1)).max()
    assert out.heights.min() >= 0


@pytest.mark.parametrize("rms_mm,correlation_mm", [(0.02, 0.0), (0.01, 0.2)])
def test_noise_has_the_requested_rms_and_keeps_heights_non_negative(rms_mm, correlation_mm):
    flat = Heightmap(np.zeros((120, 120)), 0.05)
    out = noise(rms_mm, correlation_mm).apply(flat, np.random.default_rng(3))
    assert out.heights.min() == 0.0
    assert out.heights.std() == pytest.approx(rms_mm)
    if correlation_mm:
        assert out.feature_size_mm() > 4 * noise(rms_mm).apply(flat, np.random.default_rng(3)).feature_size_mm()


def test_every_step_keeps_heights_non_negative():
    for seed in range(12):
        hm = GRAINS
        rng = np.random.default_rng(seed)
        for step in random_pipeline(seed, max_steps=8).steps:
            hm = step.apply(hm, rng)
            assert hm.heights.min() >= 0 and hm.shape == GRAINS.shape, step


def test_pipeline_json_round_trip_reproduces_the_heightmap():
    pipeline = Pipeline([lateral_scale(1.1), rotate(33.0), shift(0.3, -1.2), inflate(0.04), blur(0.05),
                         quantise(), noise(0.01, 0.05)])
    text = pipeline.to_json()
    assert json.loads(text)[0] == {"name": "lateral_scale", "params": {"factor": 1.1}}
    restored = Pipeline.from_json(text)
    assert restored == pipeline
    np.testing.assert_array_equal(restored.apply(GRAINS, seed=7).heights, pipeline.apply(GRAINS, seed=7).heights)
    assert not np.array_equal(pipeline.apply(GRAINS, seed=8).heights, pipeline.apply(GRAINS, seed=7).heights)
    np.testing.assert_array_equal(Pipeline.from_json("[]").apply(GRAINS, seed=0).heights, GRAINS.heights)


def test_perturbation_dict_round_trip():
    step = shift(1, 2)
    assert step.to_dict() == {"name": "shift", "params": {"dx_mm": 1.0, "dy_mm": 2.0}}
    assert Perturbation.from_dict(json.loads(json.dumps(step.to_dict()))) == step


def test_random_pipeline_is_deterministic_per_seed():
    assert random_pipeline(np.random.default_rng(5)).to_json() == random_pipeline(np.random.default_rng(5)).to_json()
    assert len({random_pipeline(seed).to_json() for seed in range(10)}) > 5
    a = random_pipeline(11).apply(GRAINS, seed=2)
    np.testing.assert_array_equal(a.heights, random_pipeline(11).apply(GRAINS, seed=2).heights)


def test_random_pipeline_respects_its_ranges_order_and_budget():
    rng = np.random.default_rng(0)
    pipelines = [random_pipeline(rng, max_steps=3) for _ in range(300)]
    with_quantise = 0
    for pipeline in pipelines:
        names = [step.name for step in pipeline.steps]
        assert len(names) <= 3 and len(set(names)) == len(names)
        assert names == sorted(names, key=RANDOM_ORDER.index)
        with_quantise += "quantise" in names
        for step in pipeline.steps:
            if step.name == "quantise":
                assert step.params == {"step_mm": LAYER_MM}
                continue
            for key, (low, high) in RANDOM_RANGES[step.name].items():
                assert low <= step.params[key] <= high
    assert 0.4 < with_quantise / len(pipelines) < 0.6
    assert {step.name for p in pipelines for step in p.steps} == set(RANDOM_ORDER)
    assert random_pipeline(rng, max_steps=0) == Pipeline()


@pytest.mark.parametrize("call,message", [
    (lambda: blur(-0.1), "blur parameter sigma_mm must be >= 0, got -0.1"),
    (lambda: height_scale(0), "height_scale parameter factor must be a positive finite number, got 0"),
    (lambda: lateral_scale(-1.0), "lateral_scale parameter factor must be a positive finite number"),
    (lambda: rotate(math.inf), "rotate parameter angle_deg must be a finite number, got inf"),
    (lambda: shift(float("nan"), 0.0), "shift parameter dx_mm must be a finite number, got nan"),
    (lambda: noise(0.01, -1.0), "noise parameter correlation_mm must be >= 0"),
    (lambda: quantise(0.0), "quantise parameter step_mm must be a positive finite number"),
    (lambda: inflate("0.1"), "inflate parameter radius_mm must be a finite number, got '0.1'"),
    (lambda: Perturbation("melt", {}), "unknown perturbation 'melt'; valid perturbations: blur, inflate"),
    (lambda: Perturbation("blur", {"sigma": 1.0}), "blur takes parameters sigma_mm, got sigma"),
    (lambda: Perturbation.from_dict({"name": "blur"}), 'needs exactly "name" and a "params" object'),
    (lambda: Pipeline.from_json("[{"), "pipeline JSON is malformed"),
    (lambda: Pipeline.from_json('{"steps": []}'), "pipeline JSON must be a list of perturbations, got dict"),
    (lambda: Pipeline(["blur"]), "pipeline steps must be Perturbations, got 'blur'"),
    (lambda: random_pipeline(0, max_steps=-1), "max_steps must be an integer >= 0, got -1"),
])
def test_bad_parameters_name_the_problem(call, message):
    with pytest.raises(InputError) as error:
        call()
    assert message in str(error.value)

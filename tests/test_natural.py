"""Natural-like texture families: determinism, units, feature scales, spectra, lattices and validation."""
from __future__ import annotations

import inspect
import time

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial import cKDTree

from roughness.core.errors import InputError
from roughness.dataset.families import make
from roughness.dataset.natural import FAMILIES, PARAMETER_RANGES, grains, grating

SMALL = {"size_mm": 6.0, "pixel_mm": 0.05}
GRID_ARGS = ("size_mm", "pixel_mm", "seed")


def family_params(family: str) -> dict[str, inspect.Parameter]:
    """The family's texture parameters (its signature without the grid and seed)."""
    parameters = inspect.signature(FAMILIES[family]).parameters
    return {name: p for name, p in parameters.items() if name not in GRID_ARGS}


def spectral_peak(heights: np.ndarray, pixel_mm: float) -> tuple[float, float]:
    """Wavelength (mm) and direction (degrees in [0, 180)) of the strongest non-constant Fourier component."""
    power = np.abs(np.fft.fft2(heights - heights.mean())) ** 2
    i, j = np.unravel_index(np.argmax(power), power.shape)
    fy = np.fft.fftfreq(heights.shape[0], pixel_mm)[i]
    fx = np.fft.fftfreq(heights.shape[1], pixel_mm)[j]
    return 1 / np.hypot(fx, fy), float(np.degrees(np.arctan2(fy, fx)) % 180)


def angle_gap_deg(a: float, b: float) -> float:
    """Distance (degrees) between two undirected directions."""
    return abs((a - b + 90) % 180 - 90)


def corner_params(family: str, corner: int) -> dict:
    """Numeric parameters at their low (even corner) or high (odd corner) bound; choices cycled."""
    return {name: allowed[corner % len(allowed)] if isinstance(allowed[0], str) else allowed[corner % 2]
            for name, allowed in PARAMETER_RANGES[family].items()}


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_deterministic_per_seed_and_different_across_seeds(family):
    a, b = make(family, seed=3, **SMALL), make(family, seed=3, **SMALL)
    np.testing.assert_array_equal(a.heights, b.heights)
    assert not np.allclose(a.heights, make(family, seed=4, **SMALL).heights)


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_units_and_height_range(family):
    hm = make(family, size_mm=5.0, pixel_mm=0.04)
    assert hm.shape == (125, 125) and hm.pixel_mm == 0.04 and hm.size_mm == pytest.approx((5.0, 5.0))
    h = hm.heights
    assert np.all(np.isfinite(h)) and h.min() == 0.0
    defaults = {name: p.default for name, p in family_params(family).items()}
    if family == "fbm":
        assert h.std() == pytest.approx(defaults["rms_mm"])
    else:
        assert 0.8 * defaults["height_mm"] <= h.max() <= defaults["height_mm"] + 1e-12


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_defaults_are_the_documented_parameters_and_lie_in_range(family):
    params = family_params(family)
    assert list(params) == list(PARAMETER_RANGES[family])
    for name, allowed in PARAMETER_RANGES[family].items():
        default = params[name].default
        assert default in allowed if isinstance(allowed[0], str) else allowed[0] <= default <= allowed[1]


@pytest.mark.parametrize("family", sorted(FAMILIES))
@pytest.mark.parametrize("corner", [0, 1, 2])
def test_whole_parameter_range_gives_valid_maps(family, corner):
    params = corner_params(family, corner)
    hm = make(family, seed=corner, **SMALL, **params)
    assert np.all(np.isfinite(hm.heights)) and hm.heights.min() == 0.0
    assert hm.heights.max() <= params.get("height_mm", np.inf) + 1e-12
    assert hm.heights.max() > 0


def test_every_family_is_fast():
    for family in FAMILIES:
        start = time.perf_counter()
        assert make(family).shape == (240, 240)
        assert time.perf_counter() - start < 0.5, family


@pytest.mark.parametrize("period_mm", [0.7, 1.0, 2.3])
@pytest.mark.parametrize("angle_deg", [0.0, 37.0])
def test_sine_grating_feature_size_is_its_period(period_mm, angle_deg):
    hm = grating(period_mm=period_mm, profile="sine", angle_deg=angle_deg)
    assert hm.feature_size_mm() == pytest.approx(period_mm, rel=0.05)


@pytest.mark.parametrize("profile", ["sine", "square", "triangle"])
@pytest.mark.parametrize("period_mm", [0.75, 1.2, 2.0])
def test_grating_dominant_wavelength_is_its_period(profile, period_mm):
    hm = grating(period_mm=period_mm, profile=profile, duty=0.4)
    wavelength, direction = spectral_peak(hm.heights, hm.pixel_mm)
    assert wavelength == pytest.approx(period_mm, rel=0.05)
    assert angle_gap_deg(direction, 0.0) < 1e-9


@pytest.mark.parametrize("angle_deg", [0.0, 30.0, 45.0, 60.0, 120.0, 150.0])
def test_grating_spectrum_peaks_at_its_angle(angle_deg):
    hm = grating(period_mm=1.0, profile="sine", angle_deg=angle_deg)
    assert angle_gap_deg(spectral_peak(hm.heights, hm.pixel_mm)[1], angle_deg) < 3.0


def test_grating_duty_sets_the_ridge_fraction():
    for duty in (0.2, 0.5, 0.8):
        hm = grating(period_mm=1.2, duty=duty, profile="square")
        assert np.mean(hm.heights > hm.heights.max() / 2) == pytest.approx(duty, abs=0.01)


@pytest.mark.parametrize("lattice,pitch_mm", [("square", 0.8), ("square", 1.5), ("hex", 0.8), ("hex", 1.5)])
def test_dots_lattice_pitch_and_density(lattice, pitch_mm):
    hm = make("dots", pitch_mm=pitch_mm, diameter_mm=0.4, shape="flat", lattice=lattice, seed=2)
    labels, count = ndimage.label(hm.heights > 0)
    centres = np.array(ndimage.center_of_mass(hm.heights, labels, np.arange(1, count + 1)))
    spacing = cKDTree(centres).query(centres, k=2)[0][:, 1] * hm.pixel_mm
    assert np.median(spacing) == pytest.approx(pitch_mm, rel=0.05)
    cell_area = pitch_mm**2 * (np.sqrt(3) / 2 if lattice == "hex" else 1.0)
    full = np.array([ndimage.sum_labels(hm.heights > 0, labels, k) for k in range(1, count + 1)])
    whole_dots = np.sum(full >= 0.9 * full.max())
    assert whole_dots == pytest.approx(12.0**2 / cell_area, rel=0.05)


def test_dot_diameter_and_jitter():
    hm = make("dots", pitch_mm=1.0, diameter_mm=0.6, shape="flat")
    labels, count = ndimage.label(hm.heights > hm.heights.max() / 2)
    areas = ndimage.sum_labels(np.ones_like(hm.heights), labels, np.arange(1, count + 1)) * hm.pixel_mm**2
    assert np.median(2 * np.sqrt(areas / np.pi)) == pytest.approx(0.6, rel=0.05)
    jittered = make("dots", pitch_mm=1.0, diameter_mm=0.6, shape="flat", jitter_mm=0.2)
    assert not np.array_equal(hm.heights, jittered.heights)


@pytest.mark.parametrize("cell_mm", [0.75, 1.5, 2.4])
def test_cellular_has_one_dome_per_cell_of_the_requested_size(cell_mm):
    h = make("cellular", cell_mm=cell_mm, seed=1).heights
    neighbours = np.ones((3, 3), dtype=bool)
    neighbours[1, 1] = False
    peaks = np.sum(h > ndimage.maximum_filter(h, footprint=neighbours, mode="wrap"))
    assert peaks == pytest.approx((12.0 / cell_mm) ** 2, rel=0.03)


@pytest.mark.parametrize("family,small,large", [
    ("cellular", {"cell_mm": 0.8}, {"cell_mm": 1.6}),
    ("cellular", {"cell_mm": 0.8, "profile": "wall", "wall_mm": 0.15},
     {"cell_mm": 1.6, "profile": "wall", "wall_mm": 0.3}),
    ("woven", {"pitch_mm": 0.8, "width_mm": 0.6}, {"pitch_mm": 1.6, "width_mm": 1.2}),
    ("knit", {"wale_mm": 0.8, "course_mm": 0.6, "yarn_mm": 0.25}, {"wale_mm": 1.6, "course_mm": 1.2, "yarn_mm": 0.5}),
    ("grating", {"period_mm": 0.8, "profile": "triangle"}, {"period_mm": 1.6, "profile": "triangle"}),
    ("grains", {"grain_min_mm": 0.25, "grain_max_mm": 0.5}, {"grain_min_mm": 0.5, "grain_max_mm": 1.0}),
    ("dots", {"pitch_mm": 0.8, "diameter_mm": 0.4}, {"pitch_mm": 1.6, "diameter_mm": 0.8}),
])
def test_feature_size_follows_the_scale_parameters(family, small, large):
    fine = np.mean([make(family, seed=s, size_mm=8.0, **small).feature_size_mm() for s in range(2)])
    coarse = np.mean([make(family, seed=s, size_mm=8.0, **large).feature_size_mm() for s in range(2)])
    assert 1.5 < coarse / fine < 2.3


def test_fbm_has_no_features_finer_than_its_cutoff():
    hm = make("fbm", cutoff_mm=0.8, seed=1)
    power = np.abs(np.fft.fft2(hm.heights)) ** 2
    f = np.fft.fftfreq(hm.shape[0], hm.pixel_mm)
    k = np.hypot(f[:, None], f[None, :])
    assert power[k > 1 / 0.8].sum() < 1e-20 * power.sum()


@pytest.mark.parametrize("density", [0.3, 1.0, 2.0])
def test_grain_density_sets_the_covered_fraction(density):
    covered = np.mean([(grains(size_mm=8.0, seed=s, density=density).heights > 0).mean() for s in range(3)])
    assert covered == pytest.approx(1 - np.exp(-density), abs=0.05)


def test_seamless_families_tile_without_a_seam():
    for family in ("cellular", "grains"):
        h = make(family, **SMALL).heights
        across_seam = np.abs(h[:, 0] - h[:, -1]).mean() + np.abs(h[0] - h[-1]).mean()
        inside = np.abs(np.diff(h, axis=1)).mean() + np.abs(np.diff(h, axis=0)).mean()
        assert across_seam < 2 * inside, family


def test_make_matches_the_family_function():
    direct = FAMILIES["woven"](seed=5, size_mm=6.0, pitch_mm=0.9, angle_deg=20.0)
    np.testing.assert_array_equal(make("woven", seed=5, size_mm=6.0, pitch_mm=0.9, angle_deg=20.0).heights,
                                  direct.heights)


@pytest.mark.parametrize("call,message", [
    (lambda: make("velvet"), "unknown texture family 'velvet'; valid families: cellular, woven, knit"),
    (lambda: make("grating", period=1.0), "unknown grating parameter(s) period; valid parameters: period_mm"),
    (lambda: make("grating", period_mm=5.0), "grating parameter period_mm must be between 0.1 and 4, got 5.0"),
    (lambda: make("grating", profile="zigzag"), "grating parameter profile='zigzag' must be one of sine, square"),
    (lambda: make("dots", lattice="triangular"), "dots parameter lattice='triangular' must be one of square, hex"),
    (lambda: make("knit", height_mm="tall"), "knit parameter height_mm must be a finite number, got 'tall'"),
    (lambda: make("cellular", height_mm=True), "cellular parameter height_mm must be a finite number, got True"),
    (lambda: make("woven", pitch_mm=0.4, pixel_mm=0.2), "woven parameter pitch_mm=0.4 mm is below 4 pixels"),
    (lambda: make("cellular", cell_mm=3.0, size_mm=5.0), "cellular parameter cell_mm=3 mm needs a map of at least 6"),
    (lambda: make("fbm", seed=-1), "seed must be an integer >= 0, got -1"),
    (lambda: make("dots", seed=1.5), "seed must be an integer, got 1.5"),
    (lambda: make("dots", size_mm=0), "size_mm must be a positive finite number"),
    (lambda: grating(pixel_mm=float("nan")), "pixel_mm must be a positive finite number"),
    (lambda: grating(duty=0.95), "grating parameter duty must be between 0.1 and 0.9, got 0.95"),
])
def test_bad_input_names_the_problem(call, message):
    with pytest.raises(InputError) as error:
        call()
    assert message in str(error.value)

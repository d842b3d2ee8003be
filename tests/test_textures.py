"""Parametric bump textures: determinism, bump spacing, bump geometry, names and validation."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from roughness.core.errors import InputError
from roughness.dataset.textures import (
    FLAT_TOP_DIAMETERS_MM,
    STANDARD_LAMBDAS_MM,
    BumpRecipe,
    _bump_profile,
    bump_centres,
    bump_texture,
    flat_top_texture,
    named_texture,
    nearest_neighbour_spacing,
    standard_texture,
    texture_names,
)


def plateau_diameters_mm(heights: np.ndarray, pixel_mm: float, top_mm: float) -> np.ndarray:
    """Equivalent-circle diameters (mm) of the connected regions at the maximum height."""
    labels, count = ndimage.label(heights >= top_mm - 1e-9)
    areas = ndimage.sum_labels(np.ones_like(heights), labels, np.arange(1, count + 1)) * pixel_mm**2
    return 2 * np.sqrt(areas / np.pi)


def test_same_seed_same_texture_and_seeds_differ():
    recipe = BumpRecipe(lambda_mm=1.0, size_mm=6.0)
    a, b = bump_texture(recipe), bump_texture(recipe)
    np.testing.assert_array_equal(a.heights, b.heights)
    other = bump_texture(BumpRecipe(lambda_mm=1.0, size_mm=6.0, seed=1))
    assert not np.array_equal(a.heights, other.heights)


@pytest.mark.parametrize("lambda_mm", [0.5, 0.75, 1.0, 1.5, 2.0, 2.5])
def test_mean_nearest_neighbour_spacing_matches_lambda(lambda_mm):
    size_mm, pixel_mm = 20 * lambda_mm, 0.05
    for seed in range(3):
        centres = bump_centres(lambda_mm, size_mm, pixel_mm, np.random.default_rng(seed))
        assert centres.min() >= 0 and centres.max() < size_mm
        periodic = nearest_neighbour_spacing(centres, period_mm=size_mm)
        assert abs(periodic / lambda_mm - 1) < 0.1
        assert abs(nearest_neighbour_spacing(centres) / lambda_mm - 1) < 0.1


def test_density_is_uniform_up_to_the_edges():
    size_mm = 40.0
    centres = bump_centres(1.0, size_mm, 0.05, np.random.default_rng(0))
    near_edge = np.any((centres < 2.0) | (centres > size_mm - 2.0), axis=1)
    edge_area_fraction = 1 - ((size_mm - 4.0) / size_mm) ** 2
    assert abs(near_edge.mean() / edge_area_fraction - 1) < 0.15


def test_height_range_is_zero_to_bump_height():
    for height_mm in (1.0, 0.6):
        hm = bump_texture(BumpRecipe(lambda_mm=2.0, height_mm=height_mm, size_mm=8.0))
        assert hm.heights.max() == pytest.approx(height_mm, abs=1e-9)
        assert hm.heights.min() == 0.0
        assert hm.heights.dtype == np.float64


def test_flat_top_plateau_has_requested_diameter():
    pixel_mm = 0.01
    for diameter_mm in (0.1, 0.3, 0.5):
        hm = flat_top_texture(diameter_mm, lambda_mm=2.0, size_mm=6.0, pixel_mm=pixel_mm)
        measured = np.median(plateau_diameters_mm(hm.heights, pixel_mm, 1.0))
        assert measured == pytest.approx(diameter_mm, abs=1.5 * pixel_mm)


def test_cap_top_is_rounded_and_tangent_to_the_flank():
    recipe = BumpRecipe(lambda_mm=2.0, size_mm=6.0, pixel_mm=0.01)
    hm = bump_texture(recipe)
    assert np.median(plateau_diameters_mm(hm.heights, recipe.pixel_mm, 1.0)) < 2 * recipe.pixel_mm
    a, eps = recipe.top_diameter_mm / 2, 1e-6
    z = _bump_profile(recipe, np.array([0.0, a - 2 * eps, a - eps, a, a + eps, a + 2 * eps]))
    assert z[0] == pytest.approx(recipe.height_mm)
    inner_slope, outer_slope = (z[2] - z[1]) / eps, (z[5] - z[4]) / eps
    assert z[3] == pytest.approx(z[2], abs=1e-4)
    assert inner_slope == pytest.approx(outer_slope, rel=1e-3)
    assert _bump_profile(recipe, np.array([recipe.base_mm / 2]))[0] == pytest.approx(0.0, abs=1e-12)


def test_named_textures_exist_with_mm_units():
    names = texture_names()
    assert [f"standard-{lam}" for lam in STANDARD_LAMBDAS_MM] == names[:13]
    assert {"standard-1.0", "standard-0.6875", "standard-0.625", "standard-1.625"} <= set(names)
    assert [f"flattop-{d}" for d in FLAT_TOP_DIAMETERS_MM] == names[13:18]
    assert names[18:] == ["flat"]
    for name in names:
        hm = named_texture(name)
        assert hm.pixel_mm == 0.05
        assert hm.heights.shape == (240, 240)  # 12 mm side
    assert not named_texture("flat").heights.any()
    assert named_texture("standard-0.6875", seed=2).heights.max() == pytest.approx(1.0)


def test_size_and_pixel_are_as_requested():
    hm = standard_texture(1.25, size_mm=5.0, pixel_mm=0.025)
    assert hm.pixel_mm == 0.025 and hm.heights.shape == (200, 200)


@pytest.mark.parametrize("kwargs, message", [
    (dict(lambda_mm=0.0), "lambda_mm must be a positive finite number"),
    (dict(lambda_mm=-1.0), "lambda_mm must be a positive finite number"),
    (dict(lambda_mm=0.15), "below 4 pixels"),
    (dict(lambda_mm=1.0, top="dome"), "top must be one of"),
    (dict(lambda_mm=1.0, top="flat", top_diameter_mm=0.05), "within 0.1..0.5"),
    (dict(lambda_mm=1.0, top="flat", top_diameter_mm=0.6), "within 0.1..0.5"),
    (dict(lambda_mm=1.0, top="flat", top_diameter_mm=0.5, base_diameter_mm=0.5), "below base_diameter_mm"),
    (dict(lambda_mm=1.0, size_mm=0.0), "size_mm must be a positive finite number"),
    (dict(lambda_mm=1.0, pixel_mm=-0.05), "pixel_mm must be a positive finite number"),
    (dict(lambda_mm=1.0, height_mm=0.0), "height_mm must be a positive finite number"),
    (dict(lambda_mm=1.0, base_diameter_mm=0.0), "base_diameter_mm must be a positive finite number"),
    (dict(lambda_mm=2.0, size_mm=3.0), "too small for lambda"),
    (dict(lambda_mm="abc"), "lambda_mm must be a positive finite number, got 'abc'"),
    (dict(lambda_mm=1.0, top_diameter_mm=float("nan")), "top_diameter_mm must be a positive finite number"),
    (dict(lambda_mm=1.0, seed=-1), "seed must be an integer >= 0, got -1"),
    (dict(lambda_mm=1.0, seed=1.5), "seed must be an integer, got 1.5"),
    (dict(lambda_mm=1.0, size_mm=1e5), "2000000 x 2000000 pixels: 29.1 TiB per map"),
])
def test_bad_parameters_raise_input_error(kwargs, message):
    with pytest.raises(InputError, match=message):
        bump_texture(BumpRecipe(**kwargs))


def test_bad_names_and_lambdas_raise_input_error():
    with pytest.raises(InputError, match="valid names: standard-0.625"):
        named_texture("standard-0.7")
    with pytest.raises(InputError, match="not on the standard scale"):
        standard_texture(0.7)
    with pytest.raises(InputError, match="at least two"):
        nearest_neighbour_spacing(np.zeros((1, 2)))

"""Parametric bump textures (determinism, bump spacing, bump geometry, names, validation) and the engineered
and composite families (registration, determinism, units, height range, geometry, the training-v2 recipe)."""
from __future__ import annotations

import inspect
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from roughness.core.errors import InputError
from roughness.dataset import engineered
from roughness.dataset.catalogue import make_texture, names
from roughness.dataset.families import FAMILIES, PARAMETER_RANGES, make
from roughness.dataset.recipe import default_ranges, load_recipe, realise, sample_record
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
    (dict(lambda_mm=1.0, size_mm=1e5), r"size_mm=100000 at pixel_mm=0.05: 4e\+12, above the limit of 100,000,000"),
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


# Engineered and composite families (dataset/engineered.py), registered in dataset/families.py.

ENGINEERED = sorted(engineered.FAMILIES)
SMALL = {"size_mm": 8.0, "pixel_mm": 0.05}


def peak_mm(family: str, params: dict) -> float:
    """The documented peak height (mm) of a family's map."""
    if family == "multiscale":
        return params["wave_height_mm"] + 10 * params["rms_mm"]  # waviness plus the fBm's excursions
    return params["relief_mm"] if family == "shallow" else params["height_mm"]


def corner(family: str, k: int) -> dict:
    """Numeric parameters at their low (even k) or high (odd k) bound; choices cycled."""
    return {name: allowed[k % len(allowed)] if isinstance(allowed[0], str) else allowed[k % 2]
            for name, allowed in engineered.PARAMETER_RANGES[family].items()}


def test_engineered_families_are_registered_everywhere():
    assert set(ENGINEERED) == {"knurl", "milled", "waffle", "sparse", "multiscale", "shallow", "mixture"}
    for family in ENGINEERED:
        assert FAMILIES[family] is engineered.FAMILIES[family] and family in names()
        assert default_ranges(family) == PARAMETER_RANGES[family]
        hm, record = make_texture(family, seed=1, **SMALL)
        assert record["name"] == family and hm.shape == (160, 160)
    with pytest.raises(InputError, match="unknown knurl parameter"):
        make("knurl", pitch=1.0)


@pytest.mark.parametrize("family", ENGINEERED)
def test_engineered_family_is_deterministic_per_seed(family):
    a, b = make(family, seed=3, **SMALL), make(family, seed=3, **SMALL)
    np.testing.assert_array_equal(a.heights, b.heights)
    assert not np.allclose(a.heights, make(family, seed=4, **SMALL).heights)


@pytest.mark.parametrize("family", ENGINEERED)
@pytest.mark.parametrize("k", [0, 1, 2, 3])
def test_engineered_family_units_and_height_range_over_its_parameter_range(family, k):
    params = corner(family, k)
    hm = make(family, seed=k, size_mm=12.0, pixel_mm=0.04, **params)  # the largest scales need 12 mm
    assert hm.shape == (300, 300) and hm.pixel_mm == 0.04 and hm.heights.dtype == np.float64
    h = hm.heights
    assert np.all(np.isfinite(h)) and h.min() == 0.0 and 0 < h.max() <= peak_mm(family, params) + 1e-12


@pytest.mark.parametrize("family", ENGINEERED)
def test_engineered_defaults_lie_in_their_documented_ranges(family):
    signature = inspect.signature(engineered.FAMILIES[family]).parameters
    assert list(signature)[3:] == list(engineered.PARAMETER_RANGES[family])
    for name, allowed in engineered.PARAMETER_RANGES[family].items():
        default = signature[name].default
        assert default in allowed if isinstance(allowed[0], str) else allowed[0] <= default <= allowed[1]


@pytest.mark.parametrize("family, params, message", [
    ("knurl", {"pitch_mm": 0.05}, "knurl parameter pitch_mm must be between 0.1 and 4"),
    ("milled", {"pattern": "spiral"}, "must be one of parallel, crossed"),
    ("waffle", {"pitch_mm": 4.0, "size_mm": 6.0}, "needs a map of at least 8 mm"),
    ("sparse", {"diameter_mm": 0.3, "pixel_mm": 0.1}, "below 4 pixels"),
    ("shallow", {"base": "knurl"}, "must be one of cellular"),
    ("mixture", {"overlay_share": 1.0}, "overlay_share must be between 0.1 and 0.9"),
])
def test_engineered_bad_parameters_name_the_parameter(family, params, message):
    with pytest.raises(InputError, match=message):
        make(family, **params)


def test_milled_cusps_reach_their_height_at_the_step():
    hm = make("milled", step_mm=1.0, height_mm=0.2, angle_deg=0.0, size_mm=8.0, pixel_mm=0.01)
    assert hm.heights.max() == pytest.approx(0.2, abs=2e-3)  # cusp tip sampled within half a pixel
    profile = hm.heights[0]
    cusps = np.flatnonzero((profile > np.roll(profile, 1)) & (profile >= np.roll(profile, -1)))
    assert np.median(np.diff(cusps)) * 0.01 == pytest.approx(1.0, abs=0.011)


@pytest.mark.parametrize("lattice", ["square", "hex"])
def test_waffle_rib_area_follows_the_rib_width(lattice):
    # cells shrink by (1 - rib) in each direction, so ribs cover 1 - (1 - rib)^2 of the map for both lattices
    for rib in (0.1, 0.3):
        hm = make("waffle", pitch_mm=1.0, rib=rib, lattice=lattice, height_mm=0.5, size_mm=12.0, pixel_mm=0.02)
        covered = hm.heights.mean() / 0.5
        assert covered == pytest.approx(1 - (1 - rib) ** 2, rel=0.04)


@pytest.mark.parametrize("shape", ["dome", "cone", "flat", "pit"])
def test_sparse_features_stand_alone_and_one_is_under_the_footprint(shape):
    for seed in range(5):
        hm = make("sparse", seed=seed, density_per_cm2=1.0, diameter_mm=1.0, shape=shape, height_mm=0.3)
        ground = hm.heights.max() if shape == "pit" else 0.0
        raised = np.abs(hm.heights - ground) > 1e-9
        assert raised.mean() < 0.1  # mostly flat ground
        n = hm.shape[0]
        c = round(engineered.SPARSE_CENTRE_MM / hm.pixel_mm) + 10  # the centred feature plus its radius
        assert raised[n // 2 - c:n // 2 + c, n // 2 - c:n // 2 + c].any()
        assert ndimage.label(raised)[1] <= 2  # round(1 per cm^2 x 1.44 cm^2) = 1 feature, 2 if cut by an edge


def test_shallow_and_mixture_scale_to_their_peak():
    assert make("shallow", seed=2, base="fbm", relief_mm=0.01).heights.max() == pytest.approx(0.01)
    mixed = make("mixture", seed=2, base="waffle", overlay="fbm", combine="max", height_mm=0.4)
    assert mixed.heights.max() == pytest.approx(0.4)
    assert not np.allclose(mixed.heights, make("mixture", seed=2, base="waffle", overlay="fbm", combine="add",
                                               height_mm=0.4).heights)


def test_training_v2_recipe_draws_every_family_and_never_the_held_out_one_inside_composites():
    recipe = load_recipe(Path(__file__).parents[1] / "recipes" / "training-v2.json")
    assert recipe.name == "training-v2" and recipe.holdout_family == "knit"
    records = [sample_record(recipe, i) for i in range(400)]
    assert {r["family"] for r in records} == set(recipe.families) == {"bumps", *FAMILIES}
    for r in records:
        if r["family"] in ("shallow", "mixture"):  # knit and waffle can be held out whole (--holdout-family knit,waffle)
            assert not {"knit", "waffle"} & {r["params"].get("base"), r["params"].get("overlay")}
    for r in records[:12]:
        hm = realise(r)
        assert hm.shape == (240, 240) and np.all(np.isfinite(hm.heights))


@pytest.mark.parametrize("family", sorted(FAMILIES))
@pytest.mark.parametrize("k", [0, 1, 2, 3])
def test_every_family_makes_textures_at_the_corners_of_its_limits(family, k):
    """The limits (wider than the default ranges: 0.1 mm features, a fifth of the lowest relief, 4 mm
    wavelengths) are what a recipe may ask for: each corner makes a finite texture within its relief."""
    from roughness.dataset.families import PARAMETER_LIMITS

    params = {name: allowed[k % len(allowed)] if isinstance(allowed[0], str) else allowed[k % 2]
              for name, allowed in PARAMETER_LIMITS[family].items()}
    if family == "grating" and k % 2 == 0:
        params["duty"] = 0.5  # a 0.01 mm ridge (duty 0.1 of 0.1 mm) is narrower than a pixel: sampled away
    hm = make(family, seed=k, size_mm=12.0, pixel_mm=0.025, **params)  # 0.1 mm at 4 pixels; 6 mm waves in half
    h = hm.heights
    assert hm.shape == (480, 480) and np.all(np.isfinite(h)) and h.min() == 0.0
    if family in engineered.FAMILIES:
        assert 0 < h.max() <= peak_mm(family, params) + 1e-12
    elif family != "fbm":
        assert 0 < h.max() <= params["height_mm"] + 1e-12


def test_limits_widen_the_default_ranges_and_a_recipe_may_reach_them_but_not_beyond():
    from roughness.dataset.families import PARAMETER_LIMITS
    from roughness.dataset.recipe import Recipe

    for family, ranges in PARAMETER_RANGES.items():
        for name, allowed in ranges.items():
            limit = PARAMETER_LIMITS[family][name]
            assert limit == allowed if isinstance(allowed[0], str) else limit[0] <= allowed[0] <= allowed[1] <= limit[1]
    fine = Recipe(seed=1, families={"grating": 1.0}, ranges={"grating": {"period_mm": [0.1, 0.5], "height_mm": [0.01, 0.2]}},
                  size_mm=8.5, pixel_mm=0.025)
    assert realise(sample_record(fine, 0)).shape == (340, 340)
    with pytest.raises(InputError, match="period_mm"):
        Recipe(seed=1, families={"grating": 1.0}, ranges={"grating": {"period_mm": [0.05, 0.5]}})

"""The look measure (roughness.design.look): rendered luminance and region comparison, where the answer is plain."""
from __future__ import annotations

import numpy as np
import pytest

from roughness.core.errors import InputError
from roughness.dataset.textures import standard_texture
from roughness.design.look import THRESHOLD, compare, look_difference, photograph, render
from roughness.surface.heightmap import Heightmap, flat


@pytest.fixture(scope="module")
def plate():
    """A standard texture 2 mm tall, tiled to 36 mm, with a 16 mm disk and the ring beyond 20 mm around it."""
    hm = standard_texture(1.0, seed=0, height_mm=2.0).tiled(3, 3)
    y, x = np.mgrid[:hm.shape[0], :hm.shape[1]] * hm.pixel_mm
    r2 = (x - 18) ** 2 + (y - 18) ** 2
    return hm, r2 < 8**2, r2 > 10**2


def test_a_flat_plate_is_uniformly_lit_at_the_lights_sine():
    assert np.allclose(render(flat(5.0, 0.1)), np.sin(np.radians(45)))


def test_identical_textures_look_the_same(plate):
    hm, disk, ring = plate
    assert compare(render(hm), disk, ring, hm.pixel_mm).difference < 1


def test_a_raised_flat_shape_of_half_a_millimetre_is_visible(plate):
    hm, disk, ring = plate
    raised = Heightmap(np.where(disk, np.maximum(hm.heights, 0.5), hm.heights), hm.pixel_mm)
    look = compare(render(raised), disk, ring, hm.pixel_mm)
    assert look.verdict == "visible" and look.weber_contrast > THRESHOLD  # less shadow: brighter


def test_a_change_in_shaded_valley_floors_shows_less_than_the_same_change_on_the_tops(plate):
    hm, disk, ring = plate
    h = hm.heights
    ripple = 0.1 * np.sin(2 * np.pi * np.arange(h.shape[1]) * hm.pixel_mm / 0.4)[None, :]
    valleys, tops = h <= np.quantile(h, 0.05), h >= np.quantile(h, 0.95)
    looks = [compare(render(Heightmap(h + np.where(where & disk, ripple, 0.0), hm.pixel_mm)), disk, ring, hm.pixel_mm).difference
             for where in (valleys, tops)]
    assert looks[0] < looks[1] / 2


def test_regions_too_small_or_black_are_refused():
    lum = np.ones((10, 10))
    small = np.zeros((10, 10), bool)
    small[0, :3] = True
    with pytest.raises(InputError, match="at least 16"):
        compare(lum, small, ~small, 0.1)
    with pytest.raises(InputError, match="black"):
        compare(np.zeros((10, 10)), small | True, small | True, 0.1)


def test_look_distances_of_a_set_compare_every_pair():
    from roughness.design.look import look_distances

    a, taller = standard_texture(1.0), standard_texture(1.0, height_mm=1.5)
    d = look_distances([a, taller, a])
    assert np.all(np.diag(d) == 0) and d[0, 2] == d[2, 0] == 0  # the same texture twice looks the same
    assert d[0, 1] >= 1 and d[1, 0] >= 1  # half again as tall: steeper, darker flanks


def test_the_same_bumps_laid_closer_look_different_though_their_light_and_dark_are_alike():
    """Bumps and spacing scaled down together: every flank keeps its slope, so the luminance histogram barely
    moves; the bands see the finer texture."""
    from roughness.design.tune import scaled

    a = standard_texture(1.0, seed=0, height_mm=2.0)
    closer = scaled(scaled(a, "lateral", 0.7), "height", 0.7)  # 30% closer: 1.6 look JND by its bands
    look = look_difference(closer, a)
    assert max(abs(look.weber_contrast), look.distribution_distance) / THRESHOLD < look.texture_difference
    assert look.texture_difference >= 1 and look.verdict == "visible"
    assert look_difference(a, a).texture_difference == 0


def test_a_photograph_is_white_at_the_brightest_pixels_and_keeps_the_order_of_light():
    lum = np.linspace(0.0, 0.4, 1001).reshape(7, 143)
    shown = photograph(lum)
    assert shown.max() == 1 and shown.min() == 0 and np.all(np.diff(shown.ravel()) >= 0)
    assert np.isclose(shown.ravel()[500], (0.2 / np.percentile(lum, 99.5)) ** (1 / 2.2))
    assert np.all(photograph(np.zeros((4, 4))) == 0)


def test_wasserstein_distance_is_scipys():
    from scipy.stats import wasserstein_distance as scipys

    from roughness.design.look import wasserstein_distance

    rng = np.random.default_rng(0)
    for a, b in ((rng.random(7), rng.random(11) ** 2), (rng.random(3000), rng.normal(size=1000)),
                 (np.array([0.0, 0.0, 1.0, 1.0]), np.array([0.0, 1.0, 1.0]))):  # ties between and within samples
        assert wasserstein_distance(a, b) == pytest.approx(scipys(a, b), rel=1e-12, abs=1e-15)
    assert wasserstein_distance(a, a) == 0.0


def test_a_texture_look_is_its_luminance_mean_and_contrast():
    from roughness.design.look import texture_look

    level = texture_look(flat(5.0, 0.1))
    assert level.mean_luminance == pytest.approx(np.sin(np.radians(45)), rel=1e-12)
    assert level.contrast == pytest.approx(0.0, abs=1e-12)
    bumps = texture_look(standard_texture(1.0))
    lum = render(standard_texture(1.0))
    assert bumps.mean_luminance == pytest.approx(lum.mean()) and bumps.contrast == pytest.approx(lum.std() / lum.mean())


def test_region_interiors_leave_out_a_band_at_every_border():
    from roughness.design.look import region_interiors

    labels = np.zeros((40, 60), int)
    labels[:, 30:] = 1
    labels[:, 29:31] = -1  # a line between the regions: a border of both
    left, right = region_interiors(labels, 0.1, 2, band_mm=1.0)
    assert left[:, :19].all() and not left[:, 19:].any()  # more than 10 pixels from column 29
    assert right[:, 41:].all() and not right[:, :41].any()


def test_a_region_too_small_to_compare_is_left_out_with_the_reason():
    from roughness.design.look import region_looks

    hm = standard_texture(1.0)
    labels = np.zeros(hm.shape, int)
    labels[:, 100:] = 1
    labels[:, 100:130] = 2  # 1.5 mm wide: nothing lies more than 1 mm inside it
    looks = region_looks(hm, labels, ["left", "right", "strip"])
    assert looks.differences[0][1] is not None and looks.differences[0][2] is None and looks.differences[2][1] is None
    assert np.isnan(looks.matrix[0, 2]) and looks.matrix[0, 0] == 0 and looks.matrix[0, 1] < 1  # one texture
    assert looks.unmeasured == ("strip: 0 pixels lie more than 1 mm inside its borders, fewer than the 16 needed to "
                                "compare how it looks",)

"""Heightmap geometry (sampling, footprints, resampling) and heightmap file I/O."""
from __future__ import annotations

import math
from collections.abc import Callable

import h5py
import numpy as np
import pytest
import tifffile
from PIL import Image

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap, flat
from roughness.surface.io import load_heightmap, save_heightmap

RNG = np.random.default_rng(7)


def plane_map(shape: tuple[int, int] = (30, 40), pixel_mm: float = 0.1) -> tuple[Heightmap, Callable]:
    """Heightmap of the plane z = 0.3 x - 0.2 y + 1 (mm) sampled at pixel centres, and the plane."""
    def plane(x, y):
        return 0.3 * x - 0.2 * y + 1.0

    ny, nx = shape
    x = (np.arange(nx) + 0.5) * pixel_mm
    y = (np.arange(ny) + 0.5) * pixel_mm
    return Heightmap(plane(x[None, :], y[:, None]), pixel_mm), plane


def random_map(shape: tuple[int, int] = (16, 20), pixel_mm: float = 0.1) -> Heightmap:
    return Heightmap(RNG.random(shape), pixel_mm)


# --- construction --------------------------------------------------------------------------------


def test_heights_are_a_float64_read_only_copy() -> None:
    source = np.asfortranarray(np.arange(12).reshape(3, 4))
    hm = Heightmap(source, 0.5)
    source[0, 0] = 99
    assert hm.heights.dtype == np.float64 and hm.heights.flags.c_contiguous
    assert hm.heights[0, 0] == 0.0
    assert not hm.heights.flags.writeable
    assert hm.shape == (3, 4) and hm.size_mm == (2.0, 1.5) and hm.centre_mm == (1.0, 0.75)


@pytest.mark.parametrize("heights, pixel_mm, message", [
    (np.zeros(5), 0.1, "must be 2-D, got shape (5,)"),
    (np.zeros((2, 2, 2)), 0.1, "must be 2-D"),
    (np.zeros((0, 4)), 0.1, "empty"),
    (np.zeros((1, 4)), 0.1, "at least 2 pixels"),
    (np.array([[0.0, 1.0], [np.inf, np.nan]]), 0.1, "2 NaN/Inf pixel(s); first at row 1, column 0"),
    (np.array([["a", "b"], ["c", "d"]]), 0.1, "real numbers"),
    (np.zeros((3, 3)), 0.0, "pixel_mm must be a positive finite number"),
    (np.zeros((3, 3)), -0.1, "pixel_mm must be a positive finite number"),
    (np.zeros((3, 3)), math.inf, "pixel_mm must be a positive finite number"),
    (np.zeros((3, 3)), math.nan, "pixel_mm must be a positive finite number"),
])
def test_bad_heightmaps_raise_specific_input_errors(heights, pixel_mm, message) -> None:
    with pytest.raises(InputError) as err:
        Heightmap(heights, pixel_mm)
    assert message in str(err.value)


def test_flat_map() -> None:
    hm = flat(size_mm=2.0, pixel_mm=0.05, height_mm=0.3)
    assert hm.shape == (40, 40) and np.all(hm.heights == 0.3)


# --- sampling --------------------------------------------------------------------------------------


def test_bilinear_sampling_reproduces_a_plane_exactly() -> None:
    hm, plane = plane_map()
    (width, height), p = hm.size_mm, hm.pixel_mm
    x = RNG.uniform(p / 2, width - p / 2, (50, 3))
    y = RNG.uniform(p / 2, height - p / 2, (50, 3))
    got = hm.sample(x, y)
    assert got.shape == (50, 3)
    np.testing.assert_allclose(got, plane(x, y), rtol=0, atol=1e-12)


def test_sampling_at_pixel_centres_returns_the_pixels() -> None:
    hm = random_map()
    ny, nx = hm.shape
    x = (np.arange(nx) + 0.5) * hm.pixel_mm
    y = (np.arange(ny) + 0.5) * hm.pixel_mm
    np.testing.assert_allclose(hm.sample(x[None, :], y[:, None]), hm.heights, atol=1e-12)


def test_non_periodic_sampling_takes_the_edge_value_beyond_the_pixel_centres() -> None:
    hm, plane = plane_map()
    p = hm.pixel_mm
    y = np.array([1.0, 1.5])
    np.testing.assert_allclose(hm.sample(-3.0, y), plane(p / 2, y), atol=1e-12)
    np.testing.assert_allclose(hm.sample(0.0, y), plane(p / 2, y), atol=1e-12)
    np.testing.assert_allclose(hm.sample(100.0, y), plane(hm.size_mm[0] - p / 2, y), atol=1e-12)


def test_periodic_sampling_wraps_continuously() -> None:
    hm = random_map()
    (width, height), p = hm.size_mm, hm.pixel_mm
    rows_y = (np.arange(hm.shape[0]) + 0.5) * p
    # Halfway between the last and the first pixel centre lies the seam x = 0 = width.
    np.testing.assert_allclose(hm.sample(0.0, rows_y, periodic=True),
                               0.5 * (hm.heights[:, -1] + hm.heights[:, 0]), atol=1e-12)
    eps = 1e-7
    np.testing.assert_allclose(hm.sample(width - eps, rows_y, periodic=True),
                               hm.sample(eps, rows_y, periodic=True), atol=1e-5)
    x, y = RNG.uniform(-width, 2 * width, 200), RNG.uniform(-height, 2 * height, 200)
    np.testing.assert_allclose(hm.sample(x + 3 * width, y - 2 * height, periodic=True),
                               hm.sample(x, y, periodic=True), atol=1e-9)


def test_periodic_sampling_matches_the_interior_of_a_tiled_map() -> None:
    hm = random_map()
    big = hm.tiled(3, 3)
    width, height = hm.size_mm
    x, y = RNG.uniform(0, width, 200), RNG.uniform(0, height, 200)
    np.testing.assert_allclose(big.sample(x + width, y + height), hm.sample(x, y, periodic=True), atol=1e-12)


def test_sampling_rejects_non_finite_points() -> None:
    with pytest.raises(ValueError, match="finite"):
        random_map().sample(np.array([0.1, np.nan]), 0.1)


# --- footprints --------------------------------------------------------------------------------------


def test_covers() -> None:
    hm = flat(size_mm=12.0, pixel_mm=0.05)
    assert hm.covers(10.0) and hm.covers(12.0)
    assert not hm.covers(12.01)
    assert hm.covers(10.0, (5.0, 7.0))
    assert not hm.covers(10.0, (4.9, 6.0)) and not hm.covers(10.0, (6.0, 7.1))


def test_require_footprint_on_a_small_map_suggests_tiling() -> None:
    hm = flat(size_mm=6.4, pixel_mm=0.05)
    with pytest.raises(InputError) as err:
        hm.require_footprint(10.0)
    assert str(err.value) == ("heightmap is 6.40 mm x 6.40 mm, smaller than the 10.0 mm x 10.0 mm skin "
                              "footprint; pass tile=True to repeat it as a periodic texture")
    hm.require_footprint(10.0, tile=True)


def test_require_footprint_names_an_off_map_centre() -> None:
    hm = flat(size_mm=12.0, pixel_mm=0.05)
    hm.require_footprint(10.0)
    with pytest.raises(InputError) as err:
        hm.require_footprint(10.0, (1.0, 6.0))
    assert "centred at (1.00, 6.00) mm" in str(err.value)
    assert "x 5.00..7.00 mm" in str(err.value)


def test_max_in_footprint_counts_only_pixel_centres_inside() -> None:
    heights = np.zeros((20, 20))
    heights[0, 0] = 5.0  # centre (0.05, 0.05) mm
    heights[10, 10] = 1.0  # centre (1.05, 1.05) mm
    heights[10, 12] = 2.0  # centre (1.25, 1.05) mm
    hm = Heightmap(heights, 0.1)
    assert hm.max_in_footprint(0.2, (1.1, 1.05)) == 1.0  # x 1.0..1.2 mm: columns 10 and 11
    assert hm.max_in_footprint(0.2, (1.15, 1.05)) == 2.0  # a centre on the edge counts
    assert hm.max_in_footprint(1.0) == 2.0
    assert hm.max_in_footprint(0.5, (1.6, 1.6)) == 0.0
    assert hm.max_in_footprint(0.3, (1.9, 1.9)) == 0.0
    assert hm.max_in_footprint(0.3, (1.9, 1.9), periodic=True) == 5.0  # wraps to pixel (0, 0)
    assert hm.max_in_footprint(0.5, (0.3, 0.3)) == 5.0


# --- derived maps ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("new_pixel_mm", [0.05, 0.25])
def test_resampling_preserves_a_plane(new_pixel_mm: float) -> None:
    hm, plane = plane_map(pixel_mm=0.1)
    out = hm.resampled(new_pixel_mm)
    assert out.pixel_mm == new_pixel_mm
    assert out.size_mm == pytest.approx(hm.size_mm)
    ny, nx = out.shape
    x = (np.arange(nx) + 0.5) * new_pixel_mm
    y = (np.arange(ny) + 0.5) * new_pixel_mm
    inside_x = (x >= 0.05) & (x <= hm.size_mm[0] - 0.05)
    inside_y = (y >= 0.05) & (y <= hm.size_mm[1] - 0.05)
    expected = plane(x[None, inside_x], y[inside_y, None])
    np.testing.assert_allclose(out.heights[np.ix_(inside_y, inside_x)], expected, atol=1e-12)


@pytest.mark.parametrize("axis", [0, 1])
def test_feature_size_of_a_sinusoid_is_its_wavelength(axis: int) -> None:
    wavelength, pixel = 0.8, 0.02
    n = 400
    u = (np.arange(n) + 0.5) * pixel
    heights = np.broadcast_to(0.3 * np.sin(2 * np.pi * u / wavelength), (n, n))
    hm = Heightmap(heights if axis == 1 else heights.T, pixel)
    assert hm.feature_size_mm() == pytest.approx(wavelength, rel=0.05)


def test_feature_size_of_a_flat_map_is_infinite() -> None:
    assert flat(size_mm=1.0, pixel_mm=0.1, height_mm=2.0).feature_size_mm() == math.inf


def test_tiled_repeats_the_map() -> None:
    hm = random_map((3, 4))
    big = hm.tiled(2, 3)
    assert big.shape == (6, 12) and big.pixel_mm == hm.pixel_mm
    np.testing.assert_array_equal(big.heights[3:, 8:], hm.heights)
    with pytest.raises(InputError, match="reps_x must be a positive integer"):
        hm.tiled(1, 0)


# --- file round trips ---------------------------------------------------------------------------------------


def test_npy_round_trip(tmp_path) -> None:
    hm = random_map()
    save_heightmap(hm, tmp_path / "map.npy")
    back = load_heightmap(tmp_path / "map.npy", pixel_mm=0.1)
    np.testing.assert_array_equal(back.heights, hm.heights)
    assert back.pixel_mm == 0.1
    assert [p.name for p in tmp_path.iterdir()] == ["map.npy"]  # no temporary file left behind


def test_8bit_png_scales_grey_levels_to_height(tmp_path) -> None:
    grey = np.arange(256, dtype=np.uint8).reshape(16, 16)
    Image.fromarray(grey).save(tmp_path / "map.png")
    hm = load_heightmap(tmp_path / "map.png", pixel_mm=0.05, height_mm=2.0)
    np.testing.assert_allclose(hm.heights, grey / 255 * 2.0, atol=1e-15)
    assert hm.pixel_mm == 0.05


def test_grey_rgb_png_loads_like_greyscale(tmp_path) -> None:
    grey = np.arange(64, dtype=np.uint8).reshape(8, 8) * 4
    Image.fromarray(np.dstack([grey] * 3)).save(tmp_path / "map.png")
    hm = load_heightmap(tmp_path / "map.png", pixel_mm=0.05, height_mm=1.0)
    np.testing.assert_array_equal(hm.heights, grey / 255)


def test_16bit_png_keeps_16bit_precision(tmp_path) -> None:
    levels = np.array([[0, 1, 2, 255], [256, 257, 65534, 65535]], dtype=np.uint16)
    Image.fromarray(levels).save(tmp_path / "levels.png")
    hm = load_heightmap(tmp_path / "levels.png", pixel_mm=0.1, height_mm=65.535)  # 1 um per level
    np.testing.assert_allclose(hm.heights, levels / 1000, atol=1e-12)


def test_16bit_png_round_trip(tmp_path) -> None:
    hm = Heightmap(RNG.random((30, 25)) * 1.5 + 0.2, 0.05)
    span = float(np.ptp(hm.heights))
    save_heightmap(hm, tmp_path / "map.png")
    back = load_heightmap(tmp_path / "map.png")  # units from the file's text chunk
    assert back.pixel_mm == 0.05
    assert np.abs(back.heights - hm.heights).max() <= 0.5 * span / 65535 + 1e-12
    save_heightmap(hm, tmp_path / "tall.png", height_mm=2 * span)
    back = load_heightmap(tmp_path / "tall.png", pixel_mm=0.05, height_mm=2 * span)  # agreeing flags are fine
    assert back.heights.max() == pytest.approx(hm.heights.max(), abs=2 * span / 65535)


def test_flat_map_saves_as_a_black_png(tmp_path) -> None:
    save_heightmap(flat(1.0, 0.1, height_mm=3.0), tmp_path / "flat.png")
    back = load_heightmap(tmp_path / "flat.png")
    assert np.all(back.heights == 3.0) and back.pixel_mm == 0.1


@pytest.mark.parametrize("suffix", [".npz", ".png", ".tif", ".tiff", ".h5", ".hdf5"])
def test_written_files_carry_their_units(tmp_path, suffix) -> None:
    hm = Heightmap(RNG.random((12, 9)) * 0.8 - 0.1, 0.037)
    save_heightmap(hm, tmp_path / f"map{suffix}")
    back = load_heightmap(tmp_path / f"map{suffix}")
    assert back.pixel_mm == pytest.approx(0.037, rel=1e-12)
    step = 0.5 * np.ptp(hm.heights) / 65535 if suffix == ".png" else 1e-7  # 16-bit levels, float32 TIFF
    np.testing.assert_allclose(back.heights, hm.heights, atol=step + 1e-12)


@pytest.mark.parametrize("suffix", [".npz", ".png", ".tif", ".h5"])
def test_a_flag_that_contradicts_the_file_is_an_error(tmp_path, suffix) -> None:
    save_heightmap(Heightmap(RNG.random((6, 6)), 0.05), tmp_path / f"map{suffix}")
    assert load_heightmap(tmp_path / f"map{suffix}", pixel_mm=0.05).pixel_mm == 0.05
    with pytest.raises(InputError, match="states pixel_mm = 0.05 mm, but pixel_mm = 0.1 mm was given") as err:
        load_heightmap(tmp_path / f"map{suffix}", pixel_mm=0.1)
    assert err.value.parameter == "pixel_mm"


def test_colour_images_are_refused(tmp_path) -> None:
    rgb = np.zeros((4, 4, 3), dtype=np.uint8)
    rgb[..., 0] = 200  # red: a plot, not a heightmap
    Image.fromarray(rgb).save(tmp_path / "plot.png")
    tifffile.imwrite(tmp_path / "plot.tif", rgb)
    for name in ("plot.png", "plot.tif"):
        with pytest.raises(InputError, match="is a colour image"):
            load_heightmap(tmp_path / name, pixel_mm=0.1, height_mm=1.0)


@pytest.mark.parametrize("dtype", [np.int32, np.int64, np.uint16, np.int8])
def test_integer_heights_in_mm_formats_are_refused(tmp_path, dtype) -> None:
    np.save(tmp_path / "map.npy", (np.arange(16).reshape(4, 4) * 60).astype(dtype))
    with pytest.raises(InputError, match="holds integers") as err:
        load_heightmap(tmp_path / "map.npy", pixel_mm=0.1)
    assert "millimetres as floating-point" in str(err.value)


def test_tiff_round_trip(tmp_path) -> None:
    hm = random_map()
    save_heightmap(hm, tmp_path / "map.tif")
    back = load_heightmap(tmp_path / "map.tif", pixel_mm=0.1)
    np.testing.assert_allclose(back.heights, hm.heights, rtol=1e-6)


def test_16bit_tiff_scales_grey_levels(tmp_path) -> None:
    levels = np.array([[0, 1], [32768, 65535]], dtype=np.uint16)
    tifffile.imwrite(tmp_path / "map.tiff", levels)
    hm = load_heightmap(tmp_path / "map.tiff", pixel_mm=0.1, height_mm=3.0)
    np.testing.assert_allclose(hm.heights, levels / 65535 * 3.0, atol=1e-15)


def test_h5_pixel_size_from_dataset_or_file_attribute(tmp_path) -> None:
    heights = RNG.random((5, 6))
    with h5py.File(tmp_path / "a.h5", "w") as f:
        f.create_dataset("heightmap", data=heights).attrs["pixel_mm"] = 0.02
    with h5py.File(tmp_path / "b.hdf5", "w") as f:
        f.attrs["pixel_mm"] = 0.04
        f.create_dataset("scans/s1", data=heights)
    a = load_heightmap(tmp_path / "a.h5")
    np.testing.assert_array_equal(a.heights, heights)
    assert a.pixel_mm == 0.02
    with pytest.raises(InputError, match="states pixel_mm = 0.02 mm, but pixel_mm = 0.03 mm was given"):
        load_heightmap(tmp_path / "a.h5", pixel_mm=0.03)
    assert load_heightmap(tmp_path / "b.hdf5", dataset="scans/s1").pixel_mm == 0.04
    with pytest.raises(InputError, match="no dataset 'heightmap'; datasets in the file: scans/s1"):
        load_heightmap(tmp_path / "b.hdf5")


# --- bad input files ------------------------------------------------------------------------------------


def _write(tmp_path, name: str, content) -> str:
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif isinstance(content, Image.Image):
        content.save(path)
    elif name.endswith((".h5", ".hdf5")):
        with h5py.File(path, "w") as f:
            f["heightmap"] = content
    else:
        np.save(path, content)
    return str(path)


@pytest.mark.parametrize("name, content, kwargs, message", [
    ("map.npy", np.array([[0.0, np.nan], [1.0, 2.0]]), {"pixel_mm": 0.1}, "1 NaN/Inf pixel(s); first at row 0, column 1"),
    ("map.npy", np.zeros(8), {"pixel_mm": 0.1}, "must be 2-D"),
    ("map.npy", np.zeros((0, 0)), {"pixel_mm": 0.1}, "empty"),
    ("map.npy", np.array([[True, False], [False, True]]), {"pixel_mm": 0.1}, "real numbers"),
    ("map.npy", np.zeros((4, 4)), {}, "heightmaps need pixel_mm"),
    ("map.npy", np.zeros((4, 4)), {"pixel_mm": 0.0}, "pixel_mm must be a positive finite number"),
    ("map.npy", np.zeros((4, 4)), {"pixel_mm": -1.0}, "pixel_mm must be a positive finite number"),
    ("map.npy", np.zeros((4, 4)), {"pixel_mm": 0.1, "height_mm": 1.0}, "already in mm"),
    ("map.npy", b"not an array", {"pixel_mm": 0.1}, "as NPY"),
    ("map.png", b"\x89PNG\r\n\x1a\n" + b"corrupt" * 8, {"pixel_mm": 0.1, "height_mm": 1.0}, "as PNG"),
    ("map.png", b"", {"pixel_mm": 0.1, "height_mm": 1.0}, "as PNG"),
    ("map.png", Image.new("L", (4, 4)), {"pixel_mm": 0.1}, "heightmaps need height_mm"),
    ("map.png", Image.new("L", (4, 4)), {"height_mm": 1.0}, "heightmaps need pixel_mm"),
    ("map.png", Image.new("L", (4, 4)), {"pixel_mm": 0.1, "height_mm": math.nan}, "height_mm must be"),
    ("map.png", Image.new("P", (4, 4)), {"pixel_mm": 0.1, "height_mm": 1.0}, "palette"),
    ("map.tif", b"II*\x00garbage", {"pixel_mm": 0.1, "height_mm": 1.0}, "as TIFF"),
    ("map.h5", b"not hdf5", {"pixel_mm": 0.1}, "as HDF5"),
    ("map.h5", np.zeros((4, 4)), {}, "heightmaps need pixel_mm"),
    ("map.jpg", b"\xff\xd8", {"pixel_mm": 0.1}, "unsupported heightmap format '.jpg'"),
])
def test_bad_files_raise_specific_input_errors(tmp_path, name, content, kwargs, message) -> None:
    path = _write(tmp_path, name, content)
    with pytest.raises(InputError) as err:
        load_heightmap(path, **kwargs)
    assert message in str(err.value)
    if not message.startswith(("pixel_mm", "height_mm")):  # errors about the file name it
        assert name in str(err.value)


def test_missing_file_and_directory(tmp_path) -> None:
    with pytest.raises(InputError, match="not found"):
        load_heightmap(tmp_path / "absent.npy", pixel_mm=0.1)
    (tmp_path / "dir.png").mkdir()
    with pytest.raises(InputError, match="is a directory"):
        load_heightmap(tmp_path / "dir.png", pixel_mm=0.1, height_mm=1.0)


def test_float_tiff_refuses_height_scale(tmp_path) -> None:
    tifffile.imwrite(tmp_path / "map.tif", np.zeros((4, 4), dtype=np.float32))
    with pytest.raises(InputError, match="already in mm"):
        load_heightmap(tmp_path / "map.tif", pixel_mm=0.1, height_mm=1.0)


def test_save_errors(tmp_path) -> None:
    hm = random_map()
    with pytest.raises(InputError, match="unsupported format '.jpg'"):
        save_heightmap(hm, tmp_path / "map.jpg")
    with pytest.raises(InputError, match="folder does not exist"):
        save_heightmap(hm, tmp_path / "missing" / "map.npy")
    with pytest.raises(InputError, match="would clip"):
        save_heightmap(hm, tmp_path / "map.png", height_mm=0.1)
    assert not list(tmp_path.iterdir())


def test_the_old_import_paths_still_work_and_say_where_the_modules_went():
    import importlib
    import sys

    import roughness.surface.io as surface_io

    for name in ("heightmap", "io", "detrend", "stl"):
        sys.modules.pop(f"roughness.simulate.{name}", None)
        with pytest.warns(DeprecationWarning, match=f"roughness.surface.{name}"):
            importlib.import_module(f"roughness.simulate.{name}")
    assert sys.modules["roughness.simulate.io"].load_heightmap is surface_io.load_heightmap

"""Sizes and numbers that inputs and options imply are checked before anything is allocated (issue 26, 5 and 6;
issue 46, 4 and 5).

The parser-generated bad-input matrix of test_bad_inputs.py, extended: every X,Y option with
non-finite and absurd values; files whose headers declare huge arrays (decompression bombs,
lying .npy headers); options that imply huge arrays, lists or loops. Every case must exit 2 at once,
name the option or file and the limit, print no traceback and change no file. Steps whose memory
would grow faster than the map (levelling, resampling, a printer's wide bead) hold a few maps at
most; and round-off in a stored number (a float32 pixel size, a grating constant up to 1e-15 mm)
is not taken for a different input.
"""
from __future__ import annotations

import struct
import tracemalloc
import zipfile
import zlib

import h5py
import numpy as np
import pytest
from PIL import Image

from roughness.cli.common import float_pair
from roughness.core.errors import InputError
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, MAX_MAP_POSITIONS, Limit, check_size
from roughness.dataset.textures import standard_texture
from roughness.surface.heightmap import Heightmap
from test_bad_inputs import BASE, PARSERS, _expect_refusal, _run

PAIR_OPTIONS = [(path, action.option_strings[-1]) for path, parser in PARSERS.items()
                for action in parser._actions if action.type is float_pair]
HEIGHTMAP_COMMANDS = [path for path in BASE if BASE[path][:1] == ["map.npy"]]
HUGE = 200_000  # pixels along each side of a declared bomb: 4e10 pixels, 320 GB as float64


def test_the_matrix_finds_the_pair_options_and_heightmap_commands():
    assert {" ".join(path) for path, _ in PAIR_OPTIONS} == {"simulate", "predict"}
    assert {"simulate", "predict", "homogeneity", "tune", "jnd"} <= {" ".join(p) for p in HEIGHTMAP_COMMANDS}


@pytest.mark.parametrize("path, flag", PAIR_OPTIONS, ids=str)
@pytest.mark.parametrize("value", ["nan,nan", "inf,inf", "1e300,1e300", "1,nan", "-inf,5"])
@pytest.mark.parametrize("tile", [False, True], ids=["on-map", "tile"])
def test_pair_option_not_finite_or_absurd(path, flag, value, tile, workdir, capsys):
    argv = [*path, *BASE[path], flag, value] + (["--tile"] if tile else [])
    _expect_refusal(argv, workdir, capsys, (flag, "footprint centre"))


@pytest.mark.parametrize("path, flag", PAIR_OPTIONS, ids=str)
def test_centre_off_the_map_names_the_centre(path, flag, workdir, capsys):
    _expect_refusal([*path, *BASE[path], flag, "100,100"], workdir, capsys, (flag, "centred at (100.00, 100.00)"))


@pytest.mark.parametrize("centre", [(np.nan, 5.0), (np.inf, np.inf), (1e300, 1e300)], ids=str)
@pytest.mark.parametrize("tile", [False, True])
def test_library_refuses_a_bad_centre(centre, tile):
    from roughness import PredictOptions, predict

    hm = Heightmap(np.random.default_rng(0).random((240, 240)) * 0.5, 0.05)
    with pytest.raises(InputError) as err:
        predict([hm], engine="surrogate", options=PredictOptions(centre_mm=centre, tile=tile))
    assert err.value.parameter == "centre_mm"
    with pytest.raises(InputError):
        hm.require_footprint(10.0, centre, tile)


# --- files that declare more than they hold -------------------------------------------------------

def _npy_bomb(path):
    with open(path, "wb") as f:
        np.lib.format.write_array_header_1_0(f, {"descr": "<f8", "fortran_order": False,
                                                 "shape": (100_000_000, 100_000_000)})  # 1e16 values
        f.write(bytes(64))


def _npz_bomb(path):
    member = path.with_suffix(".member")
    _npy_bomb(member)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.write(member, "heightmap.npy")
    member.unlink()


def _h5_bomb(path):
    with h5py.File(path, "w") as f:  # zeros, gzip: a few kB on disk
        data = f.create_dataset("heightmap", shape=(HUGE, HUGE), dtype="f8", chunks=(1000, 1000), compression="gzip")
        data[:10, :10] = 1.0
        data.attrs["pixel_mm"] = 0.05


def _tiff_bomb(path):
    import tifffile

    tifffile.imwrite(path, np.zeros((256, 256), np.uint8), compression="zlib", tile=(256, 256), metadata=None)
    with tifffile.TiffFile(path) as tif:
        tags = tif.pages[0].tags
        offsets = [tags[name].valueoffset for name in ("ImageWidth", "ImageLength")]
        kinds = [tags[name].dtype for name in ("ImageWidth", "ImageLength")]
    with open(path, "r+b") as f:  # the one compressed tile now claims to be part of a 200,000 x 200,000 image
        for offset, kind in zip(offsets, kinds):
            f.seek(offset)
            f.write(struct.pack("<I", HUGE) if kind == 4 else struct.pack("<H", 60_000))


def _png(path, width, height):
    """A PNG whose header declares width x height 8-bit grey pixels (and whose data is a few zeros)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(bytes(1000))) + chunk(b"IEND", b""))


BOMBS = {
    "bomb.npy": _npy_bomb,
    "bomb.npz": _npz_bomb,
    "bomb.h5": _h5_bomb,
    "bomb.tif": _tiff_bomb,
    "bomb.png": lambda p: _png(p, 100_000, 100_000),  # above twice PIL's limit: PIL's own error
    "big.png": lambda p: _png(p, 12_000, 12_000),  # 144 Mpx: between PIL's warning and its error
}


@pytest.mark.parametrize("path", HEIGHTMAP_COMMANDS, ids=" ".join)
@pytest.mark.parametrize("bomb", BOMBS)
def test_heightmap_bomb_is_refused_from_its_header(path, bomb, workdir, capsys):
    BOMBS[bomb](workdir / bomb)
    assert (workdir / bomb).stat().st_size < 20_000
    argv = [*path, bomb, *BASE[path][1:]]
    _expect_refusal(argv, workdir, capsys, ("MAX_HEIGHTMAP_PIXELS",))
    _, err = _run(argv, capsys)
    assert bomb in err and "DecompressionBomb" not in err


def test_truncated_npy_header_is_refused_before_reading(workdir, capsys):
    with open(workdir / "short.npy", "wb") as f:
        np.lib.format.write_array_header_1_0(f, {"descr": "<f8", "fortran_order": False, "shape": (3000, 3000)})
        f.write(bytes(64))
    _expect_refusal(["predict", "short.npy", *BASE[("predict",)][1:]], workdir, capsys, ("truncated",))


@pytest.mark.parametrize("width, height", [(100_000, 100_000), (12_000, 12_000), (8_000, 7_000)])
def test_tactile_image_picture_bomb(width, height, workdir, capsys):
    _png(workdir / "huge.png", width, height)
    argv = ["tactile-image", "huge.png", *BASE[("tactile-image",)][1:]]
    _expect_refusal(argv, workdir, capsys, ("MAX_IMAGE_PIXELS",))
    assert "DecompressionBomb" not in _run(argv, capsys)[1]


def test_dataset_map_bomb_is_refused_before_reading(tmp_path):
    from roughness.dataset.layout import group_maps

    with h5py.File(tmp_path / "d.h5", "w") as f:
        group = f.create_group("samples/x")
        group.create_dataset("heightmap", shape=(HUGE, HUGE), dtype="f4", chunks=(1000, 1000), compression="gzip")
        with pytest.raises(InputError, match="MAX_HEIGHTMAP_PIXELS"):
            group_maps(group)


# --- options that imply huge arrays or loops --------------------------------------------------------

OPTION_CASES = [
    (("predict",), ["--pixel-mm", "1e-7", "--tile", "--units-ok"], "--pixel-mm", "MAX_HEIGHTMAP_PIXELS"),
    (("predict",), ["--map", "m.npy", "--step-mm", "1e-5"], "--step-mm", "MAX_MAP_POSITIONS"),
    (("predict",), ["--map", "m.npy", "--step-mm", "1e-320", "--tile"], "--step-mm", "MAX_MAP_POSITIONS"),
    (("predict",), ["--pixel-mm", "1e-320", "--tile"], "--pixel-mm", "MIN_PIXEL_MM"),
    (("simulate",), ["--pixel-mm", "1e-320", "--tile"], "--pixel-mm", "MIN_PIXEL_MM"),
    (("tactile-image",), ["--pixel-mm", "1e-320"], "--pixel-mm", "MIN_PIXEL_MM"),
    (("homogeneity",), ["--n", "1000000"], "--n", "MAX_WINDOWS"),
    (("homogeneity",), ["--pixel-mm", "0.01", "--tile", "--window-mm", "2", "--n", "10000"], "--n",
     "MAX_WORKING_VALUES"),
    (("perception", "design"), ["--trials", "100000000"], "--trials", "MAX_TRIALS"),
    (("perception", "design"), ["--subjects", "1000000000"], "--subjects", "MAX_TRIALS"),
    (("perception", "simulate"), ["--trials", "1000", "--subjects", "1000"], "--trials", "MAX_TRIALS"),
    (("perception", "plan"), ["--trials", "10,100000000"], "--trials", "MAX_TRIALS"),
    (("tactile-image",), ["--pixel-mm", "1e-7"], "--size-mm", "MAX_PLATE_PIXELS"),
    (("tactile-image",), ["--step-mm", "0.01"], "--step-mm", "MAX_MAP_POSITIONS"),
    (("train",), ["--widths", "8,1000000000"], "--widths", "MAX_CHANNELS"),
]


@pytest.mark.parametrize("path, extra, flag, limit", OPTION_CASES, ids=lambda v: str(v))
def test_option_implied_size_is_refused(path, extra, flag, limit, workdir, capsys):
    """predict reports a file's problem per file (others are still predicted): "pixel size" names the option."""
    _expect_refusal([*path, *BASE[path], *extra], workdir, capsys, (flag, "pixel size"))
    assert limit in _run([*path, *BASE[path], *extra], capsys)[1]


def test_dataset_build_n_is_refused_before_preparing(tmp_path, capsys, monkeypatch):
    """The real build (no tripwire on it): refused before any sample record is made or any file written."""
    import roughness.dataset.recipe

    def tripped(*args, **kwargs):
        raise AssertionError("a record was made for a refused build")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(roughness.dataset.recipe, "sample_record", tripped)
    argv = ["dataset", "build", "--out", "new.h5", "--n", "1000000000"]
    _expect_refusal(argv, tmp_path, capsys, ("--n",))
    assert "MAX_DATASET_SAMPLES" in _run(argv, capsys)[1]
    assert not list(tmp_path.iterdir())


def test_compare_on_a_recipe_n_is_refused(workdir, capsys):
    (workdir / "recipe.json").write_text('{"seed": 1}')
    argv = ["compare", "recipe.json", *BASE[("compare",)][1:], "--n", "1000000000"]
    _expect_refusal(argv, workdir, capsys, ("--n",))
    assert "MAX_DATASET_SAMPLES" in _run(argv, capsys)[1]


@pytest.mark.parametrize("path", [("predict",), ("simulate",)], ids=" ".join)
def test_absurd_heights_are_an_input_error_about_heights(path, workdir, capsys):
    np.save(workdir / "tall.npy", np.full((240, 240), 1e300))
    argv = [*path, "tall.npy", *BASE[path][1:]]
    _expect_refusal(argv, workdir, capsys, ("MAX_HEIGHT_MM",))
    assert "patches must be" not in _run(argv, capsys)[1]


def test_absurd_height_scale_of_a_png(workdir, capsys):
    Image.fromarray(np.arange(240 * 240, dtype=np.uint16).reshape(240, 240)).save(workdir / "grey.png")
    argv = ["predict", "grey.png", *BASE[("predict",)][1:], "--height-mm", "1e300"]
    _expect_refusal(argv, workdir, capsys, ("MAX_HEIGHT_MM",))


# --- the limits themselves ----------------------------------------------------------------------

def test_check_size_names_the_limit_and_parameter():
    limit = Limit(10, "MAX_THINGS")
    assert check_size("things", 10, limit) == 10
    for count in (11, 10**400, float("inf"), float("nan")):
        with pytest.raises(InputError, match="above the limit of 10 \\(MAX_THINGS\\)") as err:
            check_size("things", count, limit, "n")
        assert err.value.parameter == "n"


def test_what_users_need_fits():
    """A 100 x 100 mm map at 0.05 mm (4 Mpx) is a heightmap; its map at the default 1 mm step is far below the limit."""
    hm = Heightmap(np.zeros((2000, 2000)), 0.05)
    assert hm.shape == (2000, 2000) and hm.heights.size <= MAX_HEIGHTMAP_PIXELS
    from roughness.surrogate.roughness_map import centre_count, centres

    for size, step, tile in [(100.0, 1.0, False), (100.0, 0.1, False), (100.0, 0.1, True), (12.0, 0.3, False)]:
        assert centre_count(size, 10.0, step, tile) == len(centres(size, 10.0, step, tile))
    assert centre_count(100.0, 10.0, 0.1, False) ** 2 <= MAX_MAP_POSITIONS


# --- round-off is not a different input ------------------------------------------------------------

FLOAT32_PIXEL = float(np.float32(5e-5)) * 1e3  # 0.05 mm stated in float32 metres (a .sur file): 0.0499999987 mm


@pytest.mark.parametrize("pixel_mm", [FLOAT32_PIXEL, 0.0499999, 0.0500001])
def test_a_pixel_within_its_precision_is_sampled_as_the_pixel_it_states(pixel_mm):
    """Its patch differs from the 0.05 mm map's only by the shift its relative difference makes across the map
    (samples move by at most that many pixels, each moving a height by at most the largest step between pixels,
    along two axes; float32 patches round at 1e-6). A fixed 1e-9 once took 0.0499999987 for a finer pixel:
    3 samples per patch pixel instead of 2, 0.0125 mm in the patch and 0.8% in V."""
    from roughness.surrogate.patch import footprint_patch, samples_per_pixel

    heights = standard_texture(1.0, seed=0).heights
    shift_px = abs(pixel_mm / 0.05 - 1) * max(heights.shape)
    step = max(float(np.abs(np.diff(heights, axis=axis)).max()) for axis in (0, 1))
    difference = footprint_patch(Heightmap(heights, pixel_mm)) - footprint_patch(Heightmap(heights, 0.05))
    assert np.abs(difference).max() <= 2 * shift_px * step + 1e-6
    assert samples_per_pixel(0.1, pixel_mm) == 2 and samples_per_pixel(0.1, 0.0499) == 3  # a finer pixel is finer


def test_a_map_of_float32_pixels_covers_the_footprint_it_spans():
    """200 pixels of 0.0499999987 mm span 9.99999974 mm: the 10 mm footprint fits, as on 0.05 mm pixels; a map a
    pixel short is still short."""
    hm = Heightmap(np.zeros((200, 200)), FLOAT32_PIXEL)
    assert hm.covers(10.0) and hm.covers(10.0, (5.0, 5.0))
    hm.require_footprint(10.0, (5.0, 5.0))
    assert not Heightmap(np.zeros((199, 199)), 0.05).covers(10.0)


@pytest.mark.parametrize("angle_deg", [0.0, 90.0])
def test_an_exactly_periodic_unit_cell_tiles(angle_deg):
    """A grating's unit cell is constant along its ridges up to round-off (1e-15 mm): that is no step, and no seam
    across the wrap (once 4.7 times the round-off 'step': refused as not periodic). A patch cut from a random
    texture still shows its seam."""
    from roughness.dataset.catalogue import make_texture
    from roughness.surface.tiling import check_tile, tile_fit

    cell, _ = make_texture("grating", size_mm=1.0, params={"period_mm": 0.5, "angle_deg": angle_deg})
    assert tile_fit(cell).seamless
    check_tile(cell, "cell", 10.0)
    assert not tile_fit(Heightmap(standard_texture(1.0, seed=0).heights[:20, :20], 0.05)).seamless


def test_a_bead_that_reaches_a_pixel_centre_up_to_round_off_reaches_it():
    """0.3 / 0.05 is 5.999999999999999 in floats: the disk of 6 pixels, not of 5."""
    from roughness.surface.printing import _disk_rows

    assert _disk_rows(0.3 / 0.05) == _disk_rows(6.0) == [6, 5, 5, 5, 4, 3, 0]
    assert _disk_rows(5.999)[0] == 5  # beyond the precision a smaller radius is a smaller disk


@pytest.mark.parametrize("radius_px", [1.0, 4.5, 12.0])
@pytest.mark.parametrize("mode", ["nearest", "wrap"])
def test_the_row_by_row_disk_filter_is_grey_morphology(radius_px, mode):
    """The printer's disks, filtered a row of the disk at a time, equal scipy's grey dilation and erosion with the
    disk as footprint, exactly (a disk wider than the map too)."""
    from scipy import ndimage

    from roughness.surface.printing import _disk_filter, _disk_rows

    rows = _disk_rows(radius_px)
    r = len(rows) - 1
    footprint = np.zeros((2 * r + 1, 2 * r + 1), bool)
    for dy, half in enumerate(rows):
        footprint[[r - dy, r + dy], r - half:r + half + 1] = True
    h = np.random.default_rng(4).random((23, 31))
    assert np.array_equal(_disk_filter(h, radius_px, mode, True), ndimage.grey_dilation(h, footprint=footprint,
                                                                                          mode=mode))
    assert np.array_equal(_disk_filter(h, radius_px, mode, False), ndimage.grey_erosion(h, footprint=footprint,
                                                                                           mode=mode))


# --- steps that grew faster than the map -------------------------------------------------------------

def _tripped(*args, **kwargs):
    raise AssertionError("a tripwire: work that must not run")


def _peak_bytes(function, *args) -> tuple[object, int]:
    """``function(*args)`` and the most bytes it held at once beyond what was held before (NumPy's arrays are
    traced)."""
    tracemalloc.start()
    try:
        out = function(*args)
        return out, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_levelling_holds_about_one_map_and_is_the_least_squares_fit():
    """poly3 levelling once stacked a basis of 10 values per pixel and copied it in lstsq (a 50 Mpx map ran out of
    memory); the projection on orthonormal polynomials of each axis holds the trend and small factors."""
    from roughness.surface.cleanup import polynomial_fit

    i, j = np.mgrid[0:300, 0:400]
    x, y = (j - 200) / 400, (i - 150) / 300  # centred, in units of the map's side
    heights = np.random.default_rng(5).random((300, 400)) + 3 * x**3 - x * y + 0.5 * y**2
    trend, peak = _peak_bytes(polynomial_fit, heights, 3)
    assert peak <= 2 * heights.nbytes
    basis = np.stack([x**a * y**b for a in range(4) for b in range(4 - a)], axis=-1).reshape(-1, 10)
    coef, *_ = np.linalg.lstsq(basis, heights.ravel(), rcond=None)
    np.testing.assert_allclose(trend, (basis @ coef).reshape(heights.shape), atol=1e-9)


def test_resampling_to_square_pixels_holds_the_output_and_a_block(monkeypatch):
    """At 1000:1 the whole-map temporaries took five outputs; in blocks of rows it is the output and one block."""
    import roughness.surface.pixels as pixels

    monkeypatch.setattr(pixels, "CHUNK_VALUES", 4096)
    heights = np.random.default_rng(6).random((2, 500))  # rows 1 mm apart, columns 0.001 mm
    (out, _), peak = _peak_bytes(pixels.square, heights, 0.001, 1.0)
    assert out.shape == (2000, 500) and peak <= 1.2 * out.nbytes
    y = (np.arange(2000) + 0.5) * 0.001 - 0.5  # rows, in the file's rows: bilinear, clamped at the outer centres
    expected = np.stack([np.interp(y, [0, 1], heights[:, j]) for j in range(500)], axis=1)
    np.testing.assert_allclose(out, expected, atol=1e-12)


def test_a_wide_bead_filters_without_footprint_tables(monkeypatch):
    """A 9 mm bead (inside the profile ranges) took 6.4 GB: scipy's 2-D footprint filters build offset tables that
    grow with the disk's area squared (84 MB for the 3 mm bead here, 30 pixels across at 0.05 mm), outside NumPy's
    arrays. The disks are filtered row by row instead (exact: test_the_row_by_row_disk_filter_is_grey_morphology)."""
    from scipy import ndimage

    from roughness.surface.printing import FdmProfile, printed

    hm = Heightmap(standard_texture(1.0, seed=0).heights[:60, :60], 0.05)
    for name in ("grey_opening", "grey_closing", "grey_dilation", "grey_erosion", "maximum_filter", "minimum_filter"):
        monkeypatch.setattr(ndimage, name, _tripped)
    result, peak = _peak_bytes(printed, hm, FdmProfile("wide", 3.0, 0.2, 3.0, 0.049))
    assert result.heightmap.shape == hm.shape and peak <= 30 * hm.heights.nbytes


def test_light_bleed_filters_each_distinct_layer_once(monkeypatch):
    """Layers 1..7 of a map holding only layers 0, 3 and 7 expose two sets: two Gaussians, not seven (a fine resin
    profile filtered 4,000 times), and each cured layer counted as a loop over all seven would count it."""
    from scipy import ndimage

    from roughness.surface.printing import SlaProfile, printed

    calls = []
    gaussian = ndimage.gaussian_filter
    monkeypatch.setattr(ndimage, "gaussian_filter", lambda *a, **k: calls.append(1) or gaussian(*a, **k))
    rng = np.random.default_rng(7)
    levels = np.choose(rng.integers(0, 3, (40, 40)), [0, 3, 7])
    profile = SlaProfile("resin", 0.01, 0.05, 0.05)  # LCD pixel finer than the map's: only the bleed acts
    out = printed(Heightmap(0.05 * levels, 0.05), profile).heightmap.heights
    assert len(calls) == 2
    cured = sum(gaussian((levels >= k).astype(float), 1.0, mode="nearest") >= 0.5 for k in range(1, 8))
    np.testing.assert_allclose(out, 0.05 * cured, atol=1e-12)


@pytest.mark.parametrize("case", ["resin layers", "wide bead"])
def test_a_print_too_large_to_filter_is_refused_before_any_filter(case, monkeypatch):
    """80,000 resin layers on 40,000 pixels (MAX_LAYER_PIXELS), or a 9 mm bead on 0.5 um pixels (MAX_FILTER_TAPS):
    refused, naming --printer, before any filter runs."""
    from scipy import ndimage

    from roughness.surface.printing import FdmProfile, SlaProfile, printed

    for name in ("gaussian_filter", "distance_transform_edt", "maximum_filter1d", "minimum_filter1d"):
        monkeypatch.setattr(ndimage, name, _tripped)
    if case == "resin layers":
        hm, profile, limit = (Heightmap(np.linspace(0, 400, 40_000).reshape(200, 200), 0.05),
                              SlaProfile("fine", 0.01, 0.005, 0.05), "MAX_LAYER_PIXELS")
    else:
        hm, profile, limit = Heightmap(np.zeros((1000, 1000)), 5e-4), FdmProfile("wide", 3.0, 0.2, 9.0, 0.049), \
            "MAX_FILTER_TAPS"
    with pytest.raises(InputError, match=limit) as err:
        printed(hm, profile)
    assert err.value.parameter == "printer"


@pytest.mark.parametrize("step", ["despike", "detrend"])
def test_steps_holding_several_maps_are_checked_before_they_allocate(step, monkeypatch):
    """Despike holds 6 maps and detrend 14: each is checked against MAX_WORKING_VALUES first (a limit of 1,000
    values here, so a 20 x 20 map is too large)."""
    from scipy import ndimage

    import roughness.surface.cleanup as cleanup
    import roughness.surface.detrend as detrend

    small = Limit(1000, "MAX_WORKING_VALUES")
    monkeypatch.setattr(cleanup, "MAX_WORKING_VALUES", small)
    monkeypatch.setattr(detrend, "MAX_WORKING_VALUES", small)
    monkeypatch.setattr(ndimage, "median_filter", _tripped)
    monkeypatch.setattr(np.fft, "rfft2", _tripped)
    heights = np.random.default_rng(8).random((20, 20))
    with pytest.raises(InputError, match="MAX_WORKING_VALUES") as err:
        cleanup.despike(heights, 5.0) if step == "despike" else detrend.detrend(Heightmap(heights, 0.05))
    assert err.value.parameter == step


def test_a_huge_model_file_is_refused_before_it_is_read(workdir, tmp_path_factory, capsys, monkeypatch):
    """A 5 GB --model was read whole; above MAX_MODEL_FILE_BYTES (a sparse file here: no disk used) it is refused
    from its size."""
    from pathlib import Path

    from roughness.core.limits import MAX_MODEL_FILE_BYTES

    huge = tmp_path_factory.mktemp("models") / "huge.onnx"
    with open(huge, "wb") as f:
        f.truncate(MAX_MODEL_FILE_BYTES + 1)
    read_bytes = Path.read_bytes
    monkeypatch.setattr(Path, "read_bytes", lambda p: _tripped() if p.name == "huge.onnx" else read_bytes(p))
    argv = ["predict", *BASE[("predict",)], "--model", str(huge)]
    _expect_refusal(argv, workdir, capsys, ("--model",))
    assert "MAX_MODEL_FILE_BYTES" in _run(argv, capsys)[1]


# --- messages name the real problem ------------------------------------------------------------------

def test_an_absurd_pixel_size_names_the_pixel_not_the_centre(workdir, capsys):
    """With --units-ok a 1e300 mm pixel (given, or stated by the file) once put the map's centre beyond
    MAX_COORDINATE_MM and blamed --centre, which was never given."""
    np.savez(workdir / "far.npz", heightmap=np.random.default_rng(9).random((50, 50)), pixel_mm=1e300)
    for argv in (["predict", "map.npy", "--pixel-mm", "1e300", "--units-ok", "--engine", "surrogate"],
                 ["predict", "far.npz", "--units-ok", "--engine", "surrogate"]):
        _expect_refusal(argv, workdir, capsys, ("MAX_PIXEL_MM",))
        assert "centre" not in _run(argv, capsys)[1].splitlines()[-1]


def test_the_maps_own_centre_is_not_checked_as_a_given_one():
    """A map wider than 2 km (1,000 mm pixels) has its patch made at its centre; only a given centre is bounded."""
    from roughness.surrogate.patch import footprint_patch

    hm = Heightmap(np.random.default_rng(10).random((2, 2100)), 1000.0)
    assert hm.centre_mm[0] > 1e6 and footprint_patch(hm).shape == (100, 100)


def test_tune_names_a_factor_range_too_large(workdir, capsys):
    """tune --max-factor 1e300 once said "check the file's unit" (the scaled heights' limit)."""
    argv = ["tune", *BASE[("tune",)], "--max-factor", "1e300"]
    _expect_refusal(argv, workdir, capsys, ("--max-factor",))
    err = _run(argv, capsys)[1].splitlines()[-1]  # the message, after argparse's usage
    assert "MAX_SCALE_FACTOR" in err and "unit" not in err


def test_a_height_factor_beyond_what_a_heightmap_holds_names_max_factor():
    from roughness.design.tune import Target, tune

    tall = Heightmap(np.linspace(0, 20, 240 * 240).reshape(240, 240), 0.05)  # 20 mm: x 100 is 2 m
    with pytest.raises(InputError, match="MAX_HEIGHT_MM") as err:
        tune(tall, Target(0.09, 1.0, "lambda"), factor_range=(0.5, 100.0))
    assert err.value.parameter == "max_factor" and "unit" not in str(err.value)


def test_a_printer_nozzle_that_is_no_number_is_named(tmp_path):
    """It was "missing line_width_mm" (the width defaults from the nozzle, which was skipped)."""
    from roughness.surface.printing import load_profile

    path = tmp_path / "printer.json"
    path.write_text('{"kind": "fdm", "nozzle_mm": "0.4 mm", "layer_mm": 0.2}')
    with pytest.raises(InputError, match="nozzle_mm must be a finite number") as err:
        load_profile(path)
    assert "line_width_mm" not in str(err.value) and err.value.parameter == "printer"

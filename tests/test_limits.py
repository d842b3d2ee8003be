"""Sizes and numbers that inputs and options imply are checked before anything is allocated (issue 26, 5 and 6).

The parser-generated bad-input matrix of test_bad_inputs.py, extended: every X,Y option with
non-finite and absurd values; files whose headers declare huge arrays (decompression bombs,
lying .npy headers); options that imply huge arrays, lists or loops. Every case must exit 2 at once,
name the option or file and the limit, print no traceback and change no file.
"""
from __future__ import annotations

import struct
import zipfile
import zlib

import h5py
import numpy as np
import pytest
from PIL import Image

from roughness.cli.common import float_pair
from roughness.core.errors import InputError
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, MAX_MAP_POSITIONS, Limit, check_size
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
    (("tactile-image",), ["--pixel-mm", "1e-320"], "--size-mm", "MAX_PLATE_PIXELS"),
    (("homogeneity",), ["--n", "1000000"], "--n", "MAX_WINDOWS"),
    (("homogeneity",), ["--pixel-mm", "0.01", "--tile", "--window-mm", "2", "--n", "10000"], "--n",
     "MAX_WORKING_VALUES"),
    (("perception", "design"), ["--trials", "100000000"], "--trials", "MAX_TRIALS"),
    (("perception", "design"), ["--subjects", "1000000000"], "--trials", "MAX_TRIALS"),
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

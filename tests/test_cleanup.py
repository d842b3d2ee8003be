"""Real surfaces in (issue 28): units checked before any work, per-file units, scan clean-up, small scans."""
from __future__ import annotations

import json

import numpy as np
import pytest

from roughness.core.errors import InputError
from roughness.dataset import natural
from roughness.dataset.textures import standard_texture
from roughness.surface.cleanup import Cleanup, Despiked, Filled, Levelled, clean, despike, fill_holes, polynomial_fit
from roughness.surface.detrend import quadratic_fit
from roughness.surface.heightmap import Heightmap, flat
from roughness.surface.io import save_heightmap
from roughness.surface.tiling import MAX_SEAM, MIN_PERIODS, check_tile, tile_fit
from roughness.surface.units import FileUnits, check_units, plausibility, split_input
from test_bad_inputs import _expect_refusal, _run


@pytest.fixture(scope="module")
def texture() -> Heightmap:
    return standard_texture(1.0)


def _save(hm: Heightmap, path) -> str:
    save_heightmap(hm, path)
    return str(path)


# Units --------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("hm", [standard_texture(0.625), standard_texture(1.625),
                                natural.fbm(rms_mm=0.02, hurst=0.9, cutoff_mm=1.5),
                                natural.grating(profile="square", height_mm=1.0, period_mm=0.3),
                                natural.grating(profile="sine", height_mm=0.05, period_mm=3.0),
                                natural.grains(height_mm=1.0), flat(12.0, 0.05)],
                         ids=["std-0.625", "std-1.625", "fbm-low", "grating-steep", "grating-low", "grains", "flat"])
def test_the_products_textures_pass_the_unit_check(hm):
    """The bounds lie outside everything the product makes (the extremes of its families), so none is refused."""
    assert plausibility(hm).problems() == []


@pytest.mark.parametrize("scale, pixel, unit", [(1e-3, 0.05, "heights in metres"),
                                                (1e3, 0.05, "heights in micrometres"),
                                                (1.0, 5e-5, "pixel size in metres"),
                                                (1.0, 2.0, "pixel size in micrometres")])
def test_implausible_units_name_the_likely_unit(texture, scale, pixel, unit):
    hm = Heightmap(texture.heights * scale, pixel)
    with pytest.raises(InputError, match=f"looks like {unit}(;|:)") as err:
        check_units(hm, "scan.npy")
    assert err.value.parameter == "units_ok"
    assert str(err.value).count("looks like") == 1 and str(err.value).count(f"{unit}") == 1  # said once
    assert check_units(hm, "scan.npy", units_ok=True).relief_mm == pytest.approx(scale)


def test_metres_refused_before_any_engine_and_confirmed_by_flag(texture, workdir, capsys):  # noqa: F811
    """Heights in metres gave V = 0.0000 "in domain"; heights in micrometres ran the FEM. Now both stop at
    loading (the workdir's tripwire fails any FEM run), and --units-ok lets the metres through."""
    _save(Heightmap(texture.heights / 1000, 0.05), workdir / "m.npz")
    _save(Heightmap(texture.heights * 1000, 0.05), workdir / "um.npz")
    for argv in (["predict", "m.npz"], ["simulate", "um.npz", "--fidelity", "coarse"], ["predict", "um.npz"],
                 ["jnd", "m.npz", "um.npz"]):
        _expect_refusal(argv, workdir, capsys, ("--units-ok",))
    code, err = _run(["simulate", "um.npz", "--fidelity", "coarse"], capsys)
    assert "looks like heights in micrometres" in err
    code, err = _run(["predict", "m.npz", "--engine", "spectral", "--units-ok", "--json"], capsys)
    assert code == 0, err


# Per-file units -----------------------------------------------------------------------------------------------------


def test_split_input(tmp_path):
    assert split_input("a.png:height-mm=0.8") == ("a.png", FileUnits(None, 0.8))
    assert split_input("d/a.png:pixel-mm=0.05,height-mm=1") == ("d/a.png", FileUnits(0.05, 1.0))
    assert split_input("a.npy") == ("a.npy", FileUnits())
    odd = tmp_path / "x:height-mm=1"  # an existing file is taken whole
    odd.write_bytes(b"")
    assert split_input(str(odd)) == (str(odd), FileUnits())
    for bad in ("a.png:height=1", "a.png:height-mm=-1", "a.png:height-mm=nan", "a.png:pixel-mm=x"):
        with pytest.raises(InputError):
            split_input(bad)
    assert FileUnits(None, 0.8).over(0.05, 2.0) == FileUnits(0.05, 0.8)


def test_jnd_of_a_picture_and_a_tuned_npz(texture, tmp_path, capsys):
    """`jnd picture.png tuned.npz` needs --height-mm for the PNG, which the .npz refused: with several inputs
    it applies to those that need it (and says so), or goes with the file as FILE:height-mm=MM."""
    from PIL import Image

    from roughness.cli import main

    picture = tmp_path / "picture.png"
    Image.fromarray(np.uint8(np.round(texture.heights * 255))).save(picture)  # grey levels, no units in the file
    tuned = _save(standard_texture(1.25), tmp_path / "tuned.npz")
    assert main(["jnd", str(picture), tuned, "--pixel-mm", "0.05", "--height-mm", "1", "--engine", "spectral",
                 "--json"]) == 0
    both = json.loads(capsys.readouterr().out)
    a, b = both["readings"]
    assert a["own_units"] is False and b["own_units"] is True
    assert a["units"]["relief_mm"] == pytest.approx(1.0)
    assert main(["jnd", f"{picture}:height-mm=1,pixel-mm=0.05", tuned, "--engine", "spectral"]) == 0
    out = capsys.readouterr().out
    assert both["a"]["roughness"] == pytest.approx(float(out.split("V = ")[1].split()[0]), abs=1e-4)
    assert main(["predict", tuned, "--height-mm", "1", "--engine", "spectral"]) == 2  # one .npz: still refused
    assert "already in mm" in capsys.readouterr().err


def test_a_folder_carries_its_units_to_each_file(texture, tmp_path, capsys):
    from PIL import Image

    from roughness.cli import main

    folder = tmp_path / "scans"
    folder.mkdir()
    Image.fromarray(np.uint8(np.round(texture.heights * 255))).save(folder / "a.png")
    np.save(folder / "b.npy", texture.heights)
    assert main(["predict", f"{folder}:pixel-mm=0.05,height-mm=1", "--engine", "spectral", "--json"]) == 0
    answers = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [a["readings"][0]["own_units"] for a in answers] == [False, True]  # the .npy holds mm: its own heights
    assert answers[0]["roughness"] == pytest.approx(answers[1]["roughness"], rel=0.02)  # 8-bit grey levels


# Clean-up -----------------------------------------------------------------------------------------------------------


def test_fill_is_exact_on_a_plane_and_reports_its_fraction():
    y, x = np.mgrid[0:60, 0:80]
    plane = 0.01 * x - 0.02 * y + 0.3
    holey = plane.copy()
    holey[10:20, 30:45] = np.nan  # a blob
    holey[0, :5] = np.nan  # on the edge
    holey[59, 79] = np.nan  # a corner
    filled = fill_holes(holey)
    np.testing.assert_allclose(filled[1:-1, 1:-1], plane[1:-1, 1:-1], atol=1e-9)  # inside: linear exactly
    # free edges (no slope across them): within the measured rim (maximum principle), a corner its neighbours' mean
    assert np.all((filled[0, :5] > plane[1, 0]) & (filled[0, :5] < plane[0, 5]))
    assert filled[59, 79] == pytest.approx((plane[58, 79] + plane[59, 78]) / 2)
    hm, done = clean(holey, 0.05, Cleanup(fill=True))
    assert done.steps == (Filled(156, 156 / 4800),)
    assert "3.25% of the map" in done.lines()[0]


def test_holes_need_fill_and_a_limit():
    holey = np.ones((40, 40)) + np.arange(40) * 0.01
    holey[:5] = np.nan  # 12.5%
    with pytest.raises(InputError, match="pass fill=True") as err:
        clean(holey, 0.05, Cleanup())
    assert err.value.parameter == "fill"
    with pytest.raises(InputError, match="more than max_fill, 10%") as err:
        clean(holey, 0.05, Cleanup(fill=True, max_fill=0.1))
    assert err.value.parameter == "max_fill"
    assert clean(holey, 0.05, Cleanup(fill=True, max_fill=0.2))[1].steps[0].fraction == 0.125


def test_despike_finds_spikes_and_leaves_clean_textures_alone(texture):
    for hm in (texture, natural.fbm(rms_mm=0.25, hurst=0.3, cutoff_mm=0.2), natural.grains(height_mm=1.0)):
        assert despike(hm.heights, 5.0)[1].pixels == 0
    rng = np.random.default_rng(1)
    spiky = texture.heights.copy()
    where = rng.random(spiky.shape) < 0.003
    spiky[where] += rng.choice([-1, 1], where.sum()) * rng.uniform(0.3, 2.0, where.sum())
    out, step = despike(spiky, 5.0)
    assert isinstance(step, Despiked) and step.pixels == where.sum()
    assert np.abs(out - texture.heights).max() < 0.06  # a spike's median is within a pixel's step of the truth
    plate = np.zeros((50, 50))
    plate[[5, 20, 40], [7, 30, 2]] = [0.5, -0.2, 1.0]
    out, step = despike(plate, 5.0)  # a flat plate: its step is 0 once the spikes are out
    assert step.pixels == 3 and not out.any()


def test_level_plane_and_polynomial(texture):
    y, x = np.mgrid[0:240, 0:240] * 0.05
    tilted = texture.heights + 0.2 * x - 0.1 * y
    hm, done = clean(tilted, 0.05, Cleanup(level="plane"))
    own = polynomial_fit(texture.heights, 1)  # the texture's own best plane (0.02 mm over the map) goes too
    np.testing.assert_allclose(hm.heights, texture.heights - own, atol=1e-9)
    assert isinstance(done.steps[0], Levelled)
    assert done.steps[0].removed_relief_mm == pytest.approx(np.ptp(own + 0.2 * x - 0.1 * y))
    np.testing.assert_allclose(polynomial_fit(tilted, 2), quadratic_fit(tilted), atol=1e-9)  # detrend's own fit
    cubic = 0.05 * (x - 6) ** 3 / 36
    np.testing.assert_allclose(polynomial_fit(cubic, 3), cubic, atol=1e-9)


def test_clean_up_options_reported_and_recorded(texture, tmp_path, capsys):
    """Every step is in the text output and in the JSON, typed per step; nothing happens without its option."""
    from roughness.cli import main

    heights = texture.heights + 0.01 * np.arange(240)[None, :]
    heights[100:110, 100:110] = np.nan
    heights[50, 50] += 1.5
    path = tmp_path / "scan.npy"
    np.save(path, heights)
    assert main(["predict", str(path), "--pixel-mm", "0.05", "--engine", "spectral"]) == 2
    assert "pass --fill" in capsys.readouterr().err
    assert main(["predict", str(path), "--pixel-mm", "0.05", "--engine", "spectral", "--fill", "--despike", "5",
                 "--level", "plane"]) == 0
    text = capsys.readouterr().err  # notes on stderr, as every command prints what loading did
    assert "filled 100 missing points (0.17% of the map)" in text and "replaced 1 spikes" in text
    assert "subtracted the least-squares plane" in text
    assert main(["predict", str(path), "--pixel-mm", "0.05", "--engine", "spectral", "--fill", "--despike", "5",
                 "--level", "plane", "--json"]) == 0
    steps = json.loads(capsys.readouterr().out)["readings"][0]["steps"]
    assert [s["step"] for s in steps] == ["filled", "despiked", "levelled"]
    assert steps[0]["pixels"] == 100 and steps[1]["pixels"] == 1 and steps[2]["method"] == "plane"


# Small scans --------------------------------------------------------------------------------------------------------


def test_tile_measures(texture):
    cut = tile_fit(Heightmap(texture.heights[:40, :40], 0.05))  # 2 mm cut from a random texture
    seamless = tile_fit(standard_texture(1.0, size_mm=3.0))  # generated periodic
    assert cut.seam > MAX_SEAM and cut.periods < MIN_PERIODS
    assert seamless.seam < MAX_SEAM
    assert tile_fit(texture).seam < MAX_SEAM  # the full texture is periodic too
    assert check_tile(texture, "full", 10.0) is None  # covers the footprint: nothing to measure
    with pytest.raises(InputError, match="too small to tile") as err:
        check_tile(Heightmap(texture.heights[:40, :40], 0.05), "patch", 10.0)
    assert err.value.parameter == "tile"


def test_small_patches_refused_or_out_of_domain(texture, tmp_path, capsys):
    """The issue's 2 mm confocal patch with --tile was "in domain": a small cut patch is refused; a seamless
    small tile and a larger cut patch are answered OUT OF DOMAIN with the reason."""
    from roughness.cli import main

    patch = _save(Heightmap(texture.heights[:40, :40], 0.05), tmp_path / "patch.npz")
    assert main(["predict", patch, "--tile", "--engine", "spectral"]) == 2
    assert "--tile" in capsys.readouterr().err
    seamless = _save(standard_texture(1.0, size_mm=3.0), tmp_path / "cell.npz")
    large_cut = _save(Heightmap(texture.heights[:140, :140], 0.05), tmp_path / "large.npz")
    for path, reason in ((seamless, "feature lengths"), (large_cut, "not periodic")):
        assert main(["predict", path, "--tile", "--engine", "spectral", "--json"]) == 0
        answer = json.loads(capsys.readouterr().out)
        assert answer["in_domain"] is False and any(reason in note for note in answer["domain_notes"])
        assert answer["readings"][0]["tile"]["periods"] > 0


# The bad-input matrix, extended -------------------------------------------------------------------------------------


def _bad_scans(folder) -> None:
    hm = standard_texture(1.0)
    np.save(folder / "metres.npy", hm.heights / 1000)
    np.save(folder / "micrometres.npy", hm.heights * 1000)
    holes = hm.heights.copy()
    holes[:60] = np.nan  # 25%
    np.save(folder / "holes.npy", holes)
    np.save(folder / "patch.npy", hm.heights[:40, :40])


BAD_SCANS = [
    (["predict", "metres.npy", "--pixel-mm", "0.05"], ("--units-ok", "metres")),
    (["predict", "micrometres.npy", "--pixel-mm", "0.05", "--engine", "auto"], ("--units-ok",)),
    (["simulate", "micrometres.npy", "--pixel-mm", "0.05", "--fidelity", "coarse"], ("micrometres",)),
    (["simulate", "metres.npy", "--pixel-mm", "0.05", "--fidelity", "coarse"], ("metres",)),
    (["predict", "map.npy", "--pixel-mm", "5e-5"], ("pixel size",)),
    (["jnd", "map.npy", "metres.npy", "--pixel-mm", "0.05"], ("--units-ok",)),
    (["homogeneity", "micrometres.npy", "--pixel-mm", "0.05", "--n", "5"], ("--units-ok",)),
    (["tune", "metres.npy", "--pixel-mm", "0.05", "--target-lambda", "1.0", "--out", "new.npz"], ("--units-ok",)),
    (["predict", "holes.npy", "--pixel-mm", "0.05"], ("--fill",)),
    (["simulate", "holes.npy", "--pixel-mm", "0.05", "--fidelity", "coarse"], ("--fill",)),
    (["predict", "holes.npy", "--pixel-mm", "0.05", "--fill"], ("--max-fill",)),
    (["predict", "patch.npy", "--pixel-mm", "0.05", "--tile"], ("--tile",)),
    (["simulate", "patch.npy", "--pixel-mm", "0.05", "--tile", "--fidelity", "coarse"], ("--tile",)),
    (["jnd", "map.npy:height=1", "map.npy", "--pixel-mm", "0.05"], ("unknown unit",)),
    (["jnd", "map.npy:pixel-mm=0", "map.npy"], ("positive finite",)),
    (["predict", "map.npy", "--pixel-mm", "0.05", "--level", "cubic"], ("--level",)),
]


@pytest.mark.parametrize("argv, names", BAD_SCANS, ids=lambda v: " ".join(v) if isinstance(v, list) else None)
def test_bad_scans_are_refused(argv, names, workdir, capsys):  # noqa: F811
    _bad_scans(workdir)
    _expect_refusal(argv, workdir, capsys, names)

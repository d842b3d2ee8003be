"""Tactile images: a 3-colour picture becomes a plate whose regions' roughness separates (surrogate only: seconds)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from roughness.core.errors import InputError
from roughness.dataset.textures import standard_texture
from roughness.design.evaluation import Evaluator
from roughness.design.tactile_image import compose, flat_colours, hex_colour, outline, plate_labels, tactile_image
from roughness.surface.heightmap import flat

EVALUATOR = Evaluator()
WHITE, GREY, BLACK = (255, 255, 255), (128, 128, 128), (0, 0, 0)


def three_stripes() -> np.ndarray:
    """60 x 24 px: white, grey and black vertical stripes (a 60 mm plate: 20 mm stripes, wider than the footprint)."""
    rgb = np.zeros((24, 60, 3), dtype=np.uint8)
    rgb[:, :20], rgb[:, 20:40], rgb[:, 40:] = WHITE, GREY, BLACK
    return rgb


def test_flat_colours_lightest_first_and_antialiasing_joins_the_nearest():
    rgb = three_stripes()
    rgb[0, 19] = (250, 250, 250)  # one anti-aliased pixel
    colours, labels = flat_colours(rgb)
    assert [tuple(c) for c in colours] == [WHITE, GREY, BLACK]
    assert labels[0, 19] == 0 and labels[5, 30] == 1 and labels[5, 50] == 2
    with pytest.raises(InputError, match="fewer than 2 flat colours"):
        flat_colours(np.zeros((10, 10, 3), dtype=np.uint8))


def test_outlines_are_smooth_raised_lines_along_edges():
    labels = plate_labels(flat_colours(three_stripes())[1], 60.0, 0.1)
    line = outline(labels, 0.1, 1.0, 0.8)
    assert line.max() == pytest.approx(0.8, rel=0.05) and line[:, :150].max() == 0  # nothing far from an edge
    profile = line[100, 190:211]  # across the edge at x = 20 mm
    assert np.all(np.diff(profile[:10]) >= 0) and np.all(np.diff(profile[11:]) <= 0)  # rises and falls smoothly


@pytest.fixture(scope="module")
def plate():
    textures = [(f"standard-{lam}", standard_texture(lam, seed=1), None) for lam in (0.625, 1.0, 1.625)]
    return tactile_image(three_stripes(), textures, width_mm=60.0, pixel_mm=0.1, step_mm=2.0, evaluator=EVALUATOR)


def test_plate_regions_carry_their_textures(plate):
    assert plate.heightmap.size_mm == pytest.approx((60.0, 24.0))
    assert plate.heightmap.heights.min() == pytest.approx(0.0, abs=1e-9)
    lam = [r.texture for r in plate.regions]
    assert lam == ["standard-0.625", "standard-1.0", "standard-1.625"]  # lightest colour: smoothest texture


def test_roughness_map_shows_the_three_regions(plate):
    """Footprints wholly inside a stripe: their V separates (every smoother one below every rougher one)."""
    v = [plate.roughness_map[plate.map_labels == i] for i in range(3)]
    assert all(len(x) >= 4 for x in v)
    assert v[0].max() < v[1].min() and v[1].max() < v[2].min()
    d = plate.distances_jnd("plate")
    # the textures are 2.7 JND apart on the standard scale; the surrogate on the plate reads at least 2
    assert d[1, 0] >= 2.0 and d[2, 1] >= 2.0


def test_plate_is_a_watertight_printable_mesh(plate, tmp_path):
    trimesh = pytest.importorskip("trimesh")
    from roughness.surface.io import save_heightmap

    save_heightmap(plate.heightmap, tmp_path / "plate.stl", base_mm=2.0)
    mesh = trimesh.load(tmp_path / "plate.stl")
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert mesh.extents[0] == pytest.approx(60.0 - 0.1, abs=1e-3)  # pixel centres span the plate less one pixel


def test_too_few_textures_and_too_small_plates_are_refused():
    textures = [("a", standard_texture(1.0, seed=1), None), ("b", standard_texture(1.5, seed=1), None)]
    with pytest.raises(InputError, match="3 flat colours but only 2 textures"):
        tactile_image(three_stripes(), textures, evaluator=EVALUATOR)
    with pytest.raises(InputError, match="smaller than the 10 mm skin footprint"):
        tactile_image(three_stripes(), textures + textures[:1], width_mm=15.0, evaluator=EVALUATOR)


def test_compose_puts_each_texture_on_the_floor():
    labels = np.zeros((50, 100), dtype=int)
    labels[:, 50:] = 1
    a, b = standard_texture(1.0, seed=1), standard_texture(1.0, seed=2)
    relief = compose(labels, [a, b], 0.1)
    assert relief.heights[:, :50].min() >= 0 and relief.heights.max() <= max(np.ptp(a.heights), np.ptp(b.heights))


def test_strain_image_tiles_fem_windows_over_the_plate():
    """A 20 x 12 mm plate: two footprints whose 8 mm strain windows abut (coarse FEM, 2 runs)."""
    rgb = np.zeros((24, 40, 3), dtype=np.uint8)
    rgb[:, :20], rgb[:, 20:] = WHITE, BLACK
    textures = [(f"standard-{lam}", standard_texture(lam, seed=1), None) for lam in (0.625, 1.625)]
    plate = tactile_image(rgb, textures, width_mm=20.0, pixel_mm=0.1, step_mm=2.0, strain=True, evaluator=EVALUATOR)
    ny, nx = plate.strain.shape
    assert nx == 2 * ny and np.isfinite(plate.strain).all()
    left, right = plate.strain[:, : nx // 2], plate.strain[:, nx // 2:]
    assert abs(left.mean()) < 1e-9 and abs(right.mean()) < 1e-9  # each window shown minus its mean
    x0, x1, y1, y0 = plate.strain_extent_mm
    assert (x0, x1, y0, y1) == pytest.approx((1.0, 17.0, 1.0, 9.0))  # centres x 5, 13 mm; y 5 mm


@pytest.mark.parametrize("pixels", [[[0, 255]], [[0], [255]], [[0, 255], [255, 0]], [[0, 255, 0]]])
def test_a_picture_of_a_few_pixels_has_its_flat_colours(pixels):
    """In a picture of one or two rows or columns every pixel is on its border, and none may have like neighbours:
    then every pixel counts (a valid two-pixel, two-colour picture was refused as having no flat colour); noise
    in a larger picture is still refused (tests/test_design_inputs.py)."""
    grey = np.array(pixels, dtype=np.uint8)
    colours, labels = flat_colours(np.repeat(grey[..., None], 3, axis=2))
    assert colours.tolist() == [[255, 255, 255], [0, 0, 0]]
    assert (labels == (grey == 0)).all()
    with pytest.raises(InputError, match="fewer than 2 flat colours"):
        flat_colours(np.zeros((1, 2, 3), dtype=np.uint8))


@pytest.fixture
def two_stripes(tmp_path, monkeypatch):
    """A 2-colour picture file; no project default printer from the tester's environment or config."""
    from PIL import Image

    monkeypatch.delenv("ROUGHNESS_PRINTER", raising=False)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    rgb = np.zeros((24, 60, 3), dtype=np.uint8)
    rgb[:, :30], rgb[:, 30:] = WHITE, BLACK
    Image.fromarray(rgb).save(tmp_path / "picture.png")
    return tmp_path / "picture.png"


def test_a_digital_palette_forecasts_each_member_on_the_common_printers(two_stripes, capsys):
    import json

    from roughness.cli import main
    from roughness.surface.printing import PROFILES

    out = two_stripes.parent / "plate"
    assert main(["tactile-image", str(two_stripes), "--out", str(out), "--verify", "spectral", "--step-mm", "4",
                 "--json", "--quiet"]) == 0
    forecast = json.loads(capsys.readouterr().out)["print_forecast"]
    assert sorted(forecast) == ["texture-1", "texture-2"] and all(sorted(f) == sorted(PROFILES)
                                                                  for f in forecast.values())
    smooth = forecast["texture-1"]
    assert smooth["msla-35um"]["jnd"] == pytest.approx(0, abs=0.5)  # resin keeps the texture
    assert smooth["fdm-0.4-0.2"]["printed_roughness"] < smooth["fdm-0.4-0.2"]["digital_roughness"]  # FDM loses V
    saved = json.loads((out / "palette" / "palette.json").read_text())
    assert saved["print_forecast"] == forecast


def test_tactile_image_with_a_printer_maps_the_printed_plate(two_stripes, capsys):
    import json

    from roughness.cli import main

    out = two_stripes.parent / "plate"
    assert main(["tactile-image", str(two_stripes), "--out", str(out), "--verify", "spectral", "--step-mm", "4",
                 "--printer", "fdm-0.4-0.2", "--background", "none", "--json", "--quiet"]) == 0  # both textured
    summary = json.loads(capsys.readouterr().out)
    assert summary["printer"]["name"] == "fdm-0.4-0.2" and "print_forecast" not in summary
    members = json.loads((out / "palette" / "palette.json").read_text())["members"]
    assert all(m["recipe"]["printer"] == "fdm-0.4-0.2" for m in members)
    for region, member in zip(summary["regions"], members):  # the plate's printed regions feel as the palette's
        assert region["digital_plate_roughness"] is not None
        assert abs(np.log(region["plate_roughness"] / member["fem_roughness"])) < 0.5


def test_with_a_printer_the_plate_is_composed_at_the_textures_pixel():
    """A palette verified as printed tiles at 0.05 mm prints alike only on a plate at that pixel
    (studies/results/print_tactile_image.md: 1.81 JND on a 0.1 mm plate, 2.02 at 0.05 mm): with a printer the
    plate takes the textures' pixel, said in a note; without one, or with --pixel-mm, the pixel is as asked; a
    plate too large at the finer pixel stays at 0.1 mm and says what that costs."""
    from roughness.design.tactile_image import PIXEL_MM, plate_pixel
    from roughness.surface.printing import PROFILES

    fdm, tile = PROFILES["fdm-0.4-0.2"], standard_texture(1.0)
    pixel, note = plate_pixel(None, (40, 60, 3), 60.0, [tile], fdm)
    assert pixel == tile.pixel_mm and "textures' 0.05 mm pixels" in note
    assert plate_pixel(None, (40, 60, 3), 60.0, [tile], None) == (PIXEL_MM, None)
    assert plate_pixel(0.2, (40, 60, 3), 60.0, [tile], fdm) == (0.2, None)
    assert plate_pixel(None, (40, 60, 3), 60.0, [], fdm) == (PIXEL_MM, None)  # lines only: no texture to keep
    pixel, note = plate_pixel(None, (400, 400, 3), 150.0, [tile], fdm)  # 9 M pixels at 0.05 mm, 2.25 M at 0.1
    assert pixel == PIXEL_MM and "too many" in note


def test_the_key_strip_counts_with_the_plate_before_any_palette(tmp_path, capsys):
    """The outlined drawing of the manual at 120 mm with a printer and a key: the plate alone fits at the textures'
    0.05 mm (3.84 M pixels) but not with its 25 mm key strip (5.04 M), which was refused after the palette's FEM.
    The key is now counted: the printer's plate stays at 0.1 mm with the note, and a --pixel-mm that cannot hold
    plate and key is refused before any palette, naming the key."""
    from roughness.cli import main
    from roughness.design.colours import cluster_colours
    from roughness.design.key import SWATCH_MM, key_spec
    from roughness.design.layout import plan_layout
    from roughness.design.tactile_image import PIXEL_MM, key_height, plate_pixel, plate_shape, read_image
    from roughness.surface.printing import PROFILES

    picture = str(Path(__file__).parents[1] / "examples" / "design" / "outlined.png")
    found = cluster_colours(read_image(picture))
    layout = plan_layout(found, 120.0 / found.labels.shape[1], 6.35)
    key_mm = key_height(layout, key_spec(found), 120.0)
    assert len(layout.textured) == 3 and key_mm == pytest.approx(SWATCH_MM + 2 * 5.0)  # three entries in one row
    plate_shape(found.labels.shape, 120.0, 0.05)  # the plate alone fits
    with pytest.raises(InputError, match="with its key"):
        plate_shape(found.labels.shape, 120.0, 0.05, key_mm=key_mm)
    tile = standard_texture(1.0)
    assert plate_pixel(None, found.labels.shape, 120.0, [tile], PROFILES["fdm-0.4-0.2"])[0] == tile.pixel_mm
    pixel, note = plate_pixel(None, found.labels.shape, 120.0, [tile], PROFILES["fdm-0.4-0.2"], key_mm)
    assert pixel == PIXEL_MM and "too many" in note
    code = main(["tactile-image", picture, "--size-mm", "120", "--pixel-mm", "0.05", "--key", "--out",
                 str(tmp_path / "plate")])
    assert code == 2 and "with its key" in capsys.readouterr().err and not (tmp_path / "plate").exists()


def two_halves() -> np.ndarray:
    """40 x 20 px: a white and a black half (a 40 mm plate: 20 mm halves)."""
    rgb = np.zeros((20, 40, 3), dtype=np.uint8)
    rgb[:, :20] = WHITE
    return rgb


@pytest.mark.parametrize("textures, alike", [
    ([("a", standard_texture(1.0, seed=1), None), ("b", standard_texture(1.0, seed=1), None)], True),
    ([("flat", flat(10.0, 0.1), None), ("tall", standard_texture(1.0, seed=1, height_mm=2.0), None)], False)])
def test_regions_look_alike_when_they_carry_one_texture_and_different_when_flat_meets_tall_bumps(textures, alike):
    from roughness.cli.tactile_image import _look_lines

    plate = tactile_image(two_halves(), textures, width_mm=40.0, pixel_mm=0.1, step_mm=4.0, evaluator=EVALUATOR)
    look = plate.looks.matrix
    assert (max(look[0, 1], look[1, 0]) < 1) if alike else (min(look[0, 1], look[1, 0]) >= 1)
    [pair] = plate.summary()["look_pairs"]
    assert pair["a"] == "#ffffff" and pair["b"] == "#000000"
    assert pair["look"]["difference_look_jnd"] == pytest.approx(look[0, 1])
    assert plate.summary()["plate_look_differences_jnd"][1][0] == pytest.approx(look[1, 0], abs=1e-3)
    lines = _look_lines(plate)
    assert len(lines) == 2 and lines[1].startswith("  #ffffff / #000000: look ")
    assert ("(not visible)" if alike else "(visible)") in lines[1]


def test_a_region_too_narrow_to_compare_has_no_look_and_says_why():
    from roughness.cli.tactile_image import _look_lines

    rgb = two_halves()
    rgb[:, 20:22] = GREY  # a 2 mm stripe between the halves: no pixel lies more than 1 mm inside it
    textures = [(f"standard-{lam}", standard_texture(lam, seed=1), None) for lam in (0.625, 1.0, 1.625)]
    plate = tactile_image(rgb, textures, width_mm=40.0, pixel_mm=0.1, step_mm=4.0, evaluator=EVALUATOR)
    grey = [hex_colour(r.colour) for r in plate.regions].index("#808080")
    look = plate.looks.matrix
    assert np.isnan(look[grey]).sum() == 2 and np.isnan(look[:, grey]).sum() == 2  # every pair with it
    summary = plate.summary()
    assert [p["look"] is None for p in summary["look_pairs"]] == [True, False, True]  # white, grey, black pairs
    assert summary["look_unmeasured"] == ["#808080: 0 pixels lie more than 1 mm inside its borders, fewer than the "
                                          "16 needed to compare how it looks"]
    assert sum("look not measured" in line for line in _look_lines(plate)) == 3  # two pairs and the reason

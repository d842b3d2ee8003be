"""Tactile graphics conventions (issue 47): thin strokes become raised lines, the background stays flat, colours
are assigned textures explicitly or by a stated rule."""
from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image, ImageDraw

from roughness.core.errors import InputError
from roughness.dataset.textures import standard_texture
from roughness.design.colours import cluster_colours
from roughness.design.evaluation import Evaluator
from roughness.design.layout import FLAT, Layout, parse_assign, plan_layout
from roughness.design.lines import LineStyle, detect_lines, line_relief, stroke_width, thin_pixels
from roughness.design.tactile_image import tactile_image

WHITE, ORANGE, BLUE, BLACK = (255, 255, 255), (220, 120, 30), (30, 40, 110), (0, 0, 0)


def outlined(stroke_px: int, size: tuple[int, int] = (240, 160)) -> np.ndarray:
    """Two filled shapes on white, each outlined in black ``stroke_px`` wide."""
    image = Image.new("RGB", size, WHITE)
    draw = ImageDraw.Draw(image)
    draw.ellipse((20, 30, 100, 110), fill=ORANGE, outline=BLACK, width=stroke_px)
    draw.rectangle((120, 20, 220, 120), fill=BLUE, outline=BLACK, width=stroke_px)
    return np.asarray(image)


@pytest.mark.parametrize("stroke", [2, 4, 8])
def test_strokes_narrower_than_the_threshold_are_lines_and_wider_ones_are_not(stroke):
    """Threshold 6 px: 2 and 4 px outlines are lines, 8 px ones a region; the shapes' fills never are."""
    found = cluster_colours(outlined(stroke))
    black = [tuple(c) for c in found.colours].index(BLACK)
    lines = detect_lines(found.labels, len(found.colours), 6.0)
    assert lines.colours == ((black,) if stroke < 6 else ())
    assert lines.thin_share[black] == (1.0 if stroke < 6 else 0.0)
    assert max(s for i, s in enumerate(lines.thin_share) if i != black) == 0.0  # fills and background: no strokes


@pytest.mark.parametrize("width", [2, 3, 4, 5, 8])
def test_stroke_width_of_a_straight_stroke(width):
    mask = np.zeros((420, 40), dtype=bool)
    mask[10:410, 15:15 + width] = True  # 400 px long: the ends' bias (about w^2 / 4 over the stroke's w L) is small
    assert stroke_width(mask) == pytest.approx(width, abs=0.34 + width / 400 * 2)
    assert (thin_pixels(mask, width + 0.5) == mask).all() and not thin_pixels(mask, width).any()


def test_a_named_line_colour_is_a_line_whatever_its_width():
    found = cluster_colours(outlined(8))
    layout = plan_layout(found, 0.5, line_colour="#000000")
    assert [tuple(found.colours[i]) for i in layout.line_colours] == [BLACK]
    with pytest.raises(InputError, match="not one of the picture's flat colours"):
        plan_layout(found, 0.5, line_colour="#00ff00")


def test_raised_lines_have_the_set_width_and_height():
    plate_lines = np.zeros((200, 200), dtype=bool)
    plate_lines[:, 95:105] = True  # a 1 mm stroke at 0.1 mm pixels
    relief, clear = line_relief(plate_lines, 0.1, LineStyle(width_mm=1.5, height_mm=1.0, gap_mm=1.0))
    row = relief[100]
    assert row.max() == pytest.approx(1.0)
    assert np.count_nonzero(row) * 0.1 == pytest.approx(1.5, abs=0.2)  # the line's foot: 1.5 mm wide
    assert np.count_nonzero(clear[100]) * 0.1 == pytest.approx(1.5 + 2 * 1.0, abs=0.2)  # and 1 mm clear each side
    assert np.all(np.diff(row[90:100]) >= 0)  # rises smoothly to the centre


def test_background_is_the_border_colour_and_assignments_are_checked():
    found = cluster_colours(outlined(4))
    layout = plan_layout(found, 0.5, 3.0)
    index = {tuple(c): i for i, c in enumerate(found.colours)}
    assert layout.background == index[WHITE] and layout.flat == [index[WHITE]]
    assert layout.textured == [index[ORANGE], index[BLUE]]
    members, rule = layout.members(2)
    assert members == {index[ORANGE]: 0, index[BLUE]: 1} and "lightest" in rule
    assigned = plan_layout(found, 0.5, 3.0, assign={"#1e286e": 1, "#dc781e": 2})
    assert assigned.members(2) == ({index[BLUE]: 0, index[ORANGE]: 1}, "as assigned")
    with pytest.raises(InputError, match="but not to colour"):
        plan_layout(found, 0.5, 3.0, assign={"#1e286e": 1}).members(2)
    with pytest.raises(InputError, match="only 2"):
        plan_layout(found, 0.5, 3.0, assign={"#1e286e": 3, "#dc781e": 1}).members(2)
    assert parse_assign("#ff0000=1,#00ff00=flat\n#0000ff=2") == {"#ff0000": 1, "#00ff00": FLAT, "#0000ff": 2}
    with pytest.raises(InputError, match="is not COLOUR=N"):
        parse_assign("#ff0000=0")


def test_one_colour_beside_a_flat_background_takes_the_rough_end_of_the_palette():
    layout = Layout(2, background=0)
    assert layout.members(2)[0] == {1: 1}
    assert Layout(3, background=0).members(4)[0] == {1: 1, 2: 3}


def test_an_outlined_drawing_makes_a_plate_with_raised_lines_and_a_flat_background():
    found = cluster_colours(outlined(4))
    layout = plan_layout(found, 0.5, 3.0)
    textures = [(f"standard-{lam}", standard_texture(lam, seed=1), None) for lam in (0.625, 1.625)]
    plate = tactile_image(found, textures, width_mm=120.0, pixel_mm=0.2, step_mm=4.0, evaluator=Evaluator(),
                          layout=layout)
    names = {r.colour: r.texture for r in plate.regions}
    assert names == {WHITE: FLAT, ORANGE: "standard-0.625", BLUE: "standard-1.625"}  # black: lines, not a region
    heights, labels = plate.heightmap.heights, plate.labels
    white = [r.colour for r in plate.regions].index(WHITE)
    assert heights[20:40, 20:40].max() == 0.0 and labels[30, 30] == white  # the flat background's corner
    summary = plate.summary()
    assert summary["lines"]["line_colours"] == ["#000000"] and summary["background"] == "#ffffff"
    assert summary["lines"]["stroke_width_mm"][0] == pytest.approx(2.0, abs=0.25)  # 4 px of 0.5 mm
    # the outline's top on the plate: its height, along the disc's edge (x 10..50 mm, y 15..55 mm)
    assert heights[int(35 / 0.2), int(10.5 / 0.2) - 10:int(10.5 / 0.2) + 10].max() == pytest.approx(1.0, abs=0.05)


def test_cli_outlined_drawing(tmp_path, monkeypatch, capsys):
    from roughness.cli import main

    monkeypatch.delenv("ROUGHNESS_PRINTER", raising=False)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    Image.fromarray(outlined(4)).save(tmp_path / "drawing.png")
    (tmp_path / "map.txt").write_text("#dc781e=2\n#1e286e=1\n")
    out = tmp_path / "plate"
    assert main(["tactile-image", str(tmp_path / "drawing.png"), "--out", str(out), "--size-mm", "120",
                 "--pixel-mm", "0.2", "--verify", "spectral", "--step-mm", "4", "--assign", f"@{tmp_path / 'map.txt'}",
                 "--key", "--key-labels", "#dc781e=Sun", "--json", "--quiet"]) == 0
    summary = json.loads(capsys.readouterr().out)
    textures = {r["colour"]: r["texture"] for r in summary["regions"]}
    assert textures == {"#ffffff": "flat", "#dc781e": "texture-2", "#1e286e": "texture-1"}
    assert [(e["label"], e["braille"], e["texture"]) for e in summary["key"]] == [
        ("Sun", "\u2820\u280e\u2825\u281d", "texture-2"), ("b", "\u2803", "texture-1")]  # capital, s, u, n; b
    assert summary["height_mm"] == pytest.approx(80 + 5 + 15 + 5, abs=0.2)  # the picture, then the key strip
    assert summary["lines"]["line_colours"] == ["#000000"] and "textures: as assigned" in summary["notes"]
    assert main(["tactile-image", str(tmp_path / "drawing.png"), "--out", str(tmp_path / "again"),
                 "--assign", "#00ff00=1", "--quiet"]) == 2
    assert "not one of the picture's flat colours" in capsys.readouterr().err


def test_a_region_too_small_is_reported_with_its_size_and_what_helps():
    """A 4 mm dot beside a 20 mm square (textured), on a flat background: the dot is listed, the square not."""
    from roughness.design.readability import MIN_TEXTURE_WIDTH_MM, small_areas

    labels = np.zeros((300, 400), dtype=int)  # 0.1 mm pixels: 40 x 30 mm
    labels[50:250, 50:250] = 1
    yy, xx = np.mgrid[:300, :400]
    labels[(yy - 150) ** 2 + (xx - 320) ** 2 <= 20 ** 2] = 1  # a disc 4 mm across, same colour
    small, specks = small_areas(labels, np.zeros(labels.shape, dtype=bool), 0.1, {1: "#1e286e"})
    assert specks == 0 and len(small) == 1
    dot = small[0]
    assert dot.width_mm == pytest.approx(4.0, abs=0.2) and dot.area_mm2 == pytest.approx(np.pi * 4, rel=0.05)
    assert dot.centre_mm == pytest.approx((32.05, 15.05), abs=0.2)
    assert dot.plate_width_mm == pytest.approx(40 * MIN_TEXTURE_WIDTH_MM / dot.width_mm, abs=1)
    assert "4.0 mm across" in dot.describe() and "--assign #1e286e=flat" in dot.describe()


def test_pages_fit_the_picture_and_the_scale_bar_is_round():
    from roughness.design.pages import page_width, scale_bar_mm

    assert page_width("A4", (160, 240)) == pytest.approx(min(297 - 20, (210 - 20) * 1.5))  # landscape
    assert page_width("letter", (300, 100)) == pytest.approx(min(215.9 - 20, (279.4 - 20) / 3))  # portrait
    with pytest.raises(InputError, match="unknown page"):
        page_width("b5", (10, 10))
    assert [scale_bar_mm(w) for w in (48, 60, 120, 277)] == [5, 10, 20, 50]


GREENS = [(0x1b, 0x5e, 0x20), (0x2e, 0x7d, 0x32), (0x43, 0xa0, 0x47), (0x66, 0xbb, 0x6a)]  # 12 to 15 Delta E apart


def logo() -> np.ndarray:
    """A logo of four flat greens on white, each pair of neighbours in shade 12 to 15 Delta E apart (< 20, the
    default tolerance, at which they used to collapse into two)."""
    rgb = np.full((80, 120, 3), 255, dtype=np.uint8)
    rgb[10:40, 10:55], rgb[10:40, 65:110], rgb[45:70, 10:55], rgb[45:70, 65:110] = GREENS
    return rgb


def test_a_logos_four_flat_colours_survive_the_default_tolerance():
    found = cluster_colours(logo())
    assert sorted(map(tuple, found.colours.tolist())) == sorted(GREENS + [WHITE])
    assert (found.clustered() == logo()).all()  # every pixel keeps its colour


def test_a_logo_at_k_4_gets_four_textures(tmp_path, monkeypatch, capsys):
    from roughness.cli import main

    monkeypatch.delenv("ROUGHNESS_PRINTER", raising=False)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    Image.fromarray(logo()).save(tmp_path / "logo.png")
    assert main(["tactile-image", str(tmp_path / "logo.png"), "--out", str(tmp_path / "plate"), "--k", "4",
                 "--size-mm", "120", "--pixel-mm", "0.2", "--verify", "spectral", "--step-mm", "4", "--json"]) == 0
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    textures = {r["colour"]: r["texture"] for r in summary["regions"]}
    assert textures == {"#ffffff": "flat", "#66bb6a": "texture-1", "#43a047": "texture-2", "#2e7d32": "texture-3",
                        "#1b5e20": "texture-4"}
    assert "#66bb6a, #43a047, #2e7d32, #1b5e20" in captured.err  # the colours found are shown


def test_a_jpeg_of_an_outlined_drawing_has_the_same_lines_and_regions(tmp_path):
    """JPEG noise (quality 75) on 4 px outlines: the black is still one flat colour, found as the lines, and the
    regions are the PNG's."""
    from roughness.design.tactile_image import read_image

    Image.fromarray(outlined(4)).save(tmp_path / "drawing.jpg", quality=75)
    found = cluster_colours(read_image(tmp_path / "drawing.jpg"))
    layout = plan_layout(found, 0.5, 6.35)
    assert len(found.colours) == 4 and len(layout.line_colours) == 1
    assert int(found.colours[layout.line_colours[0]].max()) < 30  # the outlines' colour: black within JPEG noise
    png = plan_layout(cluster_colours(outlined(4)), 0.5, 6.35)
    agree = (layout.lines.mask == png.lines.mask).mean()
    assert agree > 0.98, agree
    assert min(found.colours[layout.background]) >= 245  # the white background, left flat


def test_a_line_drawing_on_white_needs_no_palette(tmp_path, monkeypatch, capsys):
    from roughness.cli import main

    monkeypatch.delenv("ROUGHNESS_PRINTER", raising=False)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    image = Image.new("RGB", (120, 80), WHITE)
    ImageDraw.Draw(image).ellipse((20, 10, 100, 70), outline=BLACK, width=3)
    image.save(tmp_path / "ring.png")
    out = tmp_path / "plate"
    assert main(["tactile-image", str(tmp_path / "ring.png"), "--out", str(out), "--json", "--quiet"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert [r["texture"] for r in summary["regions"]] == ["flat"] and summary["lines"]["line_colours"] == ["#000000"]
    assert not (out / "palette").exists() and summary["relief_mm"] == pytest.approx(1.0, abs=0.01)  # the line alone

"""The guideline report: each rule passes or fails, saying where (surrogate only: seconds)."""
from __future__ import annotations

import numpy as np
import pytest

from roughness.dataset.textures import standard_texture
from roughness.design.colours import cluster_colours
from roughness.design.evaluation import Evaluator
from roughness.design.guidelines import MAX_TEXTURES, check_plate
from roughness.design.layout import plan_layout
from roughness.design.tactile_image import tactile_image

EVALUATOR = Evaluator()


def stripes(n: int, width: int = 20) -> np.ndarray:
    """``n`` vertical stripes of distinct greys, ``width`` pixels each, 24 rows (1 mm pixels on the plate)."""
    rgb = np.zeros((24, n * width, 3), dtype=np.uint8)
    for i in range(n):
        rgb[:, i * width:(i + 1) * width] = 255 - i * 255 // max(n - 1, 1)
    return rgb


def checks_of(plate, min_jnd: float = 2.0) -> dict:
    return {c.rule.split(" ")[0] + " " + c.rule.split(" ")[1]: c for c in check_plate(plate, min_jnd)}


def test_too_many_textures_and_close_neighbours_fail_saying_where():
    lams = [0.625, 0.6875, 1.0, 1.25, 1.5, 1.625]
    textures = [(f"standard-{lam}", standard_texture(lam, seed=1), None) for lam in lams]
    rgb = stripes(6)
    plate = tactile_image(rgb, textures, width_mm=120.0, pixel_mm=0.2, step_mm=2.0, evaluator=EVALUATOR)
    checks = checks_of(plate)
    count = checks["at most"]
    assert not count.passed and count.value == "6" and MAX_TEXTURES == 5
    contrast = checks["neighbours >="]
    d = plate.distances_jnd("plate")
    assert abs(d[0, 1]) < 2  # standard-0.625 and -0.6875 are 0.55 JND apart on the standard scale
    assert not contrast.passed and "#ffffff/#cccccc" in contrast.where
    assert checks["textured areas"].passed  # 20 mm stripes


def test_an_outlined_drawing_passes_and_a_small_area_fails():
    from PIL import Image, ImageDraw

    image = Image.new("RGB", (240, 160), "white")
    draw = ImageDraw.Draw(image)
    draw.rectangle((20, 20, 110, 140), fill=(220, 120, 30), outline="black", width=4)
    draw.rectangle((130, 20, 220, 140), fill=(30, 40, 110), outline="black", width=4)
    draw.ellipse((60, 70, 68, 78), fill=(30, 40, 110))  # a 9 px dot: 4.5 mm on a 120 mm plate
    found = cluster_colours(np.asarray(image))
    textures = [(f"standard-{lam}", standard_texture(lam, seed=1), None) for lam in (0.625, 1.625)]
    plate = tactile_image(found, textures, width_mm=120.0, pixel_mm=0.2, step_mm=2.0, evaluator=EVALUATOR,
                          layout=plan_layout(found, 0.5, 3.0))
    checks = checks_of(plate)
    assert checks["at most"].passed and checks["line width"].passed and checks["line height"].passed
    size = checks["textured areas"]
    assert not size.passed and "#1e286e at (32, 37) mm" in size.where
    assert checks["separate lines"].passed  # the two outlines' bars are 10 mm apart
    assert checks["neighbours >="].passed, checks["neighbours >="]
    merged = tactile_image(found, textures, width_mm=120.0, pixel_mm=0.2, step_mm=2.0, evaluator=EVALUATOR,
                           layout=plan_layout(found, 0.5, 3.0), merge_small=True)
    assert checks_of(merged)["textured areas"].passed and "1 textured area(s)" in " ".join(merged.notes)
    orange = [r.colour for r in merged.regions].index((220, 120, 30))
    assert merged.labels[round(37 / 0.2), round(32 / 0.2)] == orange  # the dot joined the rectangle around it


def test_the_bundled_outlined_drawing_passes_every_guideline():
    """examples/design/outlined.png (three shapes, 4 px black outlines, on white) with smooth edges and a key:
    lines found, background flat, every rule passes (standard textures 2.7 JND apart on the scale)."""
    from pathlib import Path

    from roughness.design.key import KeySpec
    from roughness.design.lines import MAX_STROKE_MM
    from roughness.design.tactile_image import read_image

    found = cluster_colours(read_image(Path(__file__).resolve().parents[1] / "examples" / "design" / "outlined.png"))
    layout = plan_layout(found, 0.5, MAX_STROKE_MM)
    textures = [(f"standard-{lam}", standard_texture(lam, seed=1), None) for lam in (0.625, 1.0, 1.625)]
    plate = tactile_image(found, textures, width_mm=120.0, pixel_mm=0.2, step_mm=2.0, evaluator=EVALUATOR,
                          layout=layout, key=KeySpec(), smooth_edges=True)
    assert [tuple(found.colours[i]) for i in layout.line_colours] == [(0, 0, 0)]
    assert [e.label for e in plate.key] == ["a", "b", "c"]
    checks = check_plate(plate)
    assert len(checks) == 7 and all(c.passed for c in checks), [c.describe() for c in checks if not c.passed]


def test_a_flat_region_is_as_far_from_a_texture_in_the_table_as_in_the_contrast_check():
    """V of a flat region is 0; the table counts it at the scale's floor as the check does, not as a wavelength
    far below any a fingertip tells apart (the table said 25.5 JND where the check said 3.8)."""
    from roughness.perceptual_scale import FLOOR_LAMBDA_MM, jnd

    plate = tactile_image(stripes(2), [None, ("standard-1.0", standard_texture(1.0, seed=1), None)], width_mm=60.0,
                          pixel_mm=0.2, step_mm=2.0, evaluator=EVALUATOR)
    flat, textured = plate.felt_lambdas_mm("plate")
    assert flat == FLOOR_LAMBDA_MM and textured >= FLOOR_LAMBDA_MM
    d = plate.distances_jnd("plate")
    assert d[0, 1] == pytest.approx(jnd(FLOOR_LAMBDA_MM, textured)) and d[0, 1] == -d[1, 0]
    contrast = checks_of(plate)["neighbours >="]
    assert f"{abs(d[0, 1]):.2f}" in contrast.value

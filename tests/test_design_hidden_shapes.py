"""Seen but not felt, felt but not seen (roughness.design.hidden_shapes), and the masks and contact gap it uses."""
from __future__ import annotations

import numpy as np
import pytest

from roughness.core.errors import InputError
from roughness.dataset.textures import standard_texture
from roughness.design.hidden_shapes import MATCH_JND, default_base, hidden_plate, lay
from roughness.design.shapes import SHAPES, builtin_mask, check_mask, inscribed_width_mm, picture_mask
from roughness.simulate.spectral.gap import contact_gap
from roughness.surface.heightmap import Heightmap, flat

PLATE_MM, SPAN, STEP_MM = 30.0, 0.4, 2.0


@pytest.fixture(scope="module")
def tile():
    return default_base()


@pytest.fixture(scope="module")
def circle(tile):
    n = round(PLATE_MM / tile.pixel_mm)
    return builtin_mask("circle", (n, n), SPAN)


@pytest.fixture(scope="module")
def seen(tile, circle):
    return hidden_plate(tile, circle, "seen", step_mm=STEP_MM)


@pytest.mark.parametrize("name", SHAPES)
def test_builtin_shapes_are_centred_and_span_what_they_say(name):
    mask = builtin_mask(name, (200, 200), 0.5)
    rows, cols = np.nonzero(mask)
    assert (rows.min() + rows.max()) / 2 == pytest.approx(99.5, abs=1)  # its box is centred
    assert (cols.min() + cols.max()) / 2 == pytest.approx(99.5, abs=1)
    assert cols.max() - cols.min() + 1 == pytest.approx(100, abs=2)


def test_a_picture_mask_is_its_dark_pixels_scaled_to_the_plate():
    rgb = np.full((10, 20, 3), 255, np.uint8)
    rgb[:, :10] = 0
    mask = picture_mask(rgb, (50, 100))
    assert mask[:, :49].all() and not mask[:, 51:].any()


@pytest.mark.parametrize("mask", [np.zeros((40, 40), bool), np.ones((40, 40), bool)], ids=["nothing", "all"])
def test_a_mask_that_is_all_or_nothing_is_refused(tile, mask):
    with pytest.raises(InputError, match="covers (none|all) of the plate"):
        check_mask(mask)
    with pytest.raises(InputError, match="covers (none|all) of the plate"):
        hidden_plate(tile, mask, "seen")


def test_the_inscribed_width_counts_the_plate_edge_as_the_shapes():
    mask = np.zeros((100, 100), bool)
    mask[:20, :40] = True  # 2 x 4 mm at 0.1 mm pixels, in a corner
    assert inscribed_width_mm(mask, 0.1) == pytest.approx(2.0, abs=0.1)


def test_the_skin_touches_a_flat_plate_everywhere_and_stays_above_a_deep_pit():
    assert contact_gap(flat(12.0, 0.1)).contact_fraction == 1.0
    h = np.zeros((240, 240))
    h[118:122, 118:122] = -1.0  # 0.2 mm wide, 1 mm deep: wider pits the soft skin fills
    gap = contact_gap(Heightmap(h, 0.05))
    assert gap.gap_mm[120, 120] > 0.5 and gap.in_contact[0, 0] and not gap.in_contact[120, 120]


def test_a_seen_plate_changes_only_the_floor_the_skin_does_not_reach_inside_the_shape(tile, circle, seen):
    base = lay(tile, circle.shape).heights
    change = seen.heightmap.heights - seen.change["recess_mm"] - base  # the plate stands on its lowest point
    lowered = change < -1e-9
    assert lowered.any() and not (lowered & ~circle).any()
    assert np.allclose(change[~lowered], 0.0, atol=1e-12) and np.allclose(change[lowered], -seen.change["recess_mm"])


def test_a_seen_plate_is_seen_and_not_felt(seen):
    claims = {c.claim: c for c in seen.checks}
    assert all(c.passed for c in seen.checks), claims
    assert abs(seen.feel.jnd) <= MATCH_JND
    assert seen.look.difference >= 1 > seen.base_look.difference
    assert seen.change["contact_pixels_changed"] < 1e-3 * seen.heightmap.heights.size


def test_a_base_in_full_contact_is_refused_with_the_change_that_makes_room():
    standard = standard_texture(1.0)
    assert contact_gap(lay(standard, (240, 240))).contact_fraction == 1.0
    mask = builtin_mask("circle", (240, 240))
    with pytest.raises(InputError, match=r"touches 100\.0% .* Least change .* heights x \d\.\d\d"):
        hidden_plate(standard, mask, "seen")


def test_a_shape_smaller_than_a_fingertip_touching_the_plates_edge_is_flagged(tile):
    n = round(PLATE_MM / tile.pixel_mm)
    mask = np.zeros((n, n), bool)
    mask[:160, :160] = True  # 8 mm square in the corner
    plate = hidden_plate(tile, mask, "seen", step_mm=STEP_MM)
    assert not plate.feelable and plate.inscribed_mm == pytest.approx(8.0, abs=0.1)
    assert any("too small to feel" in n and "at 1.25 times" in n for n in plate.notes)
    assert any("centred in it" in n for n in plate.notes)  # no sampling window fits inside it
    assert plate.inside is not None and plate.look.difference >= 1


def test_a_felt_plate_is_felt_with_the_look_change_reported(tile, circle):
    plate = hidden_plate(tile, circle, "felt", step_mm=STEP_MM, laterals=(0.8,))
    assert abs(plate.feel.jnd) >= 2 - 0.1 - 2 * plate.feel.jnd_stderr
    kept = plate.change[f"{plate.change['target_jnd']:+g} JND"]
    assert kept["look_jnd"] == min(c["look"]["difference_look_jnd"] for c in kept["candidates"] if c["reached"])
    assert plate.look.difference > 0


def test_the_command_writes_every_plate_file_and_the_measures(tmp_path, capsys):
    import json

    import trimesh

    from roughness.cli import main

    out = tmp_path / "plate"
    code = main(["hidden-shapes", "--shape", "square", "--mode", "seen", "--size-mm", "24", "--step-mm", "4",
                 "--out", str(out), "--json", "--quiet"])
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert {p.name for p in out.iterdir()} == {"seen.npz", "seen.stl", "seen.3mf", "seen.png", "hidden_shapes.json"}
    seen = summary["seen"]
    assert seen["look"]["difference_look_jnd"] >= 1 and seen["feel"]["inside"]["positions"] > 0
    assert [c["claim"].split(":")[0] for c in seen["checks"]] == ["look", "feel", "contact", "homogeneity"]
    mesh = trimesh.load(out / "seen.3mf", force="mesh")
    assert mesh.is_watertight and mesh.bounds[1][0] == pytest.approx(24 - 0.025, abs=0.03)
    assert main(["hidden-shapes", "--shape", "square", "--out", str(out)]) == 2  # nothing replaced without --overwrite

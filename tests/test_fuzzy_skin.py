"""Fuzzy skin walls against the slicers' rules (roughness.surface.fuzzy_skin), their settings from slicer configs,
and their feel (roughness.fuzzy_feel, ``roughness fuzzy-skin``)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.curvature_correction import for_base
from roughness.fuzzy_feel import fuzzy_skin_feel
from roughness.surface.fuzzy_noise import Lattice
from roughness.surface.fuzzy_skin import FuzzySkin, fuzzy_points, fuzzy_wall
from roughness.surface.printing import PROFILES, FdmProfile
from roughness.surface.slicer_config import read_slicer_config

FDM = PROFILES["fdm-0.4-0.2"]
LONG_MM = 2000.0  # a long perimeter: thousands of points for the statistics


def points(skin: FuzzySkin, seed: int = 0, z: float = 0.1):
    return fuzzy_points(skin, LONG_MM, z, FDM.line_width_mm, seed, np.random.default_rng(seed))


def test_point_spacing_follows_the_slicers_rule():
    d = 0.8
    layer = points(FuzzySkin(0.3, d))
    gaps = np.diff(layer.x_mm)
    assert gaps.min() >= 0.75 * d and gaps.max() <= 1.25 * d
    # uniform on [3/4, 5/4] d: mean d, standard deviation d / (2 sqrt 12); the mean within 5 standard errors
    assert abs(gaps.mean() - d) < 5 * d / (2 * math.sqrt(12)) / math.sqrt(len(gaps))
    starts = [points(FuzzySkin(0.3, d), seed).x_mm[0] for seed in range(50)]
    assert min(starts) >= 0 and max(starts) < 3 / 8 * d


def test_classic_offsets_are_uniform_within_the_thickness():
    t = 0.3
    r = points(FuzzySkin(t, 0.4)).offset_mm
    n = len(r)
    assert np.abs(r).max() <= t
    counts, _ = np.histogram(r, bins=4, range=(-t, t))
    assert np.all(np.abs(counts - n / 4) < 5 * math.sqrt(n * 0.25 * 0.75))  # binomial, 5 sigma


def test_coherent_noise_bounds_and_character():
    t = 0.3
    ridged = points(FuzzySkin(t, 0.4, "ridgedmulti", octaves := 4)).offset_mm
    assert ridged.min() >= -t and ridged.max() <= t * (1.25 * sum(2.0**-k for k in range(octaves)) - 1)
    billow = points(FuzzySkin(t, 0.4, "billow", 1.0, 4, 0.5)).offset_mm
    assert billow.min() >= t * (0.5 - sum(0.5**k for k in range(4)))  # each octave's 2|n| - 1 >= -1
    voronoi = points(FuzzySkin(t, 0.4, "voronoi", 5.0)).offset_mm
    assert np.abs(voronoi).max() <= t
    # a cell's value is held over the cell: far fewer values than points where cells are many points long
    assert len(np.unique(voronoi)) < len(voronoi) / 4
    lattice = Lattice(7)
    grid = np.arange(-5, 6, dtype=float)
    assert np.all(lattice.gradient(grid, grid[::-1], grid * 2) == 0)  # gradient noise vanishes on the lattice
    perlin = points(FuzzySkin(t, 0.4, "perlin", 1.0, 4, 0.5)).offset_mm
    # each octave's gradient noise stays within about +/-1 (0.99 the largest of 500,000 samples): 10% margin
    assert np.abs(perlin).max() <= t * sum(0.5**k for k in range(4)) * 1.1
    assert abs(np.mean(perlin)) < 0.1 * t and np.std(perlin) > 0.1 * t


def _layer_rows(wall):
    per = round(wall.profile.layer_mm / wall.heightmap.pixel_mm)
    return wall.heightmap.heights.reshape(-1, per, wall.heightmap.shape[1]), per


def test_thickness_zero_is_the_plain_printed_wall():
    wall = fuzzy_wall(FuzzySkin(0.0, 0.8), FDM)
    layers, per = _layer_rows(wall)
    h = FDM.layer_mm
    u = (np.arange(per) + 0.5) * wall.heightmap.pixel_mm - h / 2
    bead = np.sqrt((h / 2) ** 2 - u**2) - h / 2  # the bead's semicircular face, crest at 0
    assert np.allclose(layers, bead[None, :, None], atol=1e-12)


def test_the_bead_is_swept_along_each_layers_path():
    """Each row is the envelope of disks on the path (straight lines between the points, across the tile's end):
    never below the path lifted by the row's disk, never above its highest point lifted so."""
    wall = fuzzy_wall(FuzzySkin(0.3, 0.3), FDM)
    layers, per = _layer_rows(wall)
    h, w, pixel = FDM.layer_mm, FDM.line_width_mm, wall.heightmap.pixel_mm
    x = (np.arange(wall.heightmap.shape[1]) + 0.5) * pixel
    u = (np.arange(per) + 0.5) * pixel - h / 2
    lift = (w - h) / 2 + np.sqrt((h / 2) ** 2 - u**2) - w / 2
    for layer, rows in zip(wall.layers, layers):
        xp = np.concatenate((layer.x_mm - 12.0, layer.x_mm, layer.x_mm + 12.0))
        path = np.interp(x, xp, np.tile(layer.offset_mm, 3))
        assert np.all(rows >= path[None, :] + lift[:, None] - 1e-12)
        assert np.all(rows <= layer.offset_mm.max() + lift[:, None] + 1e-12)


def test_layers_that_do_not_divide_the_pixels():
    """0.12 mm layers on 0.05 mm pixels: the tile is whole layers (5 span 12 pixels), each row on its layer's bead."""
    profile = FdmProfile("fdm-0.4-0.12", 0.4, 0.12, 0.45, 0.049)
    wall = fuzzy_wall(FuzzySkin(0.0, 0.8), profile)
    ny, nx = wall.heightmap.shape
    assert nx == 240 and ny % 12 == 0 and ny * 0.05 >= 12.0 and len(wall.layers) == ny // 12 * 5
    y = (np.arange(ny) + 0.5) * 0.05
    u = y - (np.floor(y / 0.12) + 0.5) * 0.12
    assert np.allclose(wall.heightmap.heights, (np.sqrt(0.06**2 - u**2) - 0.06)[:, None], atol=1e-12)


def test_without_the_bead_each_row_is_its_layers_path():
    wall = fuzzy_wall(FuzzySkin(0.3, 0.3), FDM, bead=False)
    layers, per = _layer_rows(wall)
    x = (np.arange(wall.heightmap.shape[1]) + 0.5) * wall.heightmap.pixel_mm
    for layer, rows in zip(wall.layers, layers):
        xp = np.concatenate((layer.x_mm - 12.0, layer.x_mm, layer.x_mm + 12.0))
        assert np.allclose(rows, np.interp(x, xp, np.tile(layer.offset_mm, 3))[None, :], atol=1e-12)


def test_layers_each_have_their_own_displacement():
    wall = fuzzy_wall(FuzzySkin(0.3, 0.8), FDM)
    layers, per = _layer_rows(wall)
    middle = layers[:, per // 2]
    within = np.corrcoef(layers[:, 0].ravel(), middle.ravel())[0, 1]  # rows of one layer: one path
    across = np.corrcoef(middle[:-1].ravel(), middle[1:].ravel())[0, 1]  # neighbouring layers: new numbers
    assert within > 0.9 and abs(across) < 0.15  # ~900 independent points: standard error ~0.03
    perlin = fuzzy_wall(FuzzySkin(0.3, 0.8, "perlin", 2.0), FDM)
    coherent, _ = _layer_rows(perlin)
    mid = coherent[:, per // 2]
    assert np.corrcoef(mid[:-1].ravel(), mid[1:].ravel())[0, 1] > 0.5  # Orca's noise is a function of z too


def test_modes_move_the_outer_face_as_orca_does():
    kwargs = dict(fuzzy_skin_thickness=0.3, fuzzy_skin_point_distance=0.8)
    moved = points(FuzzySkin(**kwargs)).offset_mm
    extruded = points(FuzzySkin(**kwargs, fuzzy_skin_mode="extrusion")).offset_mm
    combined = points(FuzzySkin(**kwargs, fuzzy_skin_mode="combined")).offset_mm
    assert np.allclose(extruded, (moved + 0.01) / 2) and np.allclose(combined, moved + 0.01)


def test_thick_skin_beyond_the_nozzle():
    t = 0.8  # twice the 0.4 mm nozzle
    wall = fuzzy_wall(FuzzySkin(t, 0.8), FDM)
    heights = wall.heightmap.heights
    assert heights.max() <= t + 1e-12 and heights.min() >= -t - FDM.layer_mm / 2
    thick = fuzzy_skin_feel(FuzzySkin(t, 0.8), FDM, "spectral")
    usual = fuzzy_skin_feel(FuzzySkin(0.3, 0.8), FDM, "spectral")
    # rougher beyond the draw-to-draw spread (3 draws each: 3 combined standard deviations)
    assert thick.roughness - usual.roughness > 3 * math.hypot(thick.draw_std, usual.draw_std)


@pytest.mark.parametrize("seed", [0, 1])
def test_points_closer_than_the_line_feel_smoother(seed):
    """At a point distance below the 0.45 mm line V falls (spectral engine; the bead is not why: without it V is
    within 1%, studies/results/fuzzy_skin.md)."""
    fine = fuzzy_skin_feel(FuzzySkin(0.3, 0.2), FDM, "spectral", seed, draws=1).predictions[0]
    usual = fuzzy_skin_feel(FuzzySkin(0.3, 0.8), FDM, "spectral", seed, draws=1).predictions[0]
    margin = 5 * math.hypot(fine.roughness_stderr, usual.roughness_stderr)
    assert fine.roughness < usual.roughness - margin
    assert fine.placement.equivalent_lambda_mm < usual.placement.equivalent_lambda_mm


def test_bad_settings_are_refused():
    for bad in (dict(fuzzy_skin_thickness=-0.1), dict(fuzzy_skin_point_distance=0.0),
                dict(fuzzy_skin_noise_type="ripple"), dict(fuzzy_skin_octaves=2.5), dict(fuzzy_skin_mode="x")):
        with pytest.raises(InputError):
            FuzzySkin(**bad)
    with pytest.raises(InputError, match="FDM"):
        fuzzy_wall(FuzzySkin(), PROFILES["msla-35um"])
    with pytest.raises(InputError, match="fewer than 2 pixels"):
        fuzzy_wall(FuzzySkin(), FDM, pixel_mm=0.12)
    with pytest.raises(InputError, match="MAX_HEIGHTMAP_PIXELS"):  # refused before anything is allocated
        fuzzy_wall(FuzzySkin(), FDM, tile_mm=200.0, pixel_mm=0.01)


PRUSA_INI = """# generated by PrusaSlicer 2.9.4
fuzzy_skin = external
fuzzy_skin_point_dist = 0.6
fuzzy_skin_thickness = 0.25
layer_height = 0.15
nozzle_diameter = 0.6,0.4
external_perimeter_extrusion_width = 450%
"""
ORCA = {"fuzzy_skin": "external", "fuzzy_skin_thickness": "0.35", "fuzzy_skin_point_distance": "0.5",
        "fuzzy_skin_noise_type": "billow", "fuzzy_skin_scale": "2", "fuzzy_skin_octaves": "3",
        "fuzzy_skin_persistence": "0.4", "fuzzy_skin_mode": "combined", "layer_height": "0.2",
        "nozzle_diameter": ["0.4"], "outer_wall_line_width": "110%", "print_settings_id": "ignored"}


def test_prusaslicer_ini(tmp_path):
    path = tmp_path / "p.ini"
    path.write_text(PRUSA_INI)
    read = read_slicer_config(path)
    assert (read.skin.fuzzy_skin_thickness, read.skin.fuzzy_skin_point_distance) == (0.25, 0.6)
    assert (read.profile.nozzle_mm, read.profile.layer_mm) == (0.6, 0.15)
    assert read.profile.line_width_mm == pytest.approx(4.5 * 0.15)  # PrusaSlicer: % of the layer height
    path.write_text(PRUSA_INI.replace("external_perimeter_extrusion_width = 450%", "extrusion_width = 0"))
    assert read_slicer_config(path).profile.line_width_mm == pytest.approx(1.125 * 0.6)


def test_orcaslicer_json(tmp_path):
    path = tmp_path / "o.json"
    path.write_text(json.dumps(ORCA))
    read = read_slicer_config(path)
    assert read.skin == FuzzySkin(0.35, 0.5, "billow", 2.0, 3, 0.4, "combined")
    assert read.profile.line_width_mm == pytest.approx(0.44) and read.notes == ()  # Orca: % of the nozzle
    path.write_text(json.dumps({**ORCA, "fuzzy_skin": "none"}))
    assert "off" in read_slicer_config(path).notes[0]
    path.write_text(json.dumps({**ORCA, "wall_generator": "classic"}))  # the mode is Arachne's only
    classic = read_slicer_config(path)
    assert classic.skin.fuzzy_skin_mode == "displacement" and "Arachne" in classic.notes[0]


@pytest.mark.parametrize("change, message", [
    ({"layer_height": None}, "layer_height is missing"), ({"fuzzy_skin_thickness": "thick"}, "must be a number"),
    ({"fuzzy_skin_noise_type": "ripple"}, "fuzzy_skin_noise_type must be one of"),
    ({"fuzzy_skin_octaves": "2.5"}, "whole number"), ({"layer_height": "0.6"}, "layer_mm"),
    ({"fuzzy_skin_thickness": "nan"}, "must be a number")])
def test_bad_configs_are_refused(tmp_path, change, message):
    values = {k: v for k, v in {**ORCA, **change}.items() if v is not None}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(values))
    with pytest.raises(InputError, match=message):
        read_slicer_config(path)


def test_command(tmp_path, capsys):
    config = tmp_path / "p.ini"
    config.write_text(PRUSA_INI.replace("0.15", "0.2").replace("450%", "0.45"))
    out = tmp_path / "wall.npz"
    args = ["fuzzy-skin", "--config", str(config), "--engine", "spectral", "--out", str(out), "--json"]
    assert main(args) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["fuzzy_skin"]["fuzzy_skin_thickness"] == 0.25 and result["printer"]["layer_mm"] == 0.2
    low, high = result["equivalent_lambda_range_mm"]
    assert low < result["equivalent_lambda_mm"] < high
    assert result["equivalent_lambda_mm"] > 0 and result["roughness_draw_std"] > 0 and result["engine_error"] > 0 and out.is_file()
    assert main(args) == 2 and "--overwrite" in capsys.readouterr().err  # nothing overwritten unasked
    plot = tmp_path / "sweep.png"
    assert main(["fuzzy-skin", "--engine", "spectral", "--quiet", "--sweep-thickness", "0.1,0.4", "--plot",
                 str(plot)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.startswith("fuzzy skin classic, thickness 0.1") for line in lines[2:]] == [True, False]
    assert "JND" in lines[2] and "lambda" in lines[3] and plot.stat().st_size > 0
    assert main(["fuzzy-skin", "--plot", str(tmp_path / "one.png")]) == 2  # a plot needs a sweep
    assert "--plot" in capsys.readouterr().err
    assert main(["fuzzy-skin", "--config", str(tmp_path / "none.ini")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_a_cylinder_corrects_the_flat_wall_as_predict_does():
    flat = fuzzy_skin_feel(FuzzySkin(0.3, 0.8), FDM, "spectral", draws=2)
    wide = fuzzy_skin_feel(FuzzySkin(0.3, 0.8), FDM, "spectral", draws=2, radius_mm=5000.0)
    assert abs(wide.roughness - flat.roughness) <= flat.engine_error  # a large radius: the flat wall
    convex = fuzzy_skin_feel(FuzzySkin(0.3, 0.8), FDM, "spectral", draws=2, radius_mm=5.0)
    concave = fuzzy_skin_feel(FuzzySkin(0.3, 0.8), FDM, "spectral", draws=2, radius_mm=-8.0)
    for curved in (convex, concave):
        fix = for_base(curved.radius_mm, "cylinder")
        assert curved.roughness == pytest.approx(flat.roughness * fix.factor, rel=1e-12)
        assert math.copysign(1, curved.roughness - flat.roughness) == math.copysign(1, fix.factor - 1)
        assert curved.uncertainty > flat.uncertainty * fix.factor  # the correction's error is counted
    assert convex.roughness > flat.roughness > concave.roughness  # the study: convex rougher, concave smoother
    for bad, message in ((2.0, "measured range"), (-4.0, "cannot rest"), (0.0, "signed radius")):
        with pytest.raises(InputError, match=message):
            fuzzy_skin_feel(FuzzySkin(), FDM, "spectral", draws=1, radius_mm=bad)


def _project(path, members: dict[str, str | bytes]):
    """A tiny 3MF project: a zip of ``members`` (name: text) beside a placeholder model."""
    import zipfile

    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("3D/3dmodel.model", "<model/>")
        for name, text in members.items():
            archive.writestr(name, text)
    return path


def test_3mf_projects(tmp_path):
    """PrusaSlicer embeds its .ini with each line as '; key = value'; Orca and Bambu Studio embed their JSON."""
    prusa = "; generated by PrusaSlicer 2.9.4\n\n" + "".join(f"; {line}\n" for line in PRUSA_INI.splitlines()[1:])
    read = read_slicer_config(_project(tmp_path / "p.3mf", {"Metadata/Slic3r_PE.config": prusa}))
    assert read.skin == read_slicer_config(_written(tmp_path / "p.ini", PRUSA_INI)).skin
    assert (read.profile.nozzle_mm, read.profile.layer_mm) == (0.6, 0.15) and "Slic3r_PE.config" in read.notes[0]
    orca = _project(tmp_path / "o.3mf", {"Metadata/project_settings.config": json.dumps(ORCA),
                                         "Metadata/model_settings.config": "<config/>"})
    read = read_slicer_config(orca)
    assert read.skin == FuzzySkin(0.35, 0.5, "billow", 2.0, 3, 0.4, "combined")
    assert any("per-object" in n for n in read.notes)


def test_3mf_without_a_config_or_too_large_is_refused(tmp_path, capsys):
    from roughness.surface.slicer_config import MAX_EMBEDDED_BYTES

    with pytest.raises(InputError, match="has no slicer config"):
        read_slicer_config(_project(tmp_path / "bare.3mf", {}))
    bomb = _project(tmp_path / "bomb.3mf", {"Metadata/Slic3r_PE.config": b"\0" * (MAX_EMBEDDED_BYTES + 1)})
    assert bomb.stat().st_size < MAX_EMBEDDED_BYTES / 100  # zeros deflate ~1000:1
    with pytest.raises(InputError, match="not unpacked"):
        read_slicer_config(bomb)
    with pytest.raises(InputError, match="as a 3MF project"):
        read_slicer_config(_written(tmp_path / "text.3mf", "not a zip"))
    assert main(["fuzzy-skin", "--config", str(tmp_path / "bare.3mf")]) == 2
    assert "--config" in capsys.readouterr().err


def _written(path, text: str):
    path.write_text(text)
    return path

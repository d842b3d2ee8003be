"""How each part of a textured object feels (issue 30): curvature at the footprint's scale, the roughness map,
the curvature correction shared with predict --curvature-mm, and the object feel/tune commands."""
from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from roughness import curvature_correction as correction  # noqa: E402
from roughness.core.errors import InputError  # noqa: E402
from roughness.core.hashing import file_sha256  # noqa: E402
from roughness.dataset.textures import standard_texture  # noqa: E402
from roughness.objects.curvature import SurfaceSamples, principal_curvatures  # noqa: E402
from roughness.objects.feel import CANNOT_REST, OFF_OBJECT, feel_map  # noqa: E402
from roughness.prediction import PredictOptions, predict  # noqa: E402

ROOT = Path(__file__).parents[1]
TEXTURE = standard_texture(1.0, seed=0)  # 12 mm, periodic: one tile of 1 mm bumps


class Planar:
    """The texture projected straight down on faces facing up (x, y of the texture = x, y of the mesh)."""

    pixel_mm = TEXTURE.pixel_mm

    def heights(self, points, normals):
        return np.where(normals[:, 2] > 0.9, TEXTURE.sample(points[:, 0], points[:, 1], periodic=True), 0.0)


class Wrap:
    """The texture wrapped exactly around the z axis: x = arc length R theta, y = z."""

    pixel_mm = TEXTURE.pixel_mm

    def __init__(self, radius_mm: float):
        self.radius_mm = radius_mm

    def heights(self, points, normals):
        theta = np.arctan2(points[:, 1], points[:, 0])
        return TEXTURE.sample(theta * self.radius_mm, points[:, 2], periodic=True)


def _cylinder(radius_mm: float, height_mm: float = 50.0, inside: bool = False):
    mesh = trimesh.creation.cylinder(radius=radius_mm, height=height_mm, sections=180)
    if inside:  # the bore of a tube: the surface faces the axis, concave
        mesh.invert()
    return mesh, np.abs(mesh.face_normals[:, 2]) < 0.1


def _plate_v(x_mm: float, y_mm: float) -> tuple[float, float]:
    """The flat plate's spectral V (and Monte Carlo error) with the footprint centred at (x, y) of the texture."""
    [p] = predict(TEXTURE, engine="spectral", options=PredictOptions(tile=True, centre_mm=(x_mm % 12.0, y_mm % 12.0)))
    return p.roughness, p.roughness_stderr


# Curvature at the footprint's scale

def test_principal_curvatures_of_a_sphere_a_cylinder_and_a_plane_are_exact():
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=10.0)
    p = np.array([[0, 0, 10.0], [10 / math.sqrt(3)] * 3])
    c = principal_curvatures(SurfaceSamples.of(sphere), p, p / 10)
    assert np.allclose(c.k1, 0.1, rtol=0.01) and np.allclose(c.k2, 0.1, rtol=0.01)  # measured: 0.2%
    cylinder, _ = _cylinder(8.0)
    p = np.array([[8, 0, 0.0], [0, 8, 5.0]])
    c = principal_curvatures(SurfaceSamples.of(cylinder), p, p * [1, 1, 0] / 8)
    assert np.allclose(c.k1, 1 / 8, rtol=0.01) and np.allclose(c.k2, 0, atol=1e-3)
    assert np.all(np.abs(c.d2[:, 2]) > 0.999)  # the straight direction runs along the axis
    bore, _ = _cylinder(8.0, inside=True)
    c = principal_curvatures(SurfaceSamples.of(bore), p, -p * [1, 1, 0] / 8)
    assert np.allclose(c.k2, -1 / 8, rtol=0.01) and np.allclose(c.k1, 0, atol=1e-3)
    box = trimesh.creation.box([40, 40, 10])
    c = principal_curvatures(SurfaceSamples.of(box), [[3, -2, 5.0]], [[0, 0, 1.0]])
    assert abs(c.k1[0]) < 1e-9 and abs(c.k2[0]) < 1e-9
    assert np.allclose(c.d1[0], [1, 0, 0]) and np.allclose(c.d2[0], [0, 1, 0])  # turned, never mirrored


# The roughness map

def test_a_large_flat_face_gives_the_flat_plates_V_within_the_monte_carlo_error():
    box = trimesh.creation.box([40, 40, 6])
    top = box.face_normals[:, 2] > 0.9
    feel = feel_map(box, Planar(), {"top": top}, spacing_mm=8.0)
    inner = [i for i, m in enumerate(feel.method) if m != "refused"]
    assert len(inner) >= 9 and all(feel.method[i] == "flat" for i in inner)
    for i in inner:
        v, se = _plate_v(*feel.points[i][:2])
        assert abs(feel.roughness[i] - v) <= 2 * math.hypot(se, feel.uncertainty[i]), (feel.points[i], v)
    # footprints that would hang over the edge of the top face are refused as off the object
    assert set(feel.refusals()) == {OFF_OBJECT}
    [row] = feel.table()
    assert row.name == "top" and row.area_mm2 == pytest.approx(1600) and 0 < row.refused_fraction < 1


def test_with_the_surrogate_the_map_loads_the_model_once_and_answers_as_the_surrogate_flat(monkeypatch):
    """engine="surrogate": each footprint's V is the surrogate's answer for the unrolled texture, from one model
    loaded once for the whole map (not once per batch of footprints)."""
    from roughness.objects import feel as feel_module
    from roughness.surrogate import predictor

    loads = []
    original = predictor.SurrogateModel.__init__

    def counted(self, *args, **kwargs):
        loads.append(1)
        original(self, *args, **kwargs)

    monkeypatch.setattr(predictor.SurrogateModel, "__init__", counted)
    monkeypatch.setattr(feel_module, "BATCH_POINTS", 2)  # several batches (the module itself: after the studio's
    # tests the dotted path "roughness.objects..." no longer resolves as attributes of the package)
    box = trimesh.creation.box([40, 40, 6])
    feel = feel_map(box, Planar(), {"top": box.face_normals[:, 2] > 0.9}, spacing_mm=8.0, engine="surrogate",
                    reference="standard-1.0")
    inner = [i for i, m in enumerate(feel.method) if m != "refused"]
    assert len(inner) >= 9 and len(loads) == 1
    for i in inner:  # the unrolled footprint is the plate's, sampled at the same points up to float round-off
        x, y = feel.points[i][:2]
        [p] = predict(TEXTURE, engine="surrogate", options=PredictOptions(tile=True, centre_mm=(x % 12.0, y % 12.0)))
        assert feel.roughness[i] == pytest.approx(p.roughness, rel=1e-5)
        assert feel.uncertainty[i] == pytest.approx(p.roughness_std, rel=1e-5)


def test_on_a_cylinder_the_map_gives_the_curvature_studys_V_within_its_error():
    study = json.loads((ROOT / "studies/results/curvature_default.json").read_text())
    [measured] = [r for r in study["differences"]
                  if r["lambda_mm"] == 1.0 and r["curvature_mm"] == 10.0 and r.get("texture_along") == "normal"]
    mesh, side = _cylinder(10.0)
    feel = feel_map(mesh, Wrap(10.0), {"side": side}, spacing_mm=10.0)
    inner = [i for i, m in enumerate(feel.method) if m != "refused"]
    assert len(inner) >= 8 and all(feel.method[i] == "corrected" for i in inner)
    assert np.allclose(feel.k1[inner], 0.1, rtol=0.02)
    for i in inner:
        x, y, z = feel.points[i]
        v_flat, _ = _plate_v(math.atan2(y, x) * 10.0, z)
        expected = v_flat * (1 + measured["relative_difference"])  # the study's V on this cylinder
        assert abs(feel.roughness[i] - expected) <= feel.uncertainty[i], (feel.points[i], expected)
        assert feel.uncertainty[i] > feel.flat_roughness[i] * 0.01  # the correction's error is carried


def test_concave_radius_below_the_footprints_and_too_small_objects_are_refused_with_reasons():
    bore, inside = _cylinder(4.0, inside=True)  # a 4 mm bore: the 10 mm footprint cannot rest in it
    feel = feel_map(bore, Wrap(4.0), {"bore": inside}, spacing_mm=10.0)
    assert set(feel.method) == {"refused"} and set(feel.refusals()) == {CANNOT_REST}
    assert np.all(np.isnan(feel.roughness))
    cube = trimesh.creation.box([8, 8, 8])  # faces smaller than the footprint
    feel = feel_map(cube, Planar(), spacing_mm=4.0)
    assert set(feel.refusals()) == {OFF_OBJECT} and feel.table()[0].refused_fraction == 1.0
    rod, side = _cylinder(2.0)  # convex radius 2 mm: beyond the study's measured range
    feel = feel_map(rod, Wrap(2.0), {"rod": side}, spacing_mm=10.0)
    reasons = set(feel.refusals())
    assert any(r.startswith("too curved") for r in reasons), reasons


def test_bad_regions_and_options_are_refused():
    box = trimesh.creation.box([20, 20, 20])
    for kwargs, parameter in (({"regions": {"top": np.zeros(len(box.faces), bool)}}, "regions"),
                              ({"regions": {"top": np.ones(3, bool)}}, "regions"),
                              ({"spacing_mm": 0.0}, "spacing_mm"), ({"engine": "fem"}, "engine"),
                              ({"curved": "guess"}, "curved")):
        with pytest.raises(InputError) as err:
            feel_map(box, Planar(), **kwargs)
        assert err.value.parameter == parameter


def test_the_picture_colours_the_object_by_v_or_by_jnd_from_a_reference():
    from matplotlib.figure import Figure

    from roughness.objects.feel_figure import feel_figure

    mesh, side = _cylinder(10.0, height_mm=30.0)
    feel = feel_map(mesh, Wrap(10.0), {"side": side}, spacing_mm=10.0, reference="standard-1.0")
    assert isinstance(feel_figure(mesh, feel, side, by="jnd"), Figure)
    jnd = feel.jnd[~np.isnan(feel.roughness)]
    # the same texture on a convex cylinder: a little rougher than itself flat, well within a JND or so
    assert np.all(np.abs(jnd) < 1.5) and feel.table()[0].jnd_median is not None
    no_reference = feel_map(mesh, Wrap(10.0), {"side": side}, spacing_mm=10.0)
    with pytest.raises(InputError, match="reference"):
        feel_figure(mesh, no_reference, side, by="jnd")
    assert "FeelMap(" in repr(feel) and "refused" in repr(feel)


# The curvature correction, shared with predict --curvature-mm

def test_the_correction_table_comes_from_the_committed_study():
    data = json.loads(correction.TABLE_PATH.read_text())
    for base, entry in data["bases"].items():
        assert file_sha256(ROOT / entry["results"]) == entry["results_sha256"], base
        fresh = correction.table_from_study(json.loads((ROOT / entry["results"]).read_text()))
        assert list(fresh.difference) == entry["difference"] and list(fresh.error) == entry["error"]
    # a convex cylinder of 5 mm: the mean of the three textures' measured differences, its error their spread
    fix = correction.for_base(5.0, "cylinder")
    assert fix.factor == pytest.approx(1 + (0.144 + 0.087 + 0.064) / 3, abs=0.002)
    assert 1 + 0.129 - 0.002 <= fix.factor + fix.error and fix.factor - fix.error <= 1 + 0.061 + 0.002
    assert correction.correction(0.0, 0.0).factor == 1.0 and correction.correction(0.0, 0.0).error == 0.0
    with pytest.raises(InputError, match="cannot rest"):
        correction.for_base(-4.0, "cylinder")
    with pytest.raises(InputError, match="beyond"):
        correction.for_base(2.0, "cylinder")


def test_predict_curvature_no_longer_returns_the_flat_v_and_its_uncertainty_grows(capsys):
    from roughness.cli import main

    path = ROOT / "examples" / "standard-1.0mm.png"
    reading = ["--pixel-mm", "0.05", "--height-mm", "1", "--engine", "surrogate", "--json"]
    assert main(["predict", str(path), *reading]) == 0
    flat = json.loads(capsys.readouterr().out)
    assert main(["predict", str(path), *reading, "--curvature-mm", "15"]) == 0
    curved = json.loads(capsys.readouterr().out)
    fix = correction.for_base(15.0, "cylinder")
    assert curved["roughness"] == pytest.approx(flat["roughness"] * fix.factor) and fix.factor > 1.01
    assert flat["curvature_error"] is None and curved["curvature_error"] == pytest.approx(flat["roughness"] * fix.error)
    assert any("curvature study" in n for n in curved["domain_notes"])


# With the textured mesh (objgeo's texture_mesh and sample_heightmap)

def test_a_textured_flat_face_sampled_back_gives_the_flat_plates_v_within_the_monte_carlo_error():
    from roughness.objects.mapping import Triplanar
    from roughness.objects.regions import Region
    from roughness.objects.sampling import sample_heightmap
    from roughness.objects.texturing import texture_mesh

    # the texture on the middle of a large top face (its border on the flat top, 3 mm inside the edges; the box's
    # sharp edges themselves fold under 1 mm bumps: texture_mesh refuses that)
    box = trimesh.creation.box([20, 20, 4])
    box = trimesh.Trimesh(*trimesh.remesh.subdivide_to_size(box.vertices, box.faces, 1.0))
    textured = texture_mesh(box, Triplanar(TEXTURE), Region("box", low=(-7, -7, 1.9), high=(7, 7, 2.1)),
                            check_intersections=False)
    hm = sample_heightmap(textured, (1.3, -0.7, 2.0), (0, 0, 1), 10.0, TEXTURE.pixel_mm)
    [sampled] = predict(hm, engine="spectral")
    v, se = _plate_v(1.3, -0.7)
    assert abs(sampled.roughness - v) <= 2 * math.hypot(se, sampled.roughness_stderr)


# The commands

def _knob(path: Path) -> Path:
    """A knob: a cylinder of radius 15 mm, 20 mm tall, its top edge rounded to 4 mm."""
    profile = [(0, 0), (15, 0), (15, 16)] + [(11 + 4 * math.cos(a), 16 + 4 * math.sin(a))
                                             for a in np.linspace(0, math.pi / 2, 12)[1:]] + [(0, 20)]
    trimesh.creation.revolve(np.array(profile), sections=96).export(path)
    return path


def test_object_feel_reports_the_table_the_refusals_and_a_picture(tmp_path, capsys):
    from roughness.cli import main

    knob = _knob(tmp_path / "knob.stl")
    args = ["object", "feel", str(knob), "--texture", "standard-1.0", "--mapping", "cylinder", "--region",
            "cone:0,0,1,5", "--region", "all", "--spacing-mm", "8", "--reference", "standard-1.0"]
    assert main([*args, "--picture", str(tmp_path / "knob.png"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert (tmp_path / "knob.png").stat().st_size > 10_000
    top, everything = out["regions"]
    faces = trimesh.load(knob)
    expected = faces.area_faces[faces.face_normals[:, 2] >= math.cos(math.radians(5))].sum()
    assert top["name"] == "cone:0,0,1,5" and top["area_mm2"] == pytest.approx(expected)
    assert expected > math.pi * 11**2  # the flat top and the last facet of the rounded edge
    assert everything["points"] > top["points"] > 0 and everything["jnd_median"] is not None
    methods = {p["method"] for p in out["points"]}
    assert {"corrected", "refused"} <= methods  # the side is curved; the rounded edge and the rims refuse
    assert all(p["reason"] for p in out["points"] if p["method"] == "refused")
    assert any("cylinder wrap" in n for n in out["notes"])
    assert main([*args, "--picture", str(tmp_path / "knob.png")]) == 2  # exists: refused without --overwrite
    assert "already exists" in capsys.readouterr().err


def test_object_tune_meets_the_target_on_the_curved_part_and_reports_flat_and_object(tmp_path, capsys):
    from roughness.cli import main
    from roughness.surface.io import load_heightmap

    mesh, _ = _cylinder(6.0, height_mm=30.0)  # convex radius 6 mm: V about 8% above flat
    mesh.export(tmp_path / "rod.stl")
    assert main(["object", "tune", str(tmp_path / "rod.stl"), "--texture", "standard-1.0", "--mapping", "cylinder",
                 "--region", "cone:0,0,1,100", "--region", "cone:0,0,-1,100", "--spacing-mm", "10",
                 "--target-lambda", "1.0", "--out", str(tmp_path / "tuned.npz"), "--json", "--quiet"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["on_object"]["curved"] and out["reached"]
    assert abs(out["on_object"]["jnd_error"]) <= out["tolerance_jnd"]
    # the flat texture is tuned smoother than the target so that the convex rod feels like it
    assert out["flat_jnd_from_target"] < -0.1 and out["on_object"]["correction"] > 1.03
    assert load_heightmap(tmp_path / "tuned.npz").shape == TEXTURE.shape


@pytest.mark.parametrize("extra, flag", [
    (["--texture", "no-such-texture"], "--texture"),
    (["--texture", "standard-1.0", "--region", "cone:0,0,1"], "--region"),
    (["--texture", "standard-1.0", "--region", "box:100,100,100,200,200,200"], "--region"),
    (["--texture", "standard-1.0", "--spacing-mm", "0"], "--spacing-mm"),
    (["--texture", "standard-1.0", "--colour-by", "jnd"], "--colour-by"),
    (["--texture", "standard-1.0", "--reference", "standard-9"], "--reference"),
    (["--texture", "standard-1.0", "--picture", "nowhere/p.png"], "--picture"),
    # the mapping's options are object texture's, checked alike
    (["--texture", "standard-1.0", "--axis", "0,0,0,0,0,1"], "--axis"),  # triplanar has no axis
    (["--texture", "standard-1.0", "--mapping", "cylinder", "--axis", "0,0,1"], "--axis"),
    (["--texture", "standard-1.0", "--mapping", "cylinder", "--uv-mm", "2"], "--uv-mm"),
    (["--texture", "standard-1.0", "--printer", "no-such-printer"], "--printer"),
    (["--texture", "coarse.npy", "--pixel-mm", "0.25", "--printer", "fdm-0.4-0.2"], "--printer"),  # 1.8 px bead
])
def test_bad_object_feel_inputs_exit_2(tmp_path, capsys, extra, flag, monkeypatch):
    from roughness.cli import main

    knob = _knob(tmp_path / "knob.stl")
    np.save(tmp_path / "coarse.npy", np.random.default_rng(0).random((48, 48)) * 0.3)
    monkeypatch.chdir(tmp_path)
    code = main(["object", "feel", str(knob), *extra])
    err = capsys.readouterr().err
    assert code == 2 and flag in err and "Traceback" not in err, err


@pytest.mark.parametrize("extra, flag", [
    (["--jnd", "1"], "--jnd"),
    (["--target-lambda", "1", "--reference", "standard-1.0"], "--reference"),
    (["--target-lambda", "1", "--engine", "surrogate"], "--engine"),
    (["--target-lambda", "1", "--min-factor", "2", "--max-factor", "1"], "--min-factor"),
    (["--target-lambda", "1", "--mesh-out", "m.obj"], "--mesh-out"),
    (["--target-lambda", "1", "--printer", "no-such-printer"], "--printer"),
])
def test_bad_object_tune_inputs_exit_2(tmp_path, capsys, extra, flag, monkeypatch):
    from roughness.cli import main

    monkeypatch.chdir(tmp_path)
    knob = _knob(tmp_path / "knob.stl")
    code = main(["object", "tune", str(knob), "--texture", "standard-1.0", "--out", "t.npz", *extra])
    err = capsys.readouterr().err
    assert code == 2 and flag in err and "Traceback" not in err, err
    assert not (tmp_path / "t.npz").exists()


def test_curved_fem_on_request_runs_the_curved_fem_on_the_cylinder_under_the_footprint(monkeypatch):
    """--curved fem: where curvature matters each footprint goes to the curved FEM (stubbed here: seconds each) with
    the base the principal curvatures describe; the map's x runs along the curving direction, so the cylinder is
    straight along y."""
    from roughness import prediction

    calls = []
    flat_predictions = prediction.predictions

    def predictions_stub(named, engine="auto", **kwargs):
        if engine != "fem":
            return flat_predictions(named, engine=engine, **kwargs)
        calls.append(kwargs["options"].curved)
        return flat_predictions(named, engine="spectral")

    monkeypatch.setattr(prediction, "predictions", predictions_stub)
    mesh, side = _cylinder(10.0)
    feel = feel_map(mesh, Wrap(10.0), {"side": side}, spacing_mm=10.0, curved="fem")
    judged = [m for m in feel.method if m != "refused"]
    assert judged and set(judged) == {"fem"} and len(calls) == len(judged)
    for curved in calls:
        assert curved.shape == "cylinder" and curved.axis == "y"
        assert curved.radius_mm == pytest.approx(10.0, rel=0.02)


def test_object_tune_writes_the_textured_mesh_only_when_it_can_be_built(tmp_path, capsys, monkeypatch):
    """--mesh-out: the textured object with the tuned texture; a mesh the texture cannot be laid on writes nothing."""
    from roughness.cli import main
    from roughness.objects import texturing

    mesh, _ = _cylinder(6.0, height_mm=30.0)
    mesh.export(tmp_path / "rod.stl")
    built = []

    def texture_stub(base, mapping, region, *args, **kwargs):  # the real one takes a minute at 0.05 mm
        built.append((mapping.pixel_mm, region.describe()))
        return SimpleNamespace(mesh=base)  # object tune writes only the mesh

    monkeypatch.setattr(texturing, "texture_mesh", texture_stub)
    argv = ["object", "tune", str(tmp_path / "rod.stl"), "--texture", "standard-1.0", "--mapping", "cylinder",
            "--region", "cone:0,0,1,100", "--spacing-mm", "10", "--target-lambda", "1.0", "--quiet",
            "--out", str(tmp_path / "tuned.npz"), "--mesh-out", str(tmp_path / "rod_textured.stl")]
    assert main(argv) == 0
    assert "textured mesh: wrote" in capsys.readouterr().out and (tmp_path / "rod_textured.stl").stat().st_size > 0
    assert built and built[0][1].startswith("faces whose normal lies within 100 degrees")

    def refuse(*args, **kwargs):
        raise InputError("the texture is too deep for the mesh there", parameter="mapping")

    monkeypatch.setattr(texturing, "texture_mesh", refuse)
    argv[argv.index("--out") + 1] = str(tmp_path / "again.npz")
    argv[argv.index("--mesh-out") + 1] = str(tmp_path / "again.stl")
    assert main(argv) == 2 and "too deep" in capsys.readouterr().err
    assert not (tmp_path / "again.npz").exists() and not (tmp_path / "again.stl").exists()


# --- --printer: the printed object -----------------------------------------------------------------------------------

def test_the_tile_is_printed_at_its_pixel_on_the_surface_and_handed_back_at_its_own():
    from roughness.objects.printed import printed_tile
    from roughness.surface.printing import PROFILES, printed

    texture = standard_texture(1.0)
    fdm = PROFILES["fdm-0.4-0.2"]
    plain = printed_tile(texture, fdm)
    assert plain.heightmap.pixel_mm == texture.pixel_mm
    assert np.array_equal(plain.heightmap.heights, printed(texture, fdm, periodic=True).heightmap.heights)
    stretched = printed_tile(texture, fdm, 1.5 * texture.pixel_mm)  # a wrap's stretch: the bead is fewer pixels
    assert stretched.heightmap.pixel_mm == texture.pixel_mm
    assert not np.array_equal(stretched.heightmap.heights, plain.heightmap.heights)


def test_object_feel_and_tune_with_a_printer_report_printed_beside_digital(tmp_path, capsys):
    from roughness.cli import main

    mesh, _ = _cylinder(8.0, height_mm=30.0)
    mesh.export(tmp_path / "rod.stl")
    common = [str(tmp_path / "rod.stl"), "--texture", "standard-1.0", "--mapping", "cylinder", "--region",
              "cone:0,0,1,100", "--spacing-mm", "10", "--printer", "fdm-0.4-0.2"]
    assert main(["object", "feel", *common, "--json", "--quiet"]) == 0
    out = json.loads(capsys.readouterr().out)
    printed_row, digital_row = out["printing"]["printed_regions"][0], out["printing"]["digital_regions"][0]
    assert out["regions"][0]["roughness_median"] == printed_row["roughness_median"]  # the map is the print's
    assert printed_row["roughness_median"] < digital_row["roughness_median"]  # the bead rounds the bumps off
    assert main(["object", "feel", *common, "--quiet"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("as printed (fdm-0.4-0.2)") and "; digital V " in text
    assert main(["object", "tune", *common, "--target-lambda", "1.0", "--out", str(tmp_path / "t.npz"),
                 "--quiet"]) in (0, 1)
    text = capsys.readouterr().out
    assert "on the object as printed (fdm-0.4-0.2)" in text and "digital (the design as written" in text
    assert (tmp_path / "t.npz").exists()

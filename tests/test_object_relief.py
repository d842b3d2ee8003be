"""A mesh judged as it is (issue 41): its own relief over its smoothed base, against the texture it was made with;
meshes read from OBJ, OFF and glTF; large parts mapped within a budget."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from roughness.core.errors import InputError  # noqa: E402
from roughness.dataset.textures import standard_texture  # noqa: E402
from roughness.objects.feel import feel_map  # noqa: E402
from roughness.objects.feel_budget import MAX_POINTS, MAX_SAMPLES, feel_budget  # noqa: E402
from roughness.objects.footprint import Placement  # noqa: E402
from roughness.objects.layout import make_mapping  # noqa: E402
from roughness.objects.mapping import Triplanar  # noqa: E402
from roughness.objects.meshes import read_mesh  # noqa: E402
from roughness.objects.regions import Region  # noqa: E402
from roughness.objects.relief import (  # noqa: E402
    BASE_SIGMA_MM,
    MeshRelief,
    base_samples,
    levelled,
    surface_cells,
    without_quadric,
)
from roughness.objects.texturing import texture_mesh  # noqa: E402
from roughness.perceptual_scale import jnd  # noqa: E402

TEXTURE = standard_texture(1.0, seed=0)  # 12 mm, periodic: 1 mm bumps, relief 1 mm
SAME_FEEL_JND = 0.25  # the tolerance: the mesh judged as it is feels as its texture does


def _plate():
    """A 30 x 30 x 4 mm plate (faces of at most 1 mm) and the texture on the middle 26 x 26 mm of its top."""
    box = trimesh.creation.box([30, 30, 4])
    box = trimesh.Trimesh(*trimesh.remesh.subdivide_to_size(box.vertices, box.faces, 1.0))
    mapping = Triplanar(TEXTURE)
    region = Region("box", low=(-13, -13, 1.9), high=(13, 13, 2.1))
    return box, mapping, region


def _cylinder():
    """A cylinder of radius 10 mm, 24 mm tall (side faces 0.5 mm tall), the texture wrapped on |z| < 9 mm."""
    zs = np.linspace(-12, 12, 49)
    cylinder = trimesh.creation.revolve(np.array([(0, -12)] + [(10, z) for z in zs] + [(0, 12)]), sections=180)
    mapping = make_mapping("cylinder", TEXTURE, cylinder, np.abs(cylinder.face_normals[:, 2]) < 0.1)
    return cylinder, mapping, Region("box", low=(-10.1, -10.1, -9), high=(10.1, 10.1, 9))


def _jnd(scale, a: float, b: float) -> float:
    return jnd(scale.floored_lambda(a), scale.floored_lambda(b))


@pytest.mark.parametrize("shape, spacing_mm", [(_plate, 4.0), (_cylinder, 6.0)])
def test_a_mesh_textured_by_object_texture_feels_as_its_texture_within_a_quarter_jnd(shape, spacing_mm):
    base, mapping, region = shape()
    textured = texture_mesh(base, mapping, region, edge_mm=0.1, check_intersections=False).mesh
    inside = Region("box", low=np.array(region.low) - 1.05, high=np.array(region.high) + 1.05).faces(textured)  # + relief
    samples = base_samples(textured)
    relief = feel_map(textured, None, {"textured": inside}, spacing_mm=spacing_mm, samples=samples)
    # the same footprints (the base's placements) judged from the texture itself
    mapped = feel_map(textured, mapping, {"textured": inside}, spacing_mm=spacing_mm, samples=samples)
    judged = [i for i, m in enumerate(relief.method) if m != "refused"]
    assert len(judged) >= 6 and all(mapped.method[i] != "refused" for i in judged)
    worst = max(abs(_jnd(relief.scale, relief.roughness[i], mapped.roughness[i])) for i in judged)
    assert worst <= SAME_FEEL_JND, worst  # measured: plate 0.03, cylinder 0.04
    # and the whole region against the untextured part judged with the texture, as object feel --texture does
    plain = feel_map(base, mapping, {"textured": region.faces(base)}, spacing_mm=spacing_mm)
    [r], [p] = relief.table(), plain.table()
    assert abs(jnd(r.lambda_median_mm, p.lambda_median_mm)) <= SAME_FEEL_JND, (r, p)
    print(f"worst {worst:.3f} JND; medians {jnd(r.lambda_median_mm, p.lambda_median_mm):+.3f} JND; k1 "
          f"{relief.k1[judged].min():.4f}..{relief.k1[judged].max():.4f} k2 {relief.k2[judged].min():.4f}.."
          f"{relief.k2[judged].max():.4f}")
    if shape is _cylinder:  # the base's curvature is the cylinder's (the relief's mean height 0.2-0.5 mm above it)
        assert np.allclose(relief.k1[judged], 1 / 10.3, rtol=0.1) and np.allclose(relief.k2[judged], 0, atol=0.01)
        assert all(relief.method[i] == "corrected" for i in judged)
    else:  # flat: the base's curvature radii above 100 mm (measured: above 120 mm, the texture's own quadric)
        assert np.all(np.abs(relief.k1[judged]) < 0.01) and np.all(np.abs(relief.k2[judged]) < 0.01)


def test_a_smooth_untextured_mesh_feels_flat_not_refused():
    """A box of 12 triangles (a CAD export's: faces spanning the part) and a 20 mm handle of 180 facets."""
    box = trimesh.creation.box([60, 60, 6])
    handle = trimesh.creation.cylinder(radius=10.0, height=60.0, sections=180)
    for mesh, faces in ((box, box.face_normals[:, 2] > 0.9), (handle, np.abs(handle.face_normals[:, 2]) < 0.1)):
        feel = feel_map(mesh, None, {"part": faces}, spacing_mm=10.0)
        judged = [i for i, m in enumerate(feel.method) if m != "refused"]
        assert len(judged) >= 9, feel.refusals()
        assert np.all(feel.roughness[judged] < feel.scale.floor)  # below the standard scale: smoother than any texture
        assert feel.table()[0].below_scale_fraction == 1.0


def test_the_base_is_the_shape_smoothed_at_one_mm_the_relief_is_gone_from_it():
    """The base of the textured plate: normals those of the plate away from its edges (the 1 mm bumps, with slopes
    up to 60 degrees, averaged out), and positions at the relief's mean height."""
    base, mapping, region = _plate()
    textured = texture_mesh(base, mapping, region, edge_mm=0.1, check_intersections=False).mesh
    samples = base_samples(textured)
    top = (samples.points[:, 2] > 1.0) & np.all(np.abs(samples.points[:, :2]) < 15 - 3 * BASE_SIGMA_MM, axis=1)
    tilt = np.degrees(np.arccos(np.clip(samples.normals[top, 2], -1, 1)))
    faces = np.degrees(np.arccos(np.clip(textured.face_normals[textured.triangles_center[:, 2] > 2.05, 2], -1, 1)))
    print(f"tilt of the base: median {np.median(tilt):.2f}, 99% {np.percentile(tilt, 99):.2f} degrees; of the "
          f"textured faces: median {np.median(faces):.1f}")
    # what is left is the relief's own content at wavelengths of millimetres: each footprint is levelled on it
    assert np.median(tilt) < 3.0 and np.median(faces) > 10 * np.median(tilt)  # measured: 1.3 and 49 degrees
    heights = samples.points[top, 2] - 2.0
    assert abs(np.median(heights) - TEXTURE.heights.mean()) < 0.1


def test_surface_cells_hold_the_meshs_exact_area_and_normals_and_refuse_a_split_beyond_the_limit():
    box = trimesh.creation.box([60, 30, 6])  # 12 faces, split to 0.4 mm edges first
    cells = surface_cells(box, 0.4)
    assert cells.areas.sum() == pytest.approx(box.area) and len(cells.areas) > box.area / 0.4**2 / 2
    top = cells.points[:, 2] > 3 - 1e-9  # cubes of the top face only (not those holding a side too)
    assert np.allclose(cells.normal_sums[top] / cells.areas[top, None], [0, 0, 1])
    assert np.allclose(cells.normal_sums.sum(axis=0), 0, atol=1e-9)  # a closed surface
    assert set(cells.faces[top]) <= set(np.flatnonzero(box.face_normals[:, 2] > 0.9))
    with pytest.raises(InputError, match="split to 0.01 mm"):  # 12 x 4^13 faces: refused before splitting
        surface_cells(box, 0.01)


def test_the_quadric_removed_from_a_footprint_is_added_to_the_bases_curvature():
    axis = (np.arange(200) - 99.5) * 0.05
    x, y = np.meshgrid(axis, axis)
    bumps = 0.1 * np.sin(2 * np.pi * x) * np.sin(2 * np.pi * y)
    # walked with curvatures 0.05 (x) and 0: a true base of 0.1 and 0.02 sits 0.5 (0.05 - 0.1) x^2 ... below
    heights = bumps + 0.5 * (0.05 - 0.1) * x**2 + 0.5 * (0.0 - 0.02) * y**2 + 0.3 + 0.01 * x
    relief, k1, k2 = without_quadric(heights, axis, 0.05, 0.0)
    assert k1 == pytest.approx(0.1, abs=1e-3) and k2 == pytest.approx(0.02, abs=1e-3)
    assert np.abs(relief - bumps).max() < 0.01  # the bumps stay (whole periods: what leaks is their edge)


def test_a_footprint_is_levelled_onto_the_plane_of_its_relief():
    place = Placement(np.array([1.0, 2, 3]), np.array([0, 0, 1.0]), 0.0, 0.0, np.array([1.0, 0, 0]),
                      np.array([0, 1.0, 0]))
    turned = levelled(place, 0.1, -0.05)
    x, y = np.meshgrid(np.linspace(-5, 5, 5), np.linspace(-5, 5, 5))
    on_plane = np.stack([x.ravel(), y.ravel(), 0.1 * x.ravel() - 0.05 * y.ravel()], axis=1)  # h = 0.1 x - 0.05 y
    assert np.abs(on_plane @ turned.normal).max() < 1e-12
    frame = np.stack([turned.d1, turned.d2, turned.normal])
    assert np.allclose(frame @ frame.T, np.eye(3)) and np.linalg.det(frame) == pytest.approx(1)  # turned, not mirrored
    # a plate tilted 4 degrees under a level footprint: measured again on its plane, its relief is exactly flat
    plate = trimesh.creation.box([40, 40, 4])
    plate.apply_transform(trimesh.transformations.rotation_matrix(math.radians(4), [1, 0, 0]))
    top = plate.vertices[plate.vertices[:, 2].argmax()]
    start = Placement(np.array([0, 0, top[2] - 0.3]), np.array([0, 0, 1.0]), 0.0, 0.0, np.array([1.0, 0, 0]),
                      np.array([0, 1.0, 0]))
    found = MeshRelief.of(plate).unrolled(start)
    assert found.missing == 0 and np.abs(found.heights).max() < 1e-6
    assert abs(found.k1) < 1e-6 and abs(found.k2) < 1e-6


# Mesh formats

@pytest.mark.parametrize("suffix, scale", [(".obj", 1.0), (".off", 1.0), (".glb", 1000.0), (".gltf", 1000.0)])
def test_obj_off_and_gltf_meshes_are_read_with_their_units(tmp_path, suffix, scale):
    box = trimesh.creation.box([20 / scale, 10 / scale, 8 / scale])  # glTF is metres by its specification
    box.export(tmp_path / f"box{suffix}")
    read = read_mesh(tmp_path / f"box{suffix}")
    assert np.allclose(np.ptp(read.mesh.vertices, axis=0), [20, 10, 8])
    assert read.mesh.volume == pytest.approx(1600)
    said = " ".join(read.notes)
    assert ("no units stated: read as mm" in said) if scale == 1.0 else ("scaled by 1000" in said)


# Large parts

def test_budget_widens_the_spacings_of_a_large_part_and_says_so():
    small = feel_budget(2 * 30 * 30, 30 * 30)
    assert (small.sample_spacing_mm, small.point_spacing_mm, small.notes) == (0.4, 5.0, ())
    plate = 2 * 300 * 300 + 4 * 300 * 6
    large = feel_budget(plate, 300 * 300)
    assert plate / large.sample_spacing_mm**2 <= MAX_SAMPLES < plate / (large.sample_spacing_mm - 0.01) ** 2
    assert 300 * 300 / large.point_spacing_mm**2 <= MAX_POINTS
    assert len(large.notes) == 2 and "budget" in large.notes[0]
    assert feel_budget(plate, 300 * 300, spacing_mm=20.0).point_spacing_mm == 20.0  # given: kept
    assert feel_budget(plate, 300 * 300, relief=True).point_spacing_mm > large.point_spacing_mm


def test_a_300_mm_plate_is_mapped_within_the_budget_not_refused():
    plate = trimesh.creation.box([300, 300, 6])
    top = plate.face_normals[:, 2] > 0.9
    with pytest.raises(InputError):  # before: 0.4 mm samples over 181,000 mm^2, above MAX_MAP_POSITIONS
        from roughness.objects.curvature import SurfaceSamples

        SurfaceSamples.of(plate)
    feel = feel_map(plate, Triplanar(TEXTURE), {"top": top}, spacing_mm=60.0)
    judged = [i for i, m in enumerate(feel.method) if m != "refused"]
    assert len(judged) >= 9 and all(feel.method[i] == "flat" for i in judged)
    assert any("surface samples" in note for note in feel.notes)


# The command

def test_object_feel_without_texture_judges_the_mesh_as_it_is(tmp_path, capsys):
    from roughness.cli import main

    base, mapping, region = _plate()
    texture_mesh(base, mapping, region, edge_mm=0.1, check_intersections=False).mesh.export(tmp_path / "plate.stl")
    assert main(["object", "feel", str(tmp_path / "plate.stl"), "--region", "cone:0,0,1,30", "--spacing-mm", "6",
                 "--reference", "standard-1.0", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["texture"] is None and out["mapping"] is None
    [row] = out["regions"]
    assert row["points"] > 0 and row["refused_fraction"] < 1 and abs(row["jnd_median"]) < 1
    assert main(["object", "feel", str(tmp_path / "plate.stl"), "--axis", "0,0,0,0,0,1"]) == 2
    assert "--axis applies to a texture given by --texture" in capsys.readouterr().err


def test_a_gltf_with_its_files_is_read_and_checked_whole_before_reading(tmp_path, monkeypatch):
    """A glTF names its buffers; they count toward the size limit and must lie beside it (a glTF naming
    /dev/zero or a file elsewhere is refused before anything is read)."""
    import json

    from roughness.objects import meshes

    box = trimesh.creation.box([0.02, 0.01, 0.008])
    box.export(tmp_path / "box.gltf")
    buffers = [tmp_path / b["uri"] for b in json.loads((tmp_path / "box.gltf").read_text())["buffers"]]
    whole = (tmp_path / "box.gltf").stat().st_size + sum(b.stat().st_size for b in buffers)
    assert read_mesh(tmp_path / "box.gltf").mesh.volume == pytest.approx(1600)
    monkeypatch.setattr(meshes, "MAX_MESH_FILE_BYTES", whole - 1)  # the .gltf alone is far below it
    with pytest.raises(InputError, match=f"with the files it names is {whole:,} bytes"):
        read_mesh(tmp_path / "box.gltf")
    monkeypatch.undo()
    document = json.loads((tmp_path / "box.gltf").read_text())
    for uri, why in (("/dev/zero", "in its own folder"), ("../box.bin", "in its own folder"),
                     ("missing.bin", "not a file beside it")):
        document["buffers"][0]["uri"] = uri
        (tmp_path / "named.gltf").write_text(json.dumps(document))
        with pytest.raises(InputError, match=why):
            read_mesh(tmp_path / "named.gltf")

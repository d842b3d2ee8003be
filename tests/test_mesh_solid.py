"""No broken mesh called closed: every mesh the product writes passes an independent check of a closed solid, and the
word "closed" comes from that check (roughness.surface.solid), on a CAD part with a sharp inner edge."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from roughness.cli import main
from roughness.core.errors import InputError, SimulationError
from roughness.dataset.textures import standard_texture
from roughness.objects.meshes import write_mesh
from roughness.surface.heightmap import Heightmap
from roughness.surface.io import save_heightmap
from roughness.surface.solid import check_solid

L_SHAPE = [(0, 0), (40, 0), (40, 20), (20, 20), (20, 40), (0, 40)]


def _square(a0: float, a1: float, b0: float, b1: float) -> list[tuple[float, float]]:
    return [(a0, b0), (a1, b0), (a1, b1), (a0, b1)]


def octant_cube() -> trimesh.Trimesh:
    """A 40 mm cube with its (+x, +y, +z) octant cut away, each planar face a fan from its first corner, as CAD
    exports triangulate them: long thin triangles meeting at the sharp inner edges."""
    faces_2d = [(_square(0, 40, 0, 40), 2, 0), (L_SHAPE, 2, 40), (_square(20, 40, 20, 40), 2, 20),
                (_square(0, 40, 0, 40), 0, 0), (_square(0, 40, 0, 40), 1, 0), (L_SHAPE, 0, 40), (L_SHAPE, 1, 40),
                (_square(20, 40, 20, 40), 0, 20), (_square(20, 40, 20, 40), 1, 20)]
    vertices: list[tuple[float, ...]] = []
    faces = []
    for polygon, axis, value in faces_2d:
        others = [a for a in range(3) if a != axis]
        ids = []
        for a, b in polygon:
            point = [0.0, 0.0, 0.0]
            point[axis], point[others[0]], point[others[1]] = value, a, b
            if tuple(point) not in vertices:
                vertices.append(tuple(point))
            ids.append(vertices.index(tuple(point)))
        faces += [(ids[0], ids[i], ids[i + 1]) for i in range(1, len(ids) - 1)]
    mesh = trimesh.Trimesh(np.array(vertices), np.array(faces))
    trimesh.repair.fix_normals(mesh)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume == pytest.approx(56000.0)
    return mesh


def independent_verdict(path) -> tuple[bool, bool, int]:
    """(watertight, consistently wound, zero-area triangles) of a written file, as trimesh reads it (vertices
    merged, nothing repaired)."""
    mesh = trimesh.load(str(path), force="mesh", process=True, validate=False)
    return mesh.is_watertight, mesh.is_winding_consistent, int((~mesh.nondegenerate_faces()).sum())


# --- the check itself -------------------------------------------------------------------------------------------

def test_a_closed_box_passes_and_each_defect_is_named():
    box = trimesh.creation.box((10, 10, 10))
    v, f = box.vertices, box.faces
    assert check_solid(v, f).closed and "closed" in check_solid(v, f).line()
    flipped = f.copy()
    flipped[0] = flipped[0][::-1]
    assert check_solid(v, flipped).misoriented_edges == 3
    assert check_solid(v, f[1:]).open_edges == 3
    assert check_solid(v, np.vstack([f, f[:1]])).overshared_edges == 3
    broken = check_solid(v, f[1:])
    assert not broken.closed and broken.line().startswith("NOT a closed solid") and "3 open edges" in broken.line()


def test_zero_area_triangles_are_found_at_the_files_precision():
    box = trimesh.creation.box((40, 40, 40))
    v, f = box.vertices.copy(), box.faces
    # a T-junction mended badly: a corner on the middle of an edge, joined to the edge's ends (a zero-area sliver)
    a, b = f[0][:2]
    middle = (v[a] + v[b]) / 2
    sliver = check_solid(np.vstack([v, middle]), np.vstack([f, [[a, len(v), b]]]))
    assert sliver.zero_area == 1
    # two corners 1e-9 mm apart at 20 mm: distinct in float64, one point in a float32 STL
    near = np.vstack([v, v[a] + [1e-9, 0, 0]])
    triangle = np.vstack([f, [[a, len(v), b]]])
    assert check_solid(near, triangle, np.float32).zero_area == 1
    assert check_solid(near, triangle, np.float64).zero_area == 0
    # a long thin sliver that is real (1 um wide over 40 mm) is not zero-area in float32
    thin = np.array([[0, 0, 20.0], [40, 0, 20.0], [20, 1e-3, 20.0]])
    assert check_solid(thin, np.array([[0, 1, 2]])).zero_area == 0


def test_write_mesh_refuses_a_broken_mesh_and_writes_nothing(tmp_path):
    box = trimesh.creation.box((10, 10, 10))
    broken = trimesh.Trimesh(box.vertices, box.faces[1:], process=False)
    for name in ("open.stl", "open.3mf"):
        with pytest.raises(SimulationError, match="was not written: it is NOT a closed solid.*3 open edges"):
            write_mesh(broken, tmp_path / name)
        assert not (tmp_path / name).exists()
    written = write_mesh(box, tmp_path / "box.stl")
    assert written.check.closed and "checked as written (float32 corners, welded): closed" in written.line()


# --- every mesh the product writes ------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def cad_part(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cad")
    octant_cube().export(folder / "octant.stl")
    np.save(folder / "shallow.npy", np.asarray(standard_texture(1.0).heights) * 0.1)  # 0.1 mm deep: below the 0.2 mm inner radius
    return folder


@pytest.mark.parametrize("case, args", [
    ("top faces", ["--texture", "standard-1.0", "--region", "cone:0,0,1,10", "--edge-mm", "0.25", "--out", "top.stl"]),
    ("top faces, 3MF", ["--texture", "standard-1.0", "--region", "cone:0,0,1,10", "--edge-mm", "0.5",
                        "--out", "top.3mf"]),
    ("whole part", ["--texture", "shallow.npy", "--pixel-mm", "0.05", "--edge-mm", "0.5", "--out", "whole.stl"]),
])
def test_a_textured_cad_part_is_closed_by_an_independent_check(cad_part, case, args, capsys, monkeypatch):
    monkeypatch.chdir(cad_part)
    assert main(["object", "texture", "octant.stl", *args, "--overwrite"]) == 0, case
    out = capsys.readouterr().out
    written = cad_part / args[args.index("--out") + 1]
    assert independent_verdict(written) == (True, True, 0), case
    precision = "float32" if written.suffix == ".stl" else "float64"
    assert f"checked as written ({precision} corners, welded): closed" in out


def test_a_plate_written_as_stl_is_closed_by_an_independent_check(tmp_path):
    rng = np.random.default_rng(0)
    save_heightmap(Heightmap(rng.random((40, 30)) * 0.5, 0.05), tmp_path / "plate.stl")
    assert independent_verdict(tmp_path / "plate.stl") == (True, True, 0)


def test_a_mesh_broken_inside_the_pipeline_is_never_called_closed(cad_part, capsys, monkeypatch):
    """If refinement ever breaks the mesh, the check (not the code that made it) has the last word: exit 3, the
    defect named, nothing written."""
    import roughness.objects.texturing as texturing

    refine = texturing.refine

    def losing_a_face(*args, **kwargs):
        refined = refine(*args, **kwargs)
        refined.faces, refined.textured = refined.faces[1:], refined.textured[1:]
        return refined

    monkeypatch.setattr(texturing, "refine", losing_a_face)
    monkeypatch.chdir(cad_part)
    code = main(["object", "texture", "octant.stl", "--texture", "standard-1.0", "--region", "cone:0,0,1,10",
                 "--edge-mm", "2", "--out", "broken.stl"])
    err = capsys.readouterr().err
    assert code == 3 and "NOT a closed solid" in err and "3 open edges" in err and "Traceback" not in err
    assert not (cad_part / "broken.stl").exists()


def test_an_input_that_crosses_itself_is_named_as_such_not_as_a_texture_too_deep(cad_part, capsys, monkeypatch):
    a = trimesh.creation.box((10, 10, 10))
    b = trimesh.creation.box((10, 10, 10))
    b.apply_translation((5.37, 5.29, 5.31))  # general position: no vertex of one on a face plane of the other
    trimesh.util.concatenate([a, b]).export(cad_part / "two_boxes.stl")
    monkeypatch.chdir(cad_part)
    code = main(["object", "texture", "two_boxes.stl", "--texture", "shallow.npy", "--pixel-mm", "0.05",
                 "--edge-mm", "1", "--out", "crossing.stl"])
    err = capsys.readouterr().err
    assert code == 2 and "MESH: the mesh crosses itself before any texture is applied" in err, err
    assert "too deep" not in err and not (cad_part / "crossing.stl").exists()


@pytest.mark.parametrize("name, kwargs", [("edge_mm", {"edge_mm": 1e300}), ("normal_radius_mm", {"normal_radius_mm": 1e300}),
                                          ("border_mm", {"border_mm": 2e3})])
def test_texturing_lengths_are_bounded_in_the_library_too(name, kwargs):
    """The command line's bound on lengths holds for library callers: 1e300 overflowed (garbage heights on the mesh
    from a wrap radius of 1e300, with only a numpy warning)."""
    from roughness.objects.mapping import Triplanar, axis_of, wrap
    from roughness.objects.texturing import texture_mesh

    box = trimesh.creation.box((10, 10, 10))
    with pytest.raises(InputError, match=f"{name} must be at most 1000 mm .MAX_LENGTH_MM.") as err:
        texture_mesh(box, Triplanar(standard_texture(1.0)), **kwargs)
    assert err.value.parameter == name
    with pytest.raises(InputError, match="radius_mm must be at most") as err:
        wrap(standard_texture(1.0), "cylinder", axis_of((0, 0, 0), (0, 0, 1)), 1e300)
    assert err.value.parameter == "radius_mm"

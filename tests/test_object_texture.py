"""Textured objects, the geometry (issue 30): meshes in and out, regions, mappings, texture_mesh, sampling back,
and `roughness object texture`. Small meshes at coarse texture pixels, so each test takes about a second."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from roughness.cli import main  # noqa: E402
from roughness.core.errors import InputError  # noqa: E402
from roughness.dataset.textures import named_texture  # noqa: E402
from roughness.objects.intersections import self_intersections, triangles_cross  # noqa: E402
from roughness.objects.layout import make_mapping  # noqa: E402
from roughness.objects.mapping import Triplanar, Wrap, axis_of, blend_weights, whole_tiles, wrap  # noqa: E402
from roughness.objects.meshes import read_mesh, write_mesh  # noqa: E402
from roughness.objects.normals import vertex_normals  # noqa: E402
from roughness.objects.regions import Region, parse_region  # noqa: E402
from roughness.objects.remesh import refine  # noqa: E402
from roughness.objects.sampling import sample_heightmap  # noqa: E402
from roughness.objects.texturing import texture_mesh  # noqa: E402
from roughness.surface.heightmap import Heightmap  # noqa: E402
from test_bad_inputs import _expect_refusal  # noqa: E402

PIXEL = 0.25  # mm: the texture's pixel in these tests (the product's is 0.05)
RELIEF = 0.3  # mm


@pytest.fixture(scope="module")
def texture() -> Heightmap:
    """standard-1.0 at 0.25 mm, its relief scaled to 0.3 mm (lowest point 0)."""
    hm = named_texture("standard-1.0").resampled(PIXEL)
    h = hm.heights - hm.heights.min()
    return Heightmap(h * (RELIEF / h.max()), PIXEL)


@pytest.fixture(scope="module")
def waves() -> Heightmap:
    """A smooth periodic 12 mm tile (waves of 3 and 4 mm, 0.3 mm relief), whose steps between neighbouring vertices
    are small, so a seam stands out."""
    x = (np.arange(48) + 0.5) * PIXEL
    h = np.sin(2 * np.pi * x / 3)[None, :] * np.cos(2 * np.pi * x / 4)[:, None] + np.sin(2 * np.pi * x / 4)[None, :]
    return Heightmap((h - h.min()) * (RELIEF / np.ptp(h)), PIXEL)


def knob() -> trimesh.Trimesh:
    """A cylinder of radius 8 mm, 10 mm tall, with a rounded top (a quarter circle of radius 3 mm)."""
    arc = [(5 + 3 * math.cos(t), 10 + 3 * math.sin(t)) for t in np.linspace(0, math.pi / 2, 8)]
    profile = np.array([(0, 0), (8, 0), *arc, (0, 13)])
    return trimesh.creation.revolve(profile, sections=48)


def sphere() -> trimesh.Trimesh:
    return trimesh.creation.icosphere(3, radius=8)


def rounded_cube(half: float = 6.0, radius: float = 2.0) -> trimesh.Trimesh:
    """A cube of side 2 (half + radius) with edges rounded to ``radius`` (the sphere's topology, pushed out)."""
    s = trimesh.creation.icosphere(4)
    q = s.vertices / np.abs(s.vertices).max(axis=1, keepdims=True) * (half + radius)
    core = np.clip(q, -half, half)
    out = q - core
    out = out / np.linalg.norm(out, axis=1, keepdims=True) * radius
    return trimesh.Trimesh(core + out, s.faces, process=False)


def scanned() -> trimesh.Trimesh:
    """An irregular, scan-like blob: an icosphere with smooth random bumps of 10% of its radius and noise."""
    s = trimesh.creation.icosphere(4, radius=8)
    rng = np.random.default_rng(3)
    u = s.vertices / 8
    bumps = sum(a * np.sin(u @ k + p) for a, k, p in zip(rng.normal(0, 0.04, 6), rng.normal(0, 2, (6, 3)),
                                                          rng.uniform(0, 6, 6)))
    scale = 1 + bumps + rng.normal(0, 0.002, len(u))
    return trimesh.Trimesh(s.vertices * scale[:, None], s.faces, process=False)


SHAPES = {"knob": knob, "sphere": sphere, "rounded cube": rounded_cube, "scanned": scanned}


def _closed(mesh) -> bool:
    m = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    return bool(m.is_watertight and m.is_winding_consistent and m.volume > 0)


# --- texture_mesh --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("shape", SHAPES)
def test_textured_shapes_are_closed_and_do_not_cross_themselves(shape, texture):
    mesh = SHAPES[shape]()
    assert _closed(mesh)
    kind = {"knob": "cylinder", "sphere": "sphere"}.get(shape, "triplanar")
    result = texture_mesh(mesh, make_mapping(kind, texture, mesh))
    assert _closed(result.mesh)
    assert result.intersection_pairs_tested > 100  # the check tested close pairs (as many as brute force: below)
    assert result.triangles_out > 2 * result.triangles_in
    edges = result.mesh.vertices[result.mesh.edges_unique]
    assert np.linalg.norm(edges[:, 0] - edges[:, 1], axis=1).min() > 0


def test_the_intersection_check_finds_what_brute_force_finds():
    a = trimesh.creation.icosphere(2, radius=5)
    b = trimesh.creation.icosphere(2, radius=5)
    b.apply_translation((3, 1, 0.5))
    big = trimesh.creation.box((20, 20, 20))
    big.apply_translation((0, 0, -8))  # large faces: through the R-tree path
    m = trimesh.util.concatenate([a, b, big])
    found = self_intersections(m.vertices, m.faces)
    tri = m.triangles
    i, j = np.triu_indices(len(tri), 1)
    lo, hi = tri.min(1), tri.max(1)
    keep = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1)
    i, j = i[keep], j[keep]
    apart = ~(m.faces[i][:, :, None] == m.faces[j][:, None, :]).any(axis=(1, 2))
    brute = triangles_cross(tri[i[apart]], tri[j[apart]])
    assert found.count == brute.sum() > 100
    assert {tuple(p) for p in np.sort(found.pairs, axis=1)} == set(zip(i[apart][brute], j[apart][brute]))


def test_texture_that_would_cross_a_narrow_gap_is_refused(texture):
    left = trimesh.creation.box((5, 5, 5))
    right = trimesh.creation.box((5, 5, 5))
    right.apply_translation((5.2, 0, 0))  # 0.2 mm apart; the texture is 0.3 mm deep
    two = trimesh.util.concatenate([left, right])
    with pytest.raises(InputError, match="crosses itself"):
        texture_mesh(two, Triplanar(texture))
    texture_mesh(two, Triplanar(Heightmap(texture.heights / 4, PIXEL)))  # 0.075 mm on each side fits


def test_a_refinement_beyond_the_triangle_limit_is_refused_before_it_starts(texture, monkeypatch):
    import roughness.objects.remesh as remesh

    ball = trimesh.creation.icosphere(2, radius=500)
    split, whole = remesh._split, []

    def watched(v, f, *args):  # the estimate refines sampled faces one at a time; the refinement, the whole mesh
        whole.append(len(f) == len(ball.faces))
        return split(v, f, *args)

    monkeypatch.setattr(remesh, "_split", watched)
    with pytest.raises(InputError, match="MAX_MESH_TRIANGLES") as err:  # a 1 m ball at 1 um: 1e13 triangles
        texture_mesh(ball, Triplanar(texture), edge_mm=0.001)
    assert err.value.parameter == "edge_mm" and whole and not any(whole)


def test_depth_beyond_the_concave_radius_is_refused(texture):
    cavity = trimesh.creation.icosphere(4, radius=1.0)
    cavity.invert()
    block = trimesh.util.concatenate([trimesh.creation.box((6, 6, 6)), cavity])
    region = Region("box", low=(-1.5, -1.5, -1.5), high=(1.5, 1.5, 1.5))
    deep = Heightmap(texture.heights * (1.5 / RELIEF), PIXEL)  # 1.5 mm deep in a 1 mm hollow
    with pytest.raises(InputError, match="concave with a radius of") as err:
        texture_mesh(block, Triplanar(deep), region)
    assert err.value.parameter == "mapping"
    shallow = texture_mesh(block, Triplanar(Heightmap(texture.heights / 6, PIXEL)), region)  # 0.05 mm
    assert 0.5 < shallow.min_concave_radius_mm < 1.2
    assert _closed(shallow.mesh)


def test_volume_change_is_what_the_mean_height_predicts(texture):
    box = trimesh.creation.box((20, 20, 10))
    top = Region("cone", axis=(0, 0, 1), half_angle_deg=10)
    result = texture_mesh(box, Triplanar(texture), top)
    assert result.textured_area_mm2 == pytest.approx(400, rel=1e-12)
    # on a flat face the added volume is the integral of the (piecewise linear) heights: exact
    assert result.volume_out_mm3 - result.volume_in_mm3 == pytest.approx(result.height_volume_mm3, rel=1e-9)
    # and the heights' mean over the face is the texture's mean within the sampling of 400 mm^2 of a 144 mm^2 tile
    assert result.mean_height_mm == pytest.approx(float(texture.heights.mean()), rel=0.05)


def test_volume_change_on_a_sphere_includes_the_curvature_term(texture):
    result = texture_mesh(sphere(), Triplanar(texture))
    added = result.volume_out_mm3 - result.volume_in_mm3
    first_order = result.height_volume_mm3
    # a shell of thickness h on radius R adds A h (1 + h / R + ...): the excess lies within h_max / R
    assert first_order < added < first_order * (1 + result.max_height_mm / 8)


def test_region_edge_moves_along_the_region_normal(texture):
    box = trimesh.creation.box((20, 20, 10))
    result = texture_mesh(box, Triplanar(texture), Region("cone", axis=(0, 0, 1), half_angle_deg=10))
    v = result.mesh.vertices
    assert np.abs(v[:, :2]).max() == pytest.approx(10, abs=1e-12)  # nothing pushed sideways out of the box
    assert v[:, 2].max() == pytest.approx(5 + RELIEF, abs=0.02)


# --- seams ---------------------------------------------------------------------------------------------------------

def _vertex_heights(mesh, mapping, edge_mm):
    r = refine(mesh.vertices, mesh.faces, np.ones(len(mesh.faces), bool), edge_mm)
    normals = vertex_normals(r.vertices, r.faces)
    h = mapping.heights(r.vertices, normals)
    edges = np.concatenate([r.faces[:, [0, 1]], r.faces[:, [1, 2]], r.faces[:, [2, 0]]])
    return r.vertices, normals, h, edges


def test_triplanar_seams_are_blended(texture):
    """Largest height jump across an edge in a seam zone (two projections mixed) <= 1.5 x the largest jump across an
    edge inside one projection; with the blend off the seams jump by up to the texture's relief."""
    ball = trimesh.creation.icosphere(4, radius=8)
    bound = {}
    for blend in (20.0, 0.0):
        v, n, h, edges = _vertex_heights(ball, Triplanar(texture, blend), PIXEL * math.sqrt(2))
        a = np.abs(n)
        top2 = np.sort(a, axis=1)[:, -2:]
        mixed = (top2[:, 1] - top2[:, 0]) < math.sqrt(2) * math.sin(math.radians(max(blend, 20.0)) / 2)
        jump = np.abs(h[edges[:, 0]] - h[edges[:, 1]])
        seam = mixed[edges[:, 0]] | mixed[edges[:, 1]]
        bound[blend] = (jump[seam].max(), jump[~seam].max())
    seam, inside = bound[20.0]
    assert seam <= 1.5 * inside
    assert bound[0.0][0] > 1.5 * bound[0.0][1]  # the check can fail: a hard seam


@pytest.mark.parametrize("kind", ["cylinder", "sphere"])
def test_wrap_closes_without_a_seam(kind, waves):
    """A whole number of tiles around: the largest height jump across an edge crossing the wrap (angle +-pi) is at
    most 1.2 x the largest across edges crossing three other meridians (same orientation), on the side (the
    sphere's equatorial band); with the tile laid unstretched (a fraction of a tile left over) the jumps across the
    wrap are, in RMS, more than twice those across the other meridians."""
    can = trimesh.creation.cylinder(radius=7, height=8, sections=64) if kind == "cylinder" else \
        trimesh.creation.icosphere(4, radius=7)
    axis = axis_of((0, 0, 0), (0, 0, 1))
    fitted = wrap(waves, kind, axis, 7.0)
    assert fitted.tiles == 4 and fitted.stretch == pytest.approx(2 * math.pi * 7 / (4 * 12))
    unstretched = Wrap(waves, kind, axis, 7.0, 4, 1.0)
    jumps = {}
    for name, mapping in (("fitted", fitted), ("unstretched", unstretched)):
        v, n, h, edges = _vertex_heights(can, mapping, PIXEL * math.sqrt(2))
        side = np.abs(n[:, 2]) < 0.2
        ok = side[edges[:, 0]] & side[edges[:, 1]]
        _, e1, e2, _ = axis.frame()  # the wrap's angle 0 lies along e1
        angle = np.arctan2(v @ e2, v @ e1)
        jump = np.abs(h[edges[:, 0]] - h[edges[:, 1]])
        crossing = [ok & _crosses(angle, edges, at) for at in (math.pi, 0.0, math.pi / 2, -math.pi / 2)]
        across, control = crossing[0], crossing[1] | crossing[2] | crossing[3]  # control: three other meridians
        assert across.sum() > 20 and control.sum() > 60
        rms = [math.sqrt(np.mean(jump[k] ** 2)) for k in (across, control)]
        jumps[name] = (jump[across].max(), jump[control].max(), *rms)
    assert jumps["fitted"][0] <= 1.2 * jumps["fitted"][1]
    assert jumps["fitted"][2] <= 1.2 * jumps["fitted"][3]
    assert jumps["unstretched"][2] > 2 * jumps["unstretched"][3]


def _crosses(angle: np.ndarray, edges: np.ndarray, at: float) -> np.ndarray:
    """Edges that cross or touch the meridian at angle ``at`` (their ends on either side of it or one on it, both
    within 90 degrees of it)."""
    a, b = np.sin(angle[edges[:, 0]] - at), np.sin(angle[edges[:, 1]] - at)
    near = (np.cos(angle[edges[:, 0]] - at) > 0) & (np.cos(angle[edges[:, 1]] - at) > 0)
    return near & (a * b <= 1e-12) & ((np.abs(a) > 1e-12) | (np.abs(b) > 1e-12))


def test_uv_mapping_reads_the_mesh_coordinates(texture):
    ball = trimesh.creation.icosphere(3, radius=8)
    ball.visual = trimesh.visual.TextureVisuals(uv=ball.vertices[:, :2] / 10)  # a planar UV map, 10 mm per unit
    mapping = make_mapping("uv", texture, ball, uv_mm=10)
    top = ball.vertices[:, 2] > 0
    points, normals = ball.vertices[top], ball.vertex_normals[top]
    expected = texture.sample(points[:, 0], points[:, 1], periodic=True)
    assert np.abs(mapping.heights(points, normals) - expected).max() < 1e-9
    with pytest.raises(InputError, match="no texture coordinates"):
        make_mapping("uv", texture, trimesh.creation.box())


def test_whole_tiles_stretch_least():
    assert whole_tiles(50.0, 12.0) == (4, pytest.approx(50 / 48))
    assert whole_tiles(55.0, 12.0)[0] == 5  # 55/60 is a smaller change than 55/48
    assert whole_tiles(3.0, 12.0) == (1, 0.25)


def test_blend_weights_meet_at_one_half():
    assert blend_weights(np.array([0.0]), 20)[0] == 0.5
    half = math.sqrt(2) * math.sin(math.radians(10))
    assert list(blend_weights(np.array([-half, half]), 20)) == [0, 1]


# --- fitting, regions, sampling ------------------------------------------------------------------------------------

def test_cylinder_axis_and_radius_are_fitted(texture):
    can = trimesh.creation.cylinder(radius=6, height=30, sections=64)
    can.apply_transform(trimesh.transformations.rotation_matrix(0.7, (1, 1, 0)))
    can.apply_translation((3, -2, 5))
    mapping = make_mapping("cylinder", texture, can)
    assert abs(np.dot(mapping.axis.direction, can.principal_inertia_vectors[0])) == pytest.approx(1, abs=1e-6) or \
        abs(np.dot(mapping.axis.direction, trimesh.transformations.rotation_matrix(0.7, (1, 1, 0))[:3, 2])) \
        == pytest.approx(1, abs=1e-6)
    assert mapping.radius_mm == pytest.approx(6 * math.cos(math.pi / 64), rel=1e-3)
    flat = trimesh.creation.cylinder(radius=20, height=4, sections=64)  # a flat knob: the axis is the odd moment
    assert abs(make_mapping("cylinder", texture, flat).axis.direction[2]) == pytest.approx(1, abs=1e-6)


def test_regions_select_faces():
    box = trimesh.creation.box((10, 10, 10))
    assert Region().faces(box).all()
    top = parse_region("cone:0,0,1,30").faces(box)
    assert top.sum() == 2 and np.all(box.face_normals[top][:, 2] > 0.99)
    half = parse_region("box:-6,-6,-6,6,6,0").faces(box)
    assert np.all(box.triangles_center[half][:, 2] <= 0) and half.sum() == 6  # the bottom, a triangle of each side
    colours = np.full((len(box.vertices), 4), 255, dtype=np.uint8)
    colours[box.vertices[:, 0] > 0, :3] = (200, 10, 10)
    box.visual.vertex_colors = colours
    red = parse_region("colour:200,10,10,5").faces(box)
    assert red.sum() == 2 and np.all(box.face_normals[red][:, 0] > 0.99)
    with pytest.raises(InputError, match="no vertex or face colours"):
        parse_region("colour:1,2,3").faces(trimesh.creation.box())
    for bad in ("cone:0,0,1", "box:1,1,1,0,0,0", "colour:300,0,0", "ring", "cone:0,0,0,30", "cone:a,b,c,d"):
        with pytest.raises(InputError):
            parse_region(bad).faces(box)


def test_a_flat_face_samples_back_as_the_texture(texture):
    box = trimesh.creation.box((30, 30, 10))
    result = texture_mesh(box, Triplanar(texture), Region("cone", axis=(0, 0, 1), half_angle_deg=10))
    back = sample_heightmap(result, (0, 0, 5), (0, 0, 1), 12.0, PIXEL)
    n = back.shape[0]
    c = (np.arange(n) + 0.5 - n / 2) * PIXEL
    _, e1, e2, _ = axis_of((0, 0, 5), (0, 0, 1)).frame()
    x = c[None, :] * e1[0] + c[:, None] * e2[0]
    y = c[None, :] * e1[1] + c[:, None] * e2[1]
    expected = texture.sample(x, y, periodic=True)
    # the mesh interpolates the texture linearly over triangles of legs ~ one pixel: off by at most a pixel's slope
    slope = max(np.abs(np.diff(texture.heights, axis=a)).max() for a in (0, 1))
    assert np.abs(back.heights - expected).max() <= slope
    assert np.abs(back.heights - expected).mean() < 0.2 * slope


def test_sampling_outside_the_mesh_is_refused(texture):
    with pytest.raises(InputError, match="met no surface"):
        sample_heightmap(trimesh.creation.box((5, 5, 5)), (0, 0, 2.5), (0, 0, 1), 12.0, 0.5)


# --- files ---------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("suffix", [".stl", ".3mf"])
def test_write_and_read_back(suffix, tmp_path, texture):
    result = texture_mesh(sphere(), Triplanar(texture), check_intersections=False)
    written = write_mesh(result.mesh, tmp_path / f"out{suffix}")
    if suffix == ".stl":
        assert written.bytes == 84 + 50 * written.triangles
    back = read_mesh(written.path)
    assert back.triangles == written.triangles == result.triangles_out
    assert _closed(back.mesh)
    assert back.mesh.volume == pytest.approx(result.volume_out_mm3, rel=1e-5)  # float32 vertices in STL
    with pytest.raises(InputError, match="already exists"):
        write_mesh(result.mesh, written.path)


def test_bad_mesh_files_are_refused(tmp_path):
    cases = {"missing.stl": None, "empty.stl": b"", "garbage.stl": bytes(range(256)) * 3,
             "text.obj": b"hello\n", "mesh.xyz": b"1 2 3\n"}
    for name, data in cases.items():
        if data is not None:
            (tmp_path / name).write_bytes(data)
        with pytest.raises(InputError):
            read_mesh(tmp_path / name)
    open_box = trimesh.creation.box()
    open_box.update_faces(np.arange(len(open_box.faces)) != 0)
    open_box.export(tmp_path / "open.stl")
    with pytest.raises(InputError, match="not watertight"):
        read_mesh(tmp_path / "open.stl")
    count = 50_000_000  # declared triangles, above MAX_MESH_TRIANGLES
    big = tmp_path / "huge.stl"
    big.write_bytes(b" " * 80 + count.to_bytes(4, "little"))
    with open(big, "r+b") as f:
        f.truncate(84 + 50 * count)  # sparse: the declared size, nothing allocated
    with pytest.raises(InputError, match="MAX_MESH_TRIANGLES"):
        read_mesh(big)
    trimesh.PointCloud(np.random.default_rng(0).random((10, 3))).export(tmp_path / "points.ply")
    with pytest.raises(InputError, match="no triangles"):
        read_mesh(tmp_path / "points.ply")


def test_a_3mf_that_unpacks_beyond_the_limit_is_refused_unpacked(tmp_path, monkeypatch):
    import zipfile

    import roughness.objects.meshes as meshes

    monkeypatch.setattr(meshes, "MAX_MESH_FILE_BYTES", 1_000_000)  # the 4 GB limit, scaled down
    with zipfile.ZipFile(tmp_path / "bomb.3mf", "w", zipfile.ZIP_DEFLATED) as z:  # 2 MB of zeros, 2 kB packed
        z.writestr("3D/3dmodel.model", b"\0" * 2_000_000)
    assert (tmp_path / "bomb.3mf").stat().st_size < 10_000
    with pytest.raises(InputError, match="unpacks to 2,000,000 bytes"):
        read_mesh(tmp_path / "bomb.3mf")


def test_inside_out_mesh_is_turned_and_noted(tmp_path):
    box = trimesh.creation.box((2, 2, 2))
    box.invert()
    box.export(tmp_path / "inv.stl")
    read = read_mesh(tmp_path / "inv.stl")
    assert read.mesh.volume == pytest.approx(8)
    assert any("inside-out" in n for n in read.notes)


# --- CLI -----------------------------------------------------------------------------------------------------------

@pytest.fixture()
def knob_file(tmp_path, monkeypatch):
    knob().export(tmp_path / "knob.stl")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_cli_textures_a_knob(knob_file, capsys):
    argv = ["object", "texture", "knob.stl", "--texture", "standard-1.0", "--height-mm", "0.3", "--mapping",
            "cylinder", "--edge-mm", "0.5", "--out", "k.stl", "--preview", "k.png", "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["triangles"] == out["result"]["triangles_out"] > 10_000
    assert out["bytes"] == (knob_file / "k.stl").stat().st_size == 84 + 50 * out["triangles"]
    assert (knob_file / "k.png").stat().st_size > 10_000
    notes = " ".join(out["notes"])
    for said in ("read as mm", "scaled by 0.3", "whole tile(s)", "remeshed", "no two faces cross"):
        assert said in notes
    assert _closed(read_mesh(knob_file / "k.stl").mesh)
    before = (knob_file / "k.stl").read_bytes()
    assert main(argv) == 2  # never overwritten unasked
    assert (knob_file / "k.stl").read_bytes() == before


@pytest.mark.parametrize("extra, names", [
    (["--texture", "nosuch"], ("nosuch",)),
    (["--region", "cone:0,0,1"], ("--region",)),
    (["--region", "box:100,100,100,101,101,101"], ("selects no face",)),
    (["--axis", "0,0,0,0,0,0"], ("--axis",)),
    (["--axis", "1,2"], ("--axis",)),
    (["--mapping", "triplanar", "--radius-mm", "5"], ("--axis", "--radius-mm")),
    (["--mapping", "uv"], ("UV",)),
    (["--out", "k.obj"], ("k.obj",)),
    (["--preview", "k.jpg"], ("--preview",)),
    (["--texture", "standard-1.0", "--pixel-mm", "0.1"], ("--pixel-mm",)),
])
def test_cli_bad_input_exits_2(extra, names, knob_file, capsys):
    argv = ["object", "texture", "knob.stl", "--texture", "standard-1.0", "--edge-mm", "1", "--out", "k.stl", *extra]
    _expect_refusal(argv, knob_file, capsys, names)


def test_cli_refuses_a_texture_deeper_than_a_hollow(tmp_path, monkeypatch, capsys):
    cavity = trimesh.creation.icosphere(4, radius=1.0)
    cavity.invert()
    trimesh.util.concatenate([trimesh.creation.box((6, 6, 6)), cavity]).export(tmp_path / "hollow.stl")
    monkeypatch.chdir(tmp_path)
    argv = ["object", "texture", "hollow.stl", "--texture", "standard-1.0", "--region", "box:-1.5,-1.5,-1.5,1.5,1.5,1.5",
            "--edge-mm", "0.3", "--out", "h.stl"]
    _expect_refusal(argv, tmp_path, capsys, ("concave with a radius",))


def test_smoothed_normals_spread_the_turn_of_a_crease(texture):
    """Smoothing the normals over a radius spreads a crease's turn over more edges: the smallest concave radius the
    displacement sees grows, and the smoothing is reported."""
    cavity = trimesh.creation.icosphere(2, radius=2.0)  # facets of about 1 mm: creases between them
    cavity.invert()
    block = trimesh.util.concatenate([trimesh.creation.box((8, 8, 8)), cavity])
    region = Region("box", low=(-2.5, -2.5, -2.5), high=(2.5, 2.5, 2.5))
    shallow = Triplanar(Heightmap(texture.heights / 10, PIXEL))
    plain = texture_mesh(block, shallow, region)
    smooth = texture_mesh(block, shallow, region, normal_radius_mm=1.0)
    assert plain.normal_smoothing_rounds == 0 and smooth.normal_smoothing_rounds == 8  # (1 / 0.354)^2 rounded up
    assert smooth.min_concave_radius_mm > 1.5 * plain.min_concave_radius_mm
    assert any("smoothed over about 1 mm" in n for n in smooth.notes)
    assert _closed(smooth.mesh)


def test_a_region_border_stays_put_so_the_faces_beside_it_are_not_turned_over():
    """A box's top alone, textured with standard-1.0 (1 mm relief) at 0.05 mm: with the border ramp the top's edge
    does not move (the side faces keep their shape) and the mesh is closed; without it the long thin side faces the
    refinement makes at the edge turn over."""
    box = trimesh.creation.box((8.0, 8.0, 8.0))
    top = Region("cone", axis=(0.0, 0.0, 1.0), half_angle_deg=10.0)
    deep = named_texture("standard-1.0")
    result = texture_mesh(box, Triplanar(deep), top, border_mm=0.5, check_intersections=False)
    v = np.asarray(result.mesh.vertices)
    edge = (np.abs(np.abs(v[:, 0]) - 4) < 1e-9) | (np.abs(np.abs(v[:, 1]) - 4) < 1e-9)
    assert np.abs(v[edge & (v[:, 2] > 3.9), 2] - 4.0).max() < 1e-12  # the top's border: not displaced
    assert result.mesh.is_watertight and result.mesh.is_winding_consistent
    assert v[:, 2].max() > 4.0 + 0.9  # the texture's full height away from the border
    with pytest.raises(InputError, match="turns .* faces over"):
        texture_mesh(box, Triplanar(deep), top, border_mm=0.0, check_intersections=False)


def test_needle_shaped_input_faces_are_noted():
    """A capsule's cylinder band is one ring of 80 x 1.2 mm faces: the notes say they refine into slivers; an
    icosphere's faces are not needles."""
    from roughness.objects.texturing import needle_faces

    capsule = trimesh.creation.capsule(height=80.0, radius=12.0, count=[64, 64])
    ball = trimesh.creation.icosphere(subdivisions=3, radius=30.0)
    assert needle_faces(np.asarray(capsule.vertices), np.asarray(capsule.faces), 0.3) >= 128  # the band's faces
    assert needle_faces(np.asarray(ball.vertices), np.asarray(ball.faces), 0.3) == 0
    flat = Heightmap(np.zeros((40, 40)), 1.0)
    result = texture_mesh(capsule, Triplanar(flat), check_intersections=False)
    assert any("needle-shaped" in note for note in result.notes)


# --- --printer: the edge from the printer, the plan before refining -----------------------------------------------

def test_the_printer_sets_the_edge_but_never_below_the_texture_pixel():
    from roughness.objects.print_plan import printer_edge
    from roughness.surface.printing import PROFILES

    fdm = printer_edge(PROFILES["fdm-0.4-0.2"], 0.05)
    assert fdm.edge_mm == pytest.approx(0.225) and "line width" in fdm.note()  # half the 0.45 mm line
    sla = printer_edge(PROFILES["msla-35um"], 0.01)
    assert sla.edge_mm == pytest.approx(0.035)  # one LCD pixel
    coarse = printer_edge(PROFILES["msla-35um"], 0.05)  # the texture is coarser than the printer
    assert coarse.edge_mm == pytest.approx(math.sqrt(2) * 0.05) and "texture's (" in coarse.note()


def test_the_edge_given_wins_then_the_printers_then_the_textures():
    from roughness.objects.print_plan import chosen_edge, printer_edge
    from roughness.surface.printing import PROFILES

    fdm = PROFILES["fdm-0.4-0.2"]
    assert chosen_edge(0.3, fdm, 0.05) == (0.3, None)  # --edge-mm: no rule to state
    assert chosen_edge(None, fdm, 0.05) == (printer_edge(fdm, 0.05).edge_mm, printer_edge(fdm, 0.05).note())
    assert chosen_edge(None, None, 0.05) == (pytest.approx(math.sqrt(2) * 0.05), None)


def test_a_mesh_too_large_for_slicers_is_warned_before_refining():
    from roughness.objects.print_plan import SLICER_TRIANGLES, mesh_plan

    box = trimesh.creation.box((6, 6, 6))
    faces = np.asarray(box.faces)
    small = mesh_plan(np.asarray(box.vertices), faces, np.ones(len(faces), bool), 0.2)
    made = len(refine(np.asarray(box.vertices), faces, np.ones(len(faces), bool), 0.2).faces)
    assert small.warning() is None and small.triangles == made  # congruent faces: the sample's count is exact
    assert small.stl_bytes == 84 + 50 * small.triangles
    huge = mesh_plan(np.asarray(box.vertices), faces, np.ones(len(faces), bool), 0.005)  # only estimated
    assert huge.triangles > SLICER_TRIANGLES and "slicers handle comfortably" in huge.warning()
    unchecked = mesh_plan(np.asarray(box.vertices), faces, np.ones(len(faces), bool), 0.005, False)
    assert 0 < unchecked.seconds < huge.seconds  # the self-intersection check costs time


def test_cli_printer_sets_the_edge_and_reports_digital_and_printed_v(tmp_path, monkeypatch, capsys):
    trimesh.creation.box((6, 6, 6)).export(tmp_path / "box.stl")
    monkeypatch.chdir(tmp_path)
    argv = ["object", "texture", "box.stl", "--texture", "standard-1.0", "--height-mm", "0.3", "--printer",
            "fdm-0.4-0.2", "--out", "b.stl", "--json"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert out["result"]["edge_mm"] == pytest.approx(0.225) == out["plan"]["edge_mm"]
    assert out["plan"]["triangles"] == out["triangles"]  # the box's faces are congruent: the measured estimate is exact
    printing = out["printing"]
    assert printing["printer"]["name"] == "fdm-0.4-0.2"
    assert printing["printed"]["roughness"] < printing["digital"]["roughness"]  # the bead rounds the bumps off
    assert "expected: about" in captured.err and "as printed (fdm-0.4-0.2)" in captured.err
    assert any("from the printer fdm-0.4-0.2" in n for n in out["notes"])


def test_cli_unknown_printer_exits_2(knob_file, capsys):
    argv = ["object", "texture", "knob.stl", "--texture", "standard-1.0", "--printer", "nosuch", "--out", "k.stl"]
    _expect_refusal(argv, knob_file, capsys, ("nosuch",))


# --- progress of the long steps --------------------------------------------------------------------------------------

def test_long_steps_report_rising_fractions_that_end_at_one(tmp_path):
    box = trimesh.creation.box((6, 6, 6))
    faces = np.asarray(box.faces)
    seen: dict[str, list[float]] = {"refine": [], "cross": [], "write": []}
    refined = refine(np.asarray(box.vertices), faces, np.ones(len(faces), bool), 0.3, seen["refine"].append)
    self_intersections(refined.vertices, refined.faces, progress=seen["cross"].append)
    write_mesh(trimesh.Trimesh(refined.vertices, refined.faces, process=False), tmp_path / "b.stl",
               progress=seen["write"].append)
    for name, fractions in seen.items():
        assert fractions and fractions[-1] == 1.0, name
        assert all(0 <= a <= b <= 1 for a, b in zip(fractions, fractions[1:])), (name, fractions)
    assert len(seen["refine"]) == refined.rounds + 1  # one per round, then done


def test_time_left_scales_the_time_so_far_by_the_work_left():
    from roughness.objects.progress import StageMeter, eta_seconds

    assert eta_seconds(10.0, 0.25) == pytest.approx(30.0)
    assert eta_seconds(10.0, 0.0) is None and eta_seconds(10.0, 1.0) == 0
    text = StageMeter().text("refine", 0.5, 20.0)
    assert "refine:  50%" in text and "about 20 s left" in text


def test_cli_progress_is_plain_lines_when_stderr_is_not_a_terminal(knob_file, capsys):
    argv = ["object", "texture", "knob.stl", "--texture", "standard-1.0", "--region", "box:-9,-9,9,9,9,14",
            "--edge-mm", "1", "--out", "k.stl", "--preview", "k.png"]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "\r" not in err
    for line in ("refine: 100%", "self-intersection check: 100%", "writing k.stl: 100%", "preview k.png: 100%"):
        assert line in err


def test_cli_texture_too_coarse_for_the_printer_exits_2_before_meshing(knob_file, capsys):
    np.save(knob_file / "coarse.npy", np.random.default_rng(0).random((48, 48)) * 0.3)
    argv = ["object", "texture", "knob.stl", "--texture", "coarse.npy", "--pixel-mm", "0.25", "--printer",
            "fdm-0.4-0.2", "--out", "k.stl"]
    _expect_refusal(argv, knob_file, capsys, ("--printer",))


def test_cli_warns_on_stderr_and_in_the_notes_when_slicers_would_struggle(knob_file, capsys, monkeypatch):
    from roughness.objects import print_plan

    monkeypatch.setattr(print_plan, "SLICER_TRIANGLES", 1_000)  # the knob's top at 1 mm edges is more
    argv = ["object", "texture", "knob.stl", "--texture", "standard-1.0", "--region", "box:-9,-9,9,9,9,14",
            "--edge-mm", "1", "--out", "k.stl", "--json", "--quiet"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert out["plan"]["too_large_for_slicers"] and "roughness: warning:" in captured.err  # even with --quiet
    assert any("slicers handle comfortably" in n for n in out["notes"])


@pytest.mark.parametrize("shape", ["cylinder sides (needles)", "icosphere", "box"])
def test_the_triangle_estimate_is_measured_not_assumed(shape):
    """The estimate before refining is the sampled faces' own refinement scaled to the area: within 10% of what
    refinement makes (congruent faces are counted exactly; joining neighbours and the untextured transition add a
    few percent). The area rule it replaced said 1/8 of the triangles for a 96-sided cylinder's sides."""
    from roughness.objects.remesh import predicted_triangles

    if shape.startswith("cylinder"):
        mesh = trimesh.creation.cylinder(radius=5, height=20, sections=48)
        textured = np.abs(mesh.triangles_center[:, 2]) < 9.5
    else:
        mesh = trimesh.creation.icosphere(2, radius=5) if shape == "icosphere" else trimesh.creation.box((6, 6, 6))
        textured = np.ones(len(mesh.faces), bool)
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    made = len(refine(v, f, textured, 0.4).faces)
    assert predicted_triangles(v, f, textured, 0.4) == pytest.approx(made, rel=0.1)

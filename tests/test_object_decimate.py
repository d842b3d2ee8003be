"""Slicer-sized output (issue 41): the measured surface distance, decimation within a tolerance (closed, measured
within it, refused where nothing holds it), `object texture --decimate-mm`, and V of a decimated part against the
full one. Small parts at coarse edges, so that each test takes seconds."""
from __future__ import annotations

import json

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("fast_simplification")

from roughness.cli import main  # noqa: E402
from roughness.core.errors import InputError  # noqa: E402
from roughness.dataset.textures import named_texture  # noqa: E402
from roughness.objects.decimate import decimate, without_fins  # noqa: E402
from roughness.objects.mapping import Triplanar  # noqa: E402
from roughness.objects.surface_distance import (  # noqa: E402
    TriangleSurface,
    point_triangle_distance,
    surface_distance,
)
from roughness.objects.texturing import texture_mesh  # noqa: E402
from roughness.surface.solid import check_solid  # noqa: E402

ROUND = 1e-12  # mm: rounding of distances between points within 10 mm (float64 carries 1e-15 relative)


@pytest.fixture(scope="module")
def textured():
    """A 16 mm ball textured with standard-1.0 at a 0.2 mm edge (about 120,000 triangles)."""
    ball = trimesh.creation.icosphere(3, radius=8.0)
    return texture_mesh(ball, Triplanar(named_texture("standard-1.0")), edge_mm=0.2).mesh


def test_point_triangle_distance_is_the_closest_points():
    """Against trimesh's closest points on random triangles, with degenerate ones (a line, a point twice)."""
    rng = np.random.default_rng(3)
    p, a, b, c = (rng.standard_normal((5000, 3)) for _ in range(4))
    c[:50] = a[:50] + 0.3 * (b[:50] - a[:50])  # collinear corners
    b[50:100] = a[50:100]  # two corners at one point
    mine = point_triangle_distance(p, a, b, c)
    nearest = trimesh.triangles.closest_point(np.stack([a, b, c], axis=1)[100:], p[100:])
    assert np.abs(mine[100:] - np.linalg.norm(nearest - p[100:], axis=1)).max() < ROUND
    segment = np.stack([a[:100], b[:100], c[:100]], axis=1)  # degenerate: the nearest of many points on its edges
    t = np.linspace(0, 1, 2001)[:, None, None]
    on_edges = np.concatenate([segment[:, i] + t * (segment[:, (i + 1) % 3] - segment[:, i]) for i in range(3)])
    brute = np.linalg.norm(on_edges - p[:100], axis=2).min(axis=0)
    assert np.all(mine[:100] <= brute + ROUND) and np.all(brute - mine[:100] < 1e-3)  # the grid's step, 1/2000


def test_distances_are_the_nearest_triangles():
    """Every point's distance is the minimum over all triangles (brute force), on a mesh of mixed sizes."""
    import fast_simplification

    sphere = trimesh.creation.icosphere(3, radius=5.0)
    v, f = fast_simplification.simplify(sphere.vertices, sphere.faces, target_reduction=0.8)
    surface = TriangleSurface(v, f)
    points = np.random.default_rng(0).uniform(-6, 6, (400, 3))
    tri = np.asarray(v)[np.asarray(f)]
    brute = np.array([point_triangle_distance(np.broadcast_to(q, (len(tri), 3)), tri[:, 0], tri[:, 1],
                                              tri[:, 2]).min() for q in points])
    assert np.abs(surface.distances(points) - brute).max() < ROUND


def test_surface_distance_of_a_shifted_box_is_the_shift():
    """A box and the same box 0.003 mm higher: every point of either lies at most 0.003 mm from the other, the
    bottom and top faces exactly that."""
    box = trimesh.creation.box((10, 10, 10)).subdivide().subdivide()
    shifted = box.vertices + [0, 0, 0.003]
    found = surface_distance(TriangleSurface(box.vertices, box.faces), TriangleSurface(shifted, box.faces), 1.0)
    assert abs(found.a_to_b_mm - 0.003) < ROUND and abs(found.b_to_a_mm - 0.003) < ROUND
    assert found.covering_mm <= 1.0 / np.sqrt(3)


def test_without_fins_removes_folded_pairs():
    """A tetrahedron with a fin (two faces on the same corners, wound opposite ways, on one of its edges) is not a
    closed solid; without the fin it is, and the fin's own corner is gone."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1.0]])
    tetra = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    fin = np.array([[1, 2, 4], [2, 1, 4]])
    faces = np.concatenate([tetra, fin])
    assert not check_solid(v, faces, np.float64).closed
    v2, f2 = without_fins(v, faces)
    assert check_solid(v2, f2, np.float64).closed and len(v2) == 4 and len(f2) == 4


def test_decimate_holds_the_tolerance_measured_independently(textured):
    """Decimated within 0.01 mm: fewer triangles, a closed solid, and every vertex of each within 0.01 mm of the other
    surface by trimesh's own closest points (an independent measurement)."""
    found = decimate(textured.vertices, textured.faces, 0.01)
    assert found.triangles < 0.75 * len(textured.faces)
    assert found.distance.max_mm <= 0.01 and found.check.closed
    assert check_solid(found.vertices, found.faces, np.float64).closed
    small = trimesh.Trimesh(found.vertices, found.faces, process=False)
    full_vertices = textured.vertices[np.random.default_rng(1).choice(len(textured.vertices), 20_000, replace=False)]
    assert trimesh.proximity.closest_point(small, full_vertices)[1].max() <= 0.01 + ROUND
    assert trimesh.proximity.closest_point(textured, found.vertices)[1].max() <= 0.01 + ROUND
    assert found.attempts[-1].measured == "all" and not found.attempts[-1].failed


def test_decimate_refuses_a_tolerance_nothing_holds(textured):
    with pytest.raises(InputError, match="no decimation") as err:
        decimate(textured.vertices, textured.faces, 1e-4)  # above the file's rounding, far below the texture
    assert err.value.parameter == "decimate_mm" and "candidates" in str(err.value)
    with pytest.raises(InputError, match="rounds each vertex"):
        decimate(textured.vertices, textured.faces, 1e-7)
    with pytest.raises(InputError):
        decimate(textured.vertices, textured.faces, 0.0)


def test_cli_texture_decimate(tmp_path, capsys):
    """`object texture --decimate-mm`: the 3MF is decimated, smaller than the full mesh, and the JSON says both
    sizes and the measured distance; the closed-solid check of the file passed."""
    ball = tmp_path / "ball.stl"
    trimesh.creation.icosphere(3, radius=8.0).export(ball)
    out = tmp_path / "ball.3mf"
    assert main(["object", "texture", str(ball), "--texture", "standard-1.0", "--edge-mm", "0.2", "--decimate-mm",
                 "0.01", "--no-feel-check", "--out", str(out), "--json", "--quiet"]) == 0
    got = json.loads(capsys.readouterr().out)
    dec = got["result"]["decimation"]
    assert got["triangles"] == dec["triangles"] < got["full"]["triangles"] == got["result"]["triangles_out"]
    assert dec["distance_mm"] <= 0.01 and got["check"]["closed"] and got["feel_change"] is None
    read = trimesh.load(out, force="mesh")
    assert len(read.faces) == dec["triangles"] and read.is_watertight
    assert main(["object", "texture", str(ball), "--texture", "standard-1.0", "--decimate-mm", "-1", "--out",
                 str(tmp_path / "x.3mf")]) == 2
    assert "--decimate-mm" in capsys.readouterr().err


@pytest.mark.slow  # 40-100 s; benchmarks/slicer_size.py measures the same on whole parts
def test_decimated_part_feels_the_same():
    """V of a 24 mm ball textured at a 0.2 mm edge, decimated within 0.01 mm, against the full one at the same
    footprints: within 0.1 JND at every point judged."""
    from roughness.objects.feel_change import SAME_FEEL_JND, feel_change

    ball = trimesh.creation.icosphere(3, radius=12.0)
    full = texture_mesh(ball, Triplanar(named_texture("standard-1.0")), edge_mm=0.2,
                        check_intersections=False).mesh
    found = decimate(full.vertices, full.faces, 0.01)
    change = feel_change(full, trimesh.Trimesh(found.vertices, found.faces, process=False), spacing_mm=12.0)
    assert change.points >= 6 and change.max_jnd <= SAME_FEEL_JND and change.same
    assert np.isfinite(change.max_jnd_stderr) and change.median_v > 0


def test_a_candidate_the_screen_passed_but_all_samples_refuse_is_bisected_past(textured, monkeypatch):
    """With a screen of 20 samples the screen lets through candidates that fail when every sample is measured (here
    all of them); the search then bisects between the largest of those and the full mesh, all measured, and
    returns the fewest triangles that held, with every attempt listed."""
    from roughness.objects import decimate as module

    monkeypatch.setattr(module, "SCREEN_SAMPLES", 20)
    found = decimate(textured.vertices, textured.faces, 0.01)
    assert found.distance.max_mm <= 0.01 - module.ROUNDING_MM and found.check.closed
    assert found.triangles < len(textured.faces)
    verified = [a for a in found.attempts if a.measured == "all"]
    refused = [a.triangles for a in verified if a.failed]
    held = [a.triangles for a in verified if not a.failed]
    assert refused and found.triangles == min(held)
    assert max(r for r in refused if r < found.triangles) < found.triangles  # bisected up from a refused count
    assert found.attempts[-1] is verified[-1] or found.attempts[-1].measured == "screen"

"""The compact 3MF writer (issue 41): trimesh reads back the same closed surface (each vertex within the rounding),
in millimetres; the triangles come in space-filling-curve order; progress is told; a mesh that rounding would break
is written with more decimals; an open one is refused, not written."""
from __future__ import annotations

import re
import zipfile

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from roughness.core.errors import SimulationError  # noqa: E402
from roughness.objects import threemf  # noqa: E402
from roughness.objects.meshes import read_mesh, write_mesh  # noqa: E402

ROUND = 1e-12  # mm: float64 rounding of coordinates within 100 mm


@pytest.fixture(scope="module")
def rough_ball():
    """A 20 mm ball with random relief (0.05 mm), its triangles shuffled as a decimator might leave them."""
    ball = trimesh.creation.icosphere(5, radius=10.0)
    rng = np.random.default_rng(0)
    vertices = ball.vertices * (1 + 0.005 * rng.random((len(ball.vertices), 1)))
    return trimesh.Trimesh(vertices, ball.faces[rng.permutation(len(ball.faces))], process=False)


def _corner_sets(vertices: np.ndarray, faces: np.ndarray, decimals: int) -> set:
    """Each triangle as the set of its rotations' smallest corner tuple, rounded (a winding-preserving key)."""
    corners = np.round(vertices[faces], decimals)
    keys = set()
    for tri in corners.tolist():
        rotations = [tuple(map(tuple, tri[k:] + tri[:k])) for k in range(3)]
        keys.add(min(rotations))
    return keys


def test_trimesh_reads_back_the_same_surface_in_mm(rough_ball, tmp_path):
    seen: list[float] = []
    written = write_mesh(rough_ball, tmp_path / "ball.3mf", progress=seen.append)
    assert written.triangles == len(rough_ball.faces) and written.check.closed
    read = trimesh.load(tmp_path / "ball.3mf", force="mesh")
    assert read.units in ("millimeters", "millimeter", "mm")
    assert read.is_watertight and read.is_winding_consistent and read.volume > 0
    assert len(read.faces) == len(rough_ball.faces)
    # every vertex moved by at most the rounding, and the triangles are the same ones, wound the same way
    moved = trimesh.proximity.closest_point(read, rough_ball.vertices)[1]
    assert moved.max() <= threemf.ROUNDING_MM + ROUND
    rounded = np.round(rough_ball.vertices, threemf.DECIMALS[0])
    assert _corner_sets(read.vertices, read.faces, 6) == _corner_sets(rounded, rough_ball.faces, 6)
    assert read_mesh(tmp_path / "ball.3mf").notes == []  # our own reader takes it without a note
    assert seen and seen == sorted(seen) and seen[-1] == 1.0


def test_coordinates_are_written_rounded_and_the_triangles_in_curve_order(rough_ball, tmp_path):
    """The file's text holds DECIMALS decimals; consecutive triangles lie near each other (shuffled, they do not)."""
    write_mesh(rough_ball, tmp_path / "ball.3mf")
    first = _coordinate_text(tmp_path / "ball.3mf")
    assert all(len(value.split(".")[1]) == threemf.DECIMALS[0] for value in first.split('"')[1::2])
    vertices, faces = threemf.ordered(rough_ball.vertices, rough_ball.faces)
    step = np.linalg.norm(np.diff(vertices[faces].mean(axis=1), axis=0), axis=1)
    shuffled = np.linalg.norm(np.diff(rough_ball.triangles_center, axis=0), axis=1)
    edge = float(np.median(rough_ball.edges_unique_length))
    assert np.median(step) < 2 * edge < np.median(shuffled)
    assert faces.max() == len(vertices) - 1 and len(np.unique(faces)) == len(vertices)


def _coordinate_text(path) -> str:
    with zipfile.ZipFile(path) as z:
        text = z.read(threemf.MODEL).decode()
    start = text.index("<vertex ")
    return text[start:text.index("/>", start)]


def test_a_mesh_that_rounding_would_break_is_written_with_more_decimals(tmp_path):
    """A closed box 0.00004 mm across: at 4 decimals its corners collapse onto one point, so the writer takes the next
    decimals at which the mesh as written is still a closed solid (6), and trimesh reads the same box back."""
    tiny = trimesh.creation.box((4e-5, 4e-5, 4e-5))
    write_mesh(tiny, tmp_path / "tiny.3mf")
    assert all(len(value.split(".")[1]) == 6 for value in _coordinate_text(tmp_path / "tiny.3mf").split('"')[1::2])
    read = trimesh.load(tmp_path / "tiny.3mf", force="mesh")
    assert read.is_watertight and np.allclose(read.extents, 4e-5, rtol=0, atol=ROUND)


def test_an_open_mesh_is_not_written(tmp_path):
    """Defects that no number of decimals mends are refused, and no file is left."""
    open_box = trimesh.creation.box((10, 10, 10))
    open_box = trimesh.Trimesh(open_box.vertices, open_box.faces[1:], process=False)
    with pytest.raises(SimulationError, match="was not written"):
        write_mesh(open_box, tmp_path / "open.3mf")
    assert not list(tmp_path.iterdir())


def test_only_the_vertices_rounding_would_weld_take_more_decimals(tmp_path):
    """A ball whose one edge is 0.00002 mm long (a decimator's sliver): at 4 decimals its two ends would weld, so those
    vertices (and the corners of triangles that would flatten) are written with 6, every other vertex with 4, and
    trimesh reads back a closed solid with each vertex within the rounding."""
    ball = trimesh.creation.icosphere(3, radius=5.0)
    vertices = ball.vertices.copy()
    a, b = ball.edges_unique[0]
    vertices[a] = np.round(vertices[a], 4) + 1e-5
    vertices[b] = vertices[a] + np.array([2e-5, 0.0, 0.0])
    sliver = trimesh.Trimesh(vertices, ball.faces, process=False)
    write_mesh(sliver, tmp_path / "sliver.3mf")
    with zipfile.ZipFile(tmp_path / "sliver.3mf") as z:
        text = z.read(threemf.MODEL).decode()
    places = [len(number.split(".")[1]) for xyz in re.findall(r'<vertex x="([^"]+)" y="([^"]+)" z="([^"]+)"', text)
              for number in xyz]
    assert places.count(6) >= 2 * 3 and places.count(6) <= 12 * 3 and set(places) == {4, 6}
    read = trimesh.load(tmp_path / "sliver.3mf", force="mesh")
    assert read.is_watertight and len(read.faces) == len(ball.faces)
    assert trimesh.proximity.closest_point(read, vertices)[1].max() <= threemf.ROUNDING_MM + ROUND

"""Graded tetrahedral mesh of the skin block, built with TetGen.

The block occupies x, y in [-W/2, W/2] (mm) and z in [0, T] with the contact face at
z = 0 and the bone above. The contact face is a structured grid of spacing ``h_contact``;
the spacing stays at ``h_contact`` down to ``fine_depth`` (through the receptor depth)
and then grows linearly with height up to ``h_max``. An optional elastic bone layer
is meshed above z = T as a second region.
"""
from __future__ import annotations

import os
import sys
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from roughness.core.files import atomic_write
from roughness.core.hashing import digest

TISSUE, BONE = 0, 1
MESH_FORMAT_VERSION = 3

# Edges of a tetrahedron in VTK quadratic-tetra order: nodes 4..9 are their midpoints.
TET_EDGES = np.array([[0, 1], [1, 2], [0, 2], [0, 3], [1, 3], [2, 3]])


@dataclass(frozen=True)
class MeshSpec:
    """Geometry and grading of the block mesh (lengths in mm)."""

    width_mm: float = 10.0
    tissue_mm: float = 2.5
    bone_mm: float = 0.0
    h_contact_mm: float = 0.15
    fine_depth_mm: float = 1.0
    growth: float = 0.35
    h_max_mm: float = 1.0
    order: int = 1

    def spacing(self, z: float | np.ndarray) -> np.ndarray:
        """Target edge length (mm) at height z above the contact face."""
        z = np.asarray(z, dtype=float)
        grown = self.h_contact_mm + self.growth * np.maximum(z - self.fine_depth_mm, 0.0)
        return np.minimum(grown, max(self.h_max_mm, self.h_contact_mm))

    def key(self) -> str:
        return digest({**asdict(self), "format": MESH_FORMAT_VERSION})


@dataclass
class Mesh:
    """Tetrahedral mesh: ``tets`` holds 4 (P1) or 10 (P2, VTK order) node indices."""

    points: np.ndarray
    tets: np.ndarray
    region: np.ndarray
    spec: MeshSpec

    @property
    def order(self) -> int:
        return 1 if self.tets.shape[1] == 4 else 2

    @property
    def top_z(self) -> float:
        return self.spec.tissue_mm + self.spec.bone_mm

    def nodes_at_z(self, z: float) -> np.ndarray:
        tol = 1e-9 * max(1.0, abs(z))
        return np.flatnonzero(np.abs(self.points[:, 2] - z) <= tol)

    @property
    def bottom(self) -> np.ndarray:
        """Nodes on the contact face (z = 0)."""
        return self.nodes_at_z(0.0)

    @property
    def top(self) -> np.ndarray:
        """Nodes on the face attached to the bone (Dirichlet face)."""
        return self.nodes_at_z(self.top_z)


def _levels(spec: MeshSpec, z_from: float, z_to: float) -> np.ndarray:
    """Heights of side-face rows between two facets, spaced by the target spacing."""
    z = np.linspace(z_from, z_to, 2001)
    s = np.concatenate([[0.0], np.cumsum(np.diff(z) / spec.spacing(0.5 * (z[1:] + z[:-1])))])
    n = max(1, int(np.ceil(s[-1] - 1e-9)))
    return np.interp(np.linspace(0.0, s[-1], n + 1), s, z)


def _facet_heights(spec: MeshSpec) -> list[float]:
    facets = [0.0]
    if 0.0 < spec.fine_depth_mm < spec.tissue_mm:
        facets.append(spec.fine_depth_mm)
    facets.append(spec.tissue_mm)
    if spec.bone_mm > 0:
        facets.append(spec.tissue_mm + spec.bone_mm)
    return facets


class _PointSet:
    """Deduplicating point registry used to build the surface triangulation."""

    def __init__(self) -> None:
        self.coords: list[tuple[float, float, float]] = []
        self.index: dict[tuple[int, int, int], int] = {}

    def add(self, x: float, y: float, z: float) -> int:
        k = (round(x * 1e8), round(y * 1e8), round(z * 1e8))
        if k not in self.index:
            self.index[k] = len(self.coords)
            self.coords.append((x, y, z))
        return self.index[k]


def _segments(spec: MeshSpec, z: float) -> int:
    return max(1, int(np.ceil(spec.width_mm / float(spec.spacing(z)) - 1e-9)))


def _grid_facet(ps: _PointSet, spec: MeshSpec, z: float) -> list[tuple[int, int, int]]:
    """Structured criss-cross triangulation of the horizontal face at height z."""
    n = _segments(spec, z)
    c = np.linspace(-spec.width_mm / 2, spec.width_mm / 2, n + 1)
    idx = [[ps.add(c[i], c[j], z) for j in range(n + 1)] for i in range(n + 1)]
    tris = []
    for i in range(n):
        for j in range(n):
            a, b, cc, d = idx[i][j], idx[i + 1][j], idx[i + 1][j + 1], idx[i][j + 1]
            if (i + j) % 2 == 0:
                tris += [(a, b, cc), (a, cc, d)]
            else:
                tris += [(a, b, d), (b, cc, d)]
    return tris


def _side_rows(ps: _PointSet, spec: MeshSpec, z: float) -> list[list[int]]:
    """Point rows along the four sides of the block at height z (corners shared)."""
    n = _segments(spec, z)
    h = spec.width_mm / 2
    t = np.linspace(-h, h, n + 1)
    return [
        [ps.add(x, -h, z) for x in t],
        [ps.add(h, y, z) for y in t],
        [ps.add(x, h, z) for x in t[::-1]],
        [ps.add(-h, y, z) for y in t[::-1]],
    ]


def _zip(a: list[int], b: list[int]) -> list[tuple[int, int, int]]:
    """Triangulate the strip between two point rows spanning the same edge."""
    ta, tb = np.linspace(0, 1, len(a)), np.linspace(0, 1, len(b))
    i = j = 0
    tris = []
    while i < len(a) - 1 or j < len(b) - 1:
        if j == len(b) - 1 or (i < len(a) - 1 and ta[i + 1] <= tb[j + 1]):
            tris.append((a[i], b[j], a[i + 1]))
            i += 1
        else:
            tris.append((a[i], b[j], b[j + 1]))
            j += 1
    return tris


def surface(spec: MeshSpec) -> tuple[np.ndarray, np.ndarray, list[float]]:
    """Surface triangulation (with internal facets) of the graded block.

    Returns points (n, 3), triangles (m, 3) and the facet heights.
    """
    ps = _PointSet()
    facets = _facet_heights(spec)
    tris: list[tuple[int, int, int]] = []
    for z in facets:
        tris += _grid_facet(ps, spec, z)
    rows_prev = _side_rows(ps, spec, facets[0])
    for z0, z1 in zip(facets[:-1], facets[1:]):
        for z in _levels(spec, z0, z1)[1:]:
            rows = _side_rows(ps, spec, z)
            for ra, rb in zip(rows_prev, rows):
                tris += _zip(ra, rb)
            rows_prev = rows
    return np.array(ps.coords, dtype=float), np.array(tris, dtype=np.int32), facets


def _tet_volume(h: float) -> float:
    return h**3 / (6.0 * np.sqrt(2.0))


@contextmanager
def _quiet_stdout():
    """Silence C-level writes to stdout (TetGen prints even with -Q), keeping JSON output clean."""
    sys.stdout.flush()
    saved = os.dup(1)
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), 1)
        try:
            yield
        finally:
            os.dup2(saved, 1)
            os.close(saved)


def tetrahedralize(spec: MeshSpec) -> Mesh:
    """Mesh the block with TetGen (quality 1.5, boundary preserved, layer volumes)."""
    import tetgen

    points, tris, facets = surface(spec)
    tg = tetgen.TetGen(points, tris)
    for k, (z0, z1) in enumerate(zip(facets[:-1], facets[1:])):
        h = float(spec.spacing(z1))
        region = BONE if z0 >= spec.tissue_mm - 1e-12 else TISSUE
        tg.add_region(10 * k + region, (0.1234, -0.0987, 0.5 * (z0 + z1)), 1.3 * _tet_volume(h))
    with _quiet_stdout():
        nodes, elems, attrib, _ = tg.tetrahedralize(switches="pq1.5/12YAaQ")
    region = (np.asarray(attrib).ravel().astype(int) % 10).astype(np.int8)
    tets = _orient(np.asarray(nodes, float), np.asarray(elems, np.int64))
    mesh = Mesh(np.asarray(nodes, float), tets, region, spec)
    return to_quadratic(mesh) if spec.order == 2 else mesh


def _orient(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Reorder tets so that every signed volume is positive."""
    p = points[tets[:, :4]]
    vol = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    tets = tets.copy()
    flip = vol < 0
    tets[flip, 1], tets[flip, 2] = tets[flip, 2], tets[flip, 1].copy()
    return tets


def to_quadratic(mesh: Mesh) -> Mesh:
    """Add edge midpoints: 10-node tetrahedra in VTK order."""
    tets = mesh.tets[:, :4]
    edges = np.sort(tets[:, TET_EDGES].reshape(-1, 2), axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    mid = 0.5 * (mesh.points[unique[:, 0]] + mesh.points[unique[:, 1]])
    n = len(mesh.points)
    quad = np.hstack([tets, n + inverse.reshape(-1, 6)])
    return Mesh(np.vstack([mesh.points, mid]), quad, mesh.region, mesh.spec)


def cache_dir() -> Path:
    root = os.environ.get("ROUGHNESS_CACHE") or Path.home() / ".cache" / "roughness"
    path = Path(root)
    path.mkdir(parents=True, exist_ok=True)
    return path


def build(spec: MeshSpec, cache: bool = True) -> Mesh:
    """The mesh for ``spec``, from the on-disk cache when present."""
    path = cache_dir() / f"mesh-{spec.key()}.npz" if cache else None
    if path is not None and path.exists():
        with np.load(path) as f:
            return Mesh(f["points"], f["tets"], f["region"], spec)
    mesh = tetrahedralize(spec)
    if path is not None:
        # a temporary file of its own per writer: workers meshing the same spec at once each publish
        # a whole file (identical content), and none renames another's temporary file away
        atomic_write(path, lambda tmp: np.savez(tmp, points=mesh.points, tets=mesh.tets, region=mesh.region))
    return mesh

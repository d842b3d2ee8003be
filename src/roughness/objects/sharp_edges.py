"""Sharp edges of a mesh, and the faces between them (a CAD part's faces).

An edge is sharp where the normals of its two faces turn by more than ``sharp_deg`` (the dihedral turn: 0 on a flat
face, 90 at a cube's edge). The default, DEFAULT_SHARP_DEG = 40 degrees, lies above the turn between neighbouring
facets of a tessellated smooth surface and below the edges a designer draws: CAD exporters' coarsest angular
tolerance is 30 degrees (SolidWorks' "coarse" STL; finer settings and Fusion's defaults are 10-15), so a fillet or a
cylinder turns by at most 30 degrees from facet to facet, while a 45-degree chamfer, the shallowest edge commonly
drawn, turns by 45.

A sharp edge is convex where the solid's outside angle there exceeds 180 degrees (a cube's edge) and concave where
the neighbouring face rises above the face's plane (a slot's floor meeting its wall).

Faces (``patches``): the triangles connected across edges that are not sharp, within a selection of triangles. A
patch's width is twice its area over its perimeter (mm): a strip's width, a disc's radius, half a square's side;
the walls and floors of engraved letters and of small holes are narrow patches.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DEFAULT_SHARP_DEG = 40.0
"""Edges whose faces' normals turn by more than this (degrees) are sharp (module docstring)."""


@dataclass(frozen=True)
class SharpEdges:
    """The sharp edges of a closed mesh: their ends (``ends``, (k, 2) vertex indices), the turn of the normals
    across each (``turn_deg``) and whether each is concave."""

    ends: np.ndarray
    turn_deg: np.ndarray
    concave: np.ndarray

    @property
    def count(self) -> int:
        return len(self.ends)

    def sharpest_concave_deg(self) -> float | None:
        """The largest turn (degrees) of a concave sharp edge, None if none is concave."""
        return float(self.turn_deg[self.concave].max()) if self.concave.any() else None


@dataclass(frozen=True)
class _Adjacency:
    """Each edge of a closed manifold mesh with its two faces: ``ends`` (k, 2), ``faces`` (k, 2), and the vertex
    of each face opposite the edge (``opposite``, (k, 2))."""

    ends: np.ndarray
    faces: np.ndarray
    opposite: np.ndarray


def _adjacency(faces: np.ndarray, n_vertices: int) -> _Adjacency:
    """Pairs of faces sharing an edge (every edge of a closed manifold mesh is shared by exactly two)."""
    a, b = faces.ravel(), np.roll(faces, -1, axis=1).ravel()
    key = np.minimum(a, b) * n_vertices + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    key = key[order]
    first = np.flatnonzero(key[:-1] == key[1:])
    one, two = order[first], order[first + 1]  # positions in the raveled (face, corner) list
    corner = np.arange(3)
    opposite = faces[:, (corner + 2) % 3].ravel()
    return _Adjacency(np.stack([a[one], b[one]], 1), np.stack([one // 3, two // 3], 1),
                      np.stack([opposite[one], opposite[two]], 1))


def _normals_and_areas(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (m, 3) and areas (m,) (mm^2) of the faces."""
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    return cross / np.maximum(2 * area, 1e-300)[:, None], area


def _turn_deg(normals: np.ndarray, adj: _Adjacency) -> np.ndarray:
    """The turn (degrees) of the normals across each edge."""
    cosine = np.einsum("ij,ij->i", normals[adj.faces[:, 0]], normals[adj.faces[:, 1]])
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


def sharp_edges(vertices: np.ndarray, faces: np.ndarray, sharp_deg: float = DEFAULT_SHARP_DEG) -> SharpEdges:
    """The edges of the mesh (``vertices`` mm, ``faces``) shared by two faces whose normals turn by more than
    ``sharp_deg`` degrees (module docstring); ``sharp_deg`` 180 finds none. Edges of a single face (the border of a
    selection of a closed mesh's faces) are not counted."""
    faces = np.asarray(faces, dtype=np.int64)
    adj = _adjacency(faces, len(vertices))
    normals, _ = _normals_and_areas(vertices, faces)
    turn = _turn_deg(normals, adj)
    sharp = turn > sharp_deg
    rise = np.einsum("ij,ij->i", normals[adj.faces[sharp, 0]],
                     vertices[adj.opposite[sharp, 1]] - vertices[adj.ends[sharp, 0]])
    return SharpEdges(adj.ends[sharp], turn[sharp], rise > 0)


@dataclass(frozen=True)
class Patches:
    """The selected faces split into patches at sharp edges and at the selection's border: ``label`` per face
    (-1 unselected), each patch's ``area_mm2`` and ``perimeter_mm``."""

    label: np.ndarray
    area_mm2: np.ndarray
    perimeter_mm: np.ndarray

    @property
    def width_mm(self) -> np.ndarray:
        """Twice each patch's area over its perimeter (mm; module docstring)."""
        return 2 * self.area_mm2 / np.maximum(self.perimeter_mm, 1e-300)


def patches(vertices: np.ndarray, faces: np.ndarray, selected: np.ndarray,
            sharp_deg: float = DEFAULT_SHARP_DEG) -> Patches:
    """The ``selected`` faces (bool per face) of a closed mesh joined across edges that are not sharp."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    faces = np.asarray(faces, dtype=np.int64)
    adj = _adjacency(faces, len(vertices))
    normals, area = _normals_and_areas(vertices, faces)
    smooth = _turn_deg(normals, adj) <= sharp_deg
    both = selected[adj.faces[:, 0]] & selected[adj.faces[:, 1]]
    joined = adj.faces[smooth & both]
    n = len(faces)
    graph = coo_matrix((np.ones(len(joined)), (joined[:, 0], joined[:, 1])), shape=(n, n))
    _, component = connected_components(graph, directed=False)
    ids = np.flatnonzero(selected)
    _, label_of_selected = np.unique(component[ids], return_inverse=True)
    label = np.full(n, -1, dtype=np.int64)
    label[ids] = label_of_selected
    count = int(label_of_selected.max()) + 1 if len(ids) else 0
    length = np.linalg.norm(vertices[adj.ends[:, 1]] - vertices[adj.ends[:, 0]], axis=1)
    border = ~(smooth & both) & (label[adj.faces[:, 0]] != label[adj.faces[:, 1]])
    perimeter = np.zeros(count)
    for side in (0, 1):
        f = adj.faces[border, side]
        inside = label[f] >= 0
        perimeter += np.bincount(label[f[inside]], weights=length[border][inside], minlength=count)
    return Patches(label, np.bincount(label[ids], weights=area[ids], minlength=count), perimeter)

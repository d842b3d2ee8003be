"""The contact face: its triangles, nodal areas, and contact pressure from nodal reactions.

With P2 elements a uniform pressure puts no consistent nodal force on triangle corners,
so contact decisions use the pressure p = M^-1 r recovered with the face mass matrix M;
with P1 the lumped p = r / area is used.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from .mesh import Mesh

# Tet faces as (corner, corner, corner, mid(0-1), mid(1-2), mid(0-2)) in VTK quadratic order.
_FACES = np.array([[0, 1, 2, 4, 5, 6], [0, 1, 3, 4, 8, 7], [0, 2, 3, 6, 9, 7], [1, 2, 3, 5, 9, 8]])
# Mass matrix of the 6-node triangle, times 180 / area; mids 3, 4, 5 lie on edges 01, 12, 02.
_P2_MASS = np.array([
    [6, -1, -1, 0, -4, 0], [-1, 6, -1, 0, 0, -4], [-1, -1, 6, -4, 0, 0],
    [0, 0, -4, 32, 16, 16], [-4, 0, 0, 16, 32, 16], [0, -4, 0, 16, 16, 32]]) / 180.0
_SUBTRIANGLES = np.array([[0, 3, 5], [1, 4, 3], [2, 5, 4], [3, 4, 5]])


def triangles(mesh: Mesh, z: float = 0.0) -> np.ndarray:
    """Faces (k, 3) or (k, 6) of the tets lying in the plane at height z."""
    cols = _FACES if mesh.order == 2 else _FACES[:, :3]
    faces = np.concatenate([mesh.tets[:, c] for c in cols])
    on = np.all(np.abs(mesh.points[faces[:, :3], 2] - z) < 1e-9, axis=1)
    return faces[on]


def _area(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = points[tri[:, :3]]
    return 0.5 * np.abs(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2])


class ContactFace:
    """Nodal areas (mm^2) and pressure recovery (MPa) on the contact-face nodes ``nodes``."""

    def __init__(self, mesh: Mesh, nodes: np.ndarray) -> None:
        tri = triangles(mesh)
        local = np.full(len(mesh.points), -1)
        local[nodes] = np.arange(len(nodes))
        tri = local[tri]
        area = _area(mesh.points[nodes], tri)
        linear = tri[:, _SUBTRIANGLES].reshape(-1, 3) if mesh.order == 2 else tri
        sub_area = np.repeat(area / 4, 4) if mesh.order == 2 else area
        self.area = np.bincount(linear.ravel(), np.repeat(sub_area / 3, 3), minlength=len(nodes))
        self._mass = None
        if mesh.order == 2:
            rows = np.repeat(tri, 6, axis=1).ravel()
            cols = np.tile(tri, (1, 6)).ravel()
            vals = (area[:, None, None] * _P2_MASS).ravel()
            self._mass = sla.splu(sp.csc_matrix((vals, (rows, cols)), shape=(len(nodes),) * 2))

    def pressure(self, reaction_z: np.ndarray) -> np.ndarray:
        """Contact pressure (MPa) from the nodal z reactions (N)."""
        if self._mass is None:
            return reaction_z / self.area
        return self._mass.solve(reaction_z)

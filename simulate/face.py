"""The contact face: its triangles, nodal areas, and the nodal contact pressure.

The contact conditions are imposed node by node (simulate/contact.py), so the nodal z
reactions r are their multipliers. With P1 the pressure is r / area (lumped nodal areas).
With P2 a uniform pressure p puts no consistent force on triangle corners (r = 0 there, and
r < 0 at the edge of a contact where p falls), so the pressure is judged in a modified quadratic
basis N'_corner = N_corner + ALPHA x (the mid-side functions of its edges), N'_mid = (1 - 2 ALPHA)
N_mid: a partition of unity whose functions all have positive integrals (the nodal areas).
p = T r / area is exact for a uniform pressure, has the sign of r at mid-side nodes, and judges
a corner together with its edges' mid-side nodes. Two alternatives measured worse
(studies/results/contact_partial.md): p = M^-1 r with the face mass matrix M oscillates in sign at
the edge of contact, so the contact set cycled; p = r / area releases corners inside the contact
(holes 4 um deep under a Hertz sphere).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .mesh import Mesh

# Tet faces as (corner, corner, corner, mid(0-1), mid(1-2), mid(0-2)) in VTK quadratic order.
_FACES = np.array([[0, 1, 2, 4, 5, 6], [0, 1, 3, 4, 8, 7], [0, 2, 3, 6, 9, 7], [1, 2, 3, 5, 9, 8]])
# Mids 3, 4, 5 of a 6-node triangle lie on edges 01, 12, 02: (corner, mid) pairs along the edges.
_EDGE_MIDS = np.array([[0, 3], [1, 3], [1, 4], [2, 4], [0, 5], [2, 5]])
ALPHA = 0.2  # weight of a mid-side function in its corners' modified basis functions


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
    """Nodal areas (mm^2) and nodal contact pressure (MPa) on the contact-face nodes ``nodes``."""

    def __init__(self, mesh: Mesh, nodes: np.ndarray) -> None:
        tri = triangles(mesh)
        local = np.full(len(mesh.points), -1)
        local[nodes] = np.arange(len(nodes))
        tri = local[tri]
        area = _area(mesh.points[nodes], tri)
        n = len(nodes)
        self._transform = None
        if mesh.order == 1:
            self.area = np.bincount(tri.ravel(), np.repeat(area / 3, 3), minlength=n)
            return
        mids = np.unique(tri[:, 3:])
        integral = np.bincount(tri[:, 3:].ravel(), np.repeat(area / 3, 3), minlength=n)  # corners integrate to 0
        pairs = np.unique(tri[:, _EDGE_MIDS].reshape(-1, 2), axis=0)  # each edge once
        diagonal = np.ones(n)
        diagonal[mids] = 1 - 2 * ALPHA
        self._transform = (sp.diags(diagonal) + sp.csr_matrix(
            (np.full(len(pairs), ALPHA), (pairs[:, 0], pairs[:, 1])), shape=(n, n))).tocsr()
        self.area = self._transform @ integral

    def pressure(self, reaction_z: np.ndarray) -> np.ndarray:
        """Nodal contact pressure (MPa) from the nodal z reactions (N); see the module docstring."""
        if self._transform is None:
            return reaction_z / self.area
        return (self._transform @ reaction_z) / self.area

"""Strain at receptor depth: recovery at mesh vertices and sampling on a regular grid."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .elasticity import strain_tensors, vertex_strain_operator
from .mesh import Mesh


def grid_axis(window_mm: float, grid_mm: float) -> np.ndarray:
    """Sample coordinates (mm) along one axis of the centred square window."""
    n = int(round(window_mm / grid_mm))
    return (np.arange(n + 1) - n / 2) * grid_mm


def locate(mesh: Mesh, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Containing P1 cell (first four nodes) and barycentric coordinates of each point."""
    corners = mesh.points[mesh.tets[:, :4]]
    tree = cKDTree(corners.mean(axis=1))
    d = np.concatenate([np.ones(corners.shape[:2] + (1,)), corners], axis=2)
    cells = np.full(len(points), -1)
    bary = np.zeros((len(points), 4))
    todo = np.arange(len(points))
    for k in (16, 64, 256):
        _, cand = tree.query(points[todo], k=k)
        inv = np.linalg.inv(d[cand])
        rhs = np.c_[np.ones(len(todo)), points[todo]]
        b = np.einsum("pkji,pj->pki", inv, rhs)
        inside = b.min(axis=2)
        best = inside.argmax(axis=1)
        rows = np.arange(len(todo))
        ok = inside[rows, best] >= -1e-9
        cells[todo[ok]] = cand[rows[ok], best[ok]]
        bary[todo[ok]] = b[rows[ok], best[ok]]
        todo = todo[~ok]
        if len(todo) == 0:
            return cells, np.clip(bary, 0.0, 1.0)
    raise RuntimeError(f"{len(todo)} strain sample points lie outside the mesh")


def patch_weights(vertex_xyz: np.ndarray, centroid: np.ndarray, vertex: np.ndarray, element: np.ndarray,
                  vol: np.ndarray, order: int) -> np.ndarray:
    """Weights of element strains in the recovered strain at a vertex, per (vertex, element) pair.

    P1: superconvergent patch recovery (least-squares linear fit of the constant element
    strains at the element centroids of the vertex's star, evaluated at the vertex).
    P2: volume-weighted average of the element strains evaluated at the vertex.
    """
    if order == 2:
        total = np.bincount(vertex, vol[element])
        return vol[element] / total[vertex]
    offset = centroid[element] - vertex_xyz[vertex]
    scale = np.sqrt(np.bincount(vertex, (offset**2).sum(axis=1)) / np.bincount(vertex))
    q = np.c_[np.ones(len(vertex)), offset / scale[vertex, None]]
    a = np.zeros((len(scale), 4, 4))
    np.add.at(a, vertex, q[:, :, None] * q[:, None, :])
    first_row = np.linalg.solve(a, np.broadcast_to(np.eye(4)[0], (len(scale), 4))[..., None])[..., 0]
    return np.einsum("pi,pi->p", first_row[vertex], q)


class StrainSampler:
    """Recovered small strain on the regular grid at a material depth of the block.

    Element strains are recovered at the mesh vertices (``patch_weights``), then
    interpolated linearly inside the cell that contains each grid point.
    """

    def __init__(self, mesh: Mesh, depth_mm: float, window_mm: float, grid_mm: float) -> None:
        axis = grid_axis(window_mm, grid_mm)
        gx, gy = np.meshgrid(axis, axis)
        pts = np.c_[gx.ravel(), gy.ravel(), np.full(gx.size, depth_mm)]
        cells, bary = locate(mesh, pts)
        corner = mesh.tets[:, :4]
        verts = np.unique(corner[cells])
        star = np.flatnonzero(np.isin(corner, verts).any(axis=1))
        g, dofs, vol = vertex_strain_operator(Mesh(mesh.points, mesh.tets[star], mesh.region[star], mesh.spec))
        self.g, self.dofs, self.shape = g, dofs, gx.shape
        local = np.full(len(mesh.points), -1)
        local[verts] = np.arange(len(verts))
        slot = np.arange(4 * len(star)).reshape(-1, 4)
        owner = local[corner[star]]
        use = owner >= 0
        element = np.broadcast_to(np.arange(len(star))[:, None], owner.shape)[use]
        centroid = mesh.points[corner[star]].mean(axis=1)
        w = patch_weights(mesh.points[verts], centroid, owner[use], element, vol, mesh.order)
        avg = sp.csr_matrix((w, (owner[use], slot[use])), shape=(len(verts), 4 * len(star)))
        interp = sp.csr_matrix(
            (bary.ravel(), (np.repeat(np.arange(len(pts)), 4), local[corner[cells]].ravel())),
            shape=(len(pts), len(verts)),
        )
        self.operator = (interp @ avg).tocsr()
        self.axis = axis

    def strain(self, u: np.ndarray) -> np.ndarray:
        """Strain tensors (ny, nx, 3, 3) on the grid for displacements u (3N,)."""
        eps = strain_tensors(self.g, self.dofs, u).reshape(-1, 9)
        return (self.operator @ eps).reshape(self.shape + (3, 3))

    def max_compression(self, u: np.ndarray) -> np.ndarray:
        """lambda3: the most negative principal strain (ny, nx)."""
        return np.linalg.eigvalsh(self.strain(u))[..., 0]

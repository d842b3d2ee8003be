"""Linear elasticity on P1/P2 tetrahedra: shape gradients, stiffness, strain.

Degrees of freedom are interleaved: dof = 3 * node + component (x, y, z).
Units: mm for lengths, MPa (N/mm^2) for moduli, so forces come out in N.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .mesh import Mesh

# Four-point rule on the reference tetrahedron, exact for quadratics (barycentric).
_A, _B = 0.5854101966249685, 0.1381966011250105
QUAD4 = np.array([[_A, _B, _B, _B], [_B, _A, _B, _B], [_B, _B, _A, _B], [_B, _B, _B, _A]])
_EDGES = np.array([[0, 1], [1, 2], [0, 2], [0, 3], [1, 3], [2, 3]])


def lame(young_mpa: np.ndarray, poisson: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lamé parameters (lambda, mu) in MPa."""
    lam = young_mpa * poisson / ((1 + poisson) * (1 - 2 * poisson))
    mu = young_mpa / (2 * (1 + poisson))
    return lam, mu


def barycentric_gradients(points: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gradients (m, 4, 3) of the barycentric coordinates and volumes (m,) in mm^3."""
    p = points[tets[:, :4]]
    d = np.concatenate([np.ones((len(tets), 4, 1)), p], axis=2)
    inv = np.linalg.inv(d)
    vol = np.abs(np.linalg.det(d)) / 6.0
    return np.transpose(inv[:, 1:, :], (0, 2, 1)), vol


def shape_gradients(grad_bary: np.ndarray, bary: np.ndarray, order: int) -> np.ndarray:
    """Gradients (m, n, 3) of the P1 or P2 shape functions at barycentric point ``bary``."""
    if order == 1:
        return grad_bary
    vert = (4 * bary - 1)[None, :, None] * grad_bary
    i, j = _EDGES[:, 0], _EDGES[:, 1]
    edge = 4 * (bary[i][None, :, None] * grad_bary[:, j] + bary[j][None, :, None] * grad_bary[:, i])
    return np.concatenate([vert, edge], axis=1)


def quadrature(order: int) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric points and weights (fractions of the volume) for the stiffness."""
    if order == 1:
        return np.full((1, 4), 0.25), np.ones(1)
    return QUAD4, np.full(4, 0.25)


def stiffness(mesh: Mesh, young_mpa: np.ndarray, poisson: np.ndarray) -> sp.csr_matrix:
    """Global stiffness matrix (N/mm) for per-element moduli."""
    grad_bary, vol = barycentric_gradients(mesh.points, mesh.tets)
    lam, mu = lame(np.asarray(young_mpa, float), np.asarray(poisson, float))
    nn = mesh.tets.shape[1]
    ke = np.zeros((len(vol), nn, 3, nn, 3))
    points, weights = quadrature(mesh.order)
    for bary, w in zip(points, weights):
        g = shape_gradients(grad_bary, bary, mesh.order)
        wv = w * vol
        ke += np.einsum("e,eia,ejb->eiajb", wv * lam, g, g)
        ke += np.einsum("e,eib,eja->eiajb", wv * mu, g, g)
        gg = np.einsum("e,eic,ejc->eij", wv * mu, g, g)
        ke += gg[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
    dofs = (3 * mesh.tets[:, :, None] + np.arange(3)).reshape(len(vol), -1)
    rows = np.repeat(dofs, 3 * nn, axis=1).ravel()
    cols = np.tile(dofs, (1, 3 * nn)).ravel()
    n = 3 * len(mesh.points)
    return sp.csr_matrix((ke.ravel(), (rows, cols)), shape=(n, n))


def vertex_strain_operator(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shape-function gradients at each element's four vertices.

    Returns gradients (m, 4, n, 3) (the same for all four vertices in P1), element dofs
    (m, 3n) and volumes (m,) for strain recovery at the mesh vertices.
    """
    grad_bary, vol = barycentric_gradients(mesh.points, mesh.tets)
    g = np.stack([shape_gradients(grad_bary, np.eye(4)[k], mesh.order) for k in range(4)], axis=1)
    dofs = (3 * mesh.tets[:, :, None] + np.arange(3)).reshape(len(mesh.tets), -1)
    return g, dofs, vol


def strain_tensors(g: np.ndarray, dofs: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Small-strain tensors (..., 3, 3) from gradients (m, ..., n, 3) and displacements (3N,)."""
    ue = u[dofs].reshape(len(dofs), -1, 3)
    grad = np.einsum("mia,m...ib->m...ab", ue, g)
    return 0.5 * (grad + np.swapaxes(grad, -1, -2))


def rigid_body_modes(points: np.ndarray) -> np.ndarray:
    """The six rigid-body modes (3N, 6) used as AMG near-null space."""
    n = len(points)
    b = np.zeros((3 * n, 6))
    x, y, z = (points - points.mean(axis=0)).T
    for a in range(3):
        b[a::3, a] = 1.0
    b[0::3, 3], b[1::3, 3] = -y, x
    b[1::3, 4], b[2::3, 4] = -z, y
    b[0::3, 5], b[2::3, 5] = z, -x
    return b

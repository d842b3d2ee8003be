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
# Node-pair blocks per assembly chunk (16 per P1 element, 100 per P2): bounds each element-matrix
# array to about 230 MB however fine the mesh.
CHUNK_BLOCKS = 3_200_000
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


def stiffness(mesh: Mesh, young_mpa: np.ndarray, poisson: np.ndarray,
              chunk: int = CHUNK_BLOCKS) -> sp.csr_matrix:
    """Global stiffness matrix (N/mm) for per-element moduli, assembled about ``chunk`` node-pair blocks at a time."""
    grad_bary, vol = barycentric_gradients(mesh.points, mesh.tets)
    lam, mu = lame(np.asarray(young_mpa, float), np.asarray(poisson, float))
    lam, mu = np.broadcast_to(lam, vol.shape), np.broadcast_to(mu, vol.shape)
    total = None
    step = max(1, chunk // mesh.tets.shape[1] ** 2)
    for start in range(0, len(vol), step):
        part = slice(start, start + step)
        blocks = element_blocks(grad_bary[part], vol[part], lam[part], mu[part], mesh.order)
        matrix = assemble_blocks(blocks, mesh.tets[part], len(mesh.points))
        total = matrix if total is None else total + matrix
    return total.tocsr()


def element_blocks(grad_bary: np.ndarray, vol: np.ndarray, lam: np.ndarray, mu: np.ndarray,
                   order: int) -> np.ndarray:
    """Element stiffness matrices as 3x3 blocks (m, n, n, 3, 3): block (a, b) couples nodes i and j."""
    nn = 4 if order == 1 else 10
    blocks = np.zeros((len(vol), nn, nn, 3, 3))
    diagonal = np.arange(3)
    points, weights = quadrature(order)
    for bary, w in zip(points, weights):
        g = shape_gradients(grad_bary, bary, order)
        wv = w * vol
        outer = g[:, :, None, :, None] * g[:, None, :, None, :]  # g_ia g_jb
        blocks += (wv * lam)[:, None, None, None, None] * outer
        outer *= (wv * mu)[:, None, None, None, None]
        blocks += outer.swapaxes(3, 4)  # mu g_ib g_ja
        blocks[:, :, :, diagonal, diagonal] += ((wv * mu)[:, None, None] * (g @ g.transpose(0, 2, 1)))[..., None]
    return blocks


def assemble_blocks(blocks: np.ndarray, cells: np.ndarray, n_nodes: int) -> sp.bsr_matrix:
    """Sum element matrices given as 3x3 node blocks (m, n, n, 3, 3) into a global 3x3-block matrix.

    Entries are summed per node pair (nine times fewer than per DOF) after one sort of the
    pair keys, packed with their position into one int64 when it fits (a plain sort is
    faster than an argsort).
    """
    keys = (cells[:, :, None].astype(np.int64) * n_nodes + cells[:, None, :]).ravel()
    shift = max(1, int(len(keys) - 1).bit_length())
    if int(keys.max()).bit_length() + shift <= 63:
        packed = np.sort((keys << shift) | np.arange(len(keys)))
        order, keys = packed & ((1 << shift) - 1), packed >> shift
    else:
        order = np.argsort(keys)
        keys = keys[order]
    starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    summed = np.add.reduceat(blocks.reshape(-1, 9)[order], starts, axis=0)
    rows, cols = np.divmod(keys[starts], n_nodes)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n_nodes))])
    return sp.bsr_matrix((summed.reshape(-1, 3, 3), cols, indptr), shape=(3 * n_nodes, 3 * n_nodes))


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

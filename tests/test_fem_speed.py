"""The fast paths of the FEM agree with their plain formulations: assembly, constraints, float32 V-cycle."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from conftest import SMALL_MESH as SMALL
from roughness.simulate.elasticity import (
    barycentric_gradients,
    lame,
    quadrature,
    rigid_body_modes,
    shape_gradients,
    stiffness,
)
from roughness.simulate.linsolve import AMGCache, _Layout, constrain
from roughness.simulate.mesh import build


def _voigt_stiffness(mesh, young: np.ndarray, poisson: np.ndarray) -> sp.csr_matrix:
    """K = sum_e sum_q w_q vol_e B^T D B, summed entry by entry (the textbook form)."""
    grad_bary, vol = barycentric_gradients(mesh.points, mesh.tets)
    lam, mu = lame(young, poisson)
    d = np.zeros((len(vol), 6, 6))
    d[:, :3, :3] = lam[:, None, None]
    d[:, np.arange(3), np.arange(3)] += 2 * mu[:, None]
    d[:, np.arange(3, 6), np.arange(3, 6)] = mu[:, None]
    nn = mesh.tets.shape[1]
    ke = np.zeros((len(vol), 3 * nn, 3 * nn))
    for bary, w in zip(*quadrature(mesh.order)):
        g = shape_gradients(grad_bary, bary, mesh.order)
        b = np.zeros((len(vol), 6, nn, 3))
        for a in range(3):
            b[:, a, :, a] = g[:, :, a]
        for row, (a, c) in zip(range(3, 6), ((1, 2), (0, 2), (0, 1))):  # engineering shear strains
            b[:, row, :, a] = g[:, :, c]
            b[:, row, :, c] = g[:, :, a]
        b = b.reshape(len(vol), 6, 3 * nn)
        ke += (w * vol)[:, None, None] * np.einsum("eki,ekl,elj->eij", b, d, b)
    dofs = (3 * mesh.tets[:, :, None] + np.arange(3)).reshape(len(vol), -1)
    rows = np.repeat(dofs, 3 * nn, axis=1).ravel()
    cols = np.tile(dofs, (1, 3 * nn)).ravel()
    n = 3 * len(mesh.points)
    return sp.coo_matrix((ke.ravel(), (rows, cols)), shape=(n, n)).tocsr()


def test_block_assembly_equals_the_textbook_sum(mesh):
    rng = np.random.default_rng(0)
    young = rng.uniform(0.01, 0.1, len(mesh.tets))
    poisson = rng.uniform(0.2, 0.45, len(mesh.tets))
    reference = _voigt_stiffness(mesh, young, poisson)
    for chunk in (10**9, 4000):  # in one piece, and in chunks of a few hundred elements
        k = stiffness(mesh, young, poisson, chunk=chunk)
        assert k.shape == reference.shape and k.nnz == reference.nnz  # the same pattern: every node pair's 3x3 block
        assert abs(k - reference).max() < 1e-12 * abs(reference).max()  # round-off of summing ~30 terms


@pytest.fixture(scope="module")
def small():
    m = build(SMALL)
    k = stiffness(m, np.full(len(m.tets), 0.042), np.full(len(m.tets), 0.45))
    fixed = np.zeros(k.shape[0], dtype=bool)
    fixed[3 * m.top[:, None] + np.arange(3)] = True
    fixed[3 * m.bottom[::2, None] + np.arange(3)] = True  # every other contact node held
    values = np.zeros(k.shape[0])
    values[3 * m.top + 2] = -0.02
    values[3 * m.bottom + 2] = 0.01 * np.sin(m.points[m.bottom, 0])
    return m, k, fixed, values


def test_constrained_matrix_is_the_projection_and_leaves_the_stiffness_alone(small):
    m, k, fixed, _ = small
    before = (k.data.copy(), k.indices.copy(), k.indptr.copy())
    system = constrain(k, fixed, AMGCache(rigid_body_modes(m.points)))
    keep = sp.diags((~fixed).astype(float))
    projection = (keep @ k @ keep + sp.diags(np.where(fixed, k.diagonal(), 0.0))).tocsr()
    assert abs(system.matrix - projection).max() == 0.0
    stored = system.matrix.tocoo()
    coupled = (fixed[stored.row] | fixed[stored.col]) & (stored.row != stored.col)
    assert np.all(stored.data[coupled] == 0)  # prescribed rows and columns: zeros off the diagonal
    assert all(np.array_equal(a, b) for a, b in zip(before, (k.data, k.indices, k.indptr)))


def test_constrained_matrices_updated_round_by_round_equal_fresh_projections(small):
    """A few nodes change state per contact round: each new matrix is the last one updated in their rows
    and columns, and must equal the projection built from scratch; earlier systems keep their matrix."""
    m, k, fixed, _ = small
    amg = AMGCache(rigid_body_modes(m.points))
    rng = np.random.default_rng(3)
    systems, sets = [], []
    current = fixed.copy()
    for changes in (0, 3, 1, 12, len(m.bottom) // 2):  # the last beyond UPDATE_LIMIT: masked afresh
        flip = rng.choice(m.bottom, changes, replace=False)
        current = current.copy()
        current[3 * flip[:, None] + np.arange(3)] ^= True
        systems.append(constrain(k, current, amg))
        sets.append(current)
    assert 3 * (len(m.bottom) // 2) > _Layout.UPDATE_LIMIT * k.shape[0] > 3 * 12
    for system, held in zip(systems, sets):
        keep = sp.diags((~held).astype(float))
        projection = (keep @ k @ keep + sp.diags(np.where(held, k.diagonal(), 0.0))).tocsr()
        assert abs(system.matrix - projection).max() == 0.0


def test_float32_v_cycle_converges_like_float64_to_the_same_solution(small):
    """Both stop on the float64 residual, so both lie within |r| / lambda_min(A) of the exact solution."""
    m, k, fixed, values = small
    solutions = {}
    for precision in (np.float32, np.float64):
        system = constrain(k, fixed, AMGCache(rigid_body_modes(m.points), precision=precision), rtol=1e-8)
        solutions[precision] = system.solve(values)
    exact = np.where(fixed, values, 0.0)
    b = np.where(fixed, system.diag * exact, -(k @ exact))
    exact = sla.spsolve(system.matrix.tocsc(), b)
    lam_min = sla.eigsh(system.matrix, k=1, sigma=0, which="LM", return_eigenvectors=False)[0]
    for sol in solutions.values():
        assert sol.residual <= 1e-8
        assert np.linalg.norm(sol.u - exact) <= sol.residual * np.linalg.norm(b) / lam_min
    assert solutions[np.float32].iterations <= solutions[np.float64].iterations + 2

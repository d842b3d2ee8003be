"""Exact properties of the mesh, the elasticity operators and the variation measure."""
from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from conftest import SMALL_MESH as SMALL
from roughness.simulate.elasticity import (
    rigid_body_modes,
    stiffness,
    strain_tensors,
    vertex_strain_operator,
)
from roughness.simulate.mesh import build, surface
from roughness.simulate.strain import StrainSampler
from roughness.simulate.variation import PairSampling, variation


def test_mesh_is_graded_with_structured_contact_face():
    m = build(SMALL)
    bottom = m.points[m.bottom]
    n_side = int(round(SMALL.width_mm / SMALL.h_contact_mm)) + 1
    assert len(bottom) == n_side**2
    assert len(m.top) < len(bottom)
    p = m.points[m.tets]
    vol = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]) / 6
    assert vol.min() > 0
    assert np.isclose(vol.sum(), SMALL.width_mm**2 * SMALL.tissue_mm)
    low = m.points[m.tets].mean(axis=1)[:, 2] < 0.5
    assert vol[low].mean() < vol[~low].mean()


def test_surface_is_closed():
    _, tris, _ = surface(SMALL)
    edges = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [0, 2]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert counts.min() >= 2  # every edge shared (internal facets make some 3- or 4-fold)


def test_mesh_cache_returns_identical_mesh():
    a, b = build(SMALL), build(SMALL)
    assert np.array_equal(a.points, b.points) and np.array_equal(a.tets, b.tets)


def test_two_workers_caching_the_same_mesh_at_once_both_succeed(tmp_path, monkeypatch):
    """Dataset workers mesh the same block together: each writes its own temporary file, and
    both have written before either publishes (a barrier), the interleaving that once failed one
    of them with FileNotFoundError (they shared one temporary name)."""
    monkeypatch.setenv("ROUGHNESS_CACHE", str(tmp_path))
    both_written = threading.Barrier(2, timeout=60)
    savez = np.savez

    def savez_then_wait(*args, **kwargs):
        savez(*args, **kwargs)
        both_written.wait()

    monkeypatch.setattr(np, "savez", savez_then_wait)
    with ThreadPoolExecutor(2) as pool:
        meshes = list(pool.map(lambda _: build(SMALL), range(2)))
    assert np.array_equal(meshes[0].tets, meshes[1].tets)
    assert [p.name for p in tmp_path.iterdir()] == [f"mesh-{SMALL.key()}.npz"]  # no temporary file left


def test_rigid_body_modes_are_in_the_stiffness_null_space(mesh):
    k = stiffness(mesh, np.full(len(mesh.tets), 0.042), np.full(len(mesh.tets), 0.45))
    b = rigid_body_modes(mesh.points)
    assert abs(k - k.T).max() < 1e-12 * abs(k).max()
    assert np.abs(k @ b).max() < 1e-9 * abs(k).max() * np.abs(b).max()


def test_affine_displacement_gives_exact_constant_strain(mesh):
    grad = np.array([[0.01, 0.02, -0.03], [0.0, -0.02, 0.01], [0.04, 0.0, -0.05]])
    u = (mesh.points @ grad.T).ravel()
    g, dofs, _ = vertex_strain_operator(mesh)
    eps = strain_tensors(g, dofs, u)
    assert np.allclose(eps, 0.5 * (grad + grad.T), atol=1e-12)
    sampler = StrainSampler(mesh, 0.75, 2.0, 0.25)
    assert np.allclose(sampler.strain(u), 0.5 * (grad + grad.T), atol=1e-10)


def test_recovery_of_a_linear_strain_field(mesh):
    """Exact for P2 (quadratic u is in the space); within a few % of the value for P1."""
    m = mesh
    x, y, z = m.points.T
    u = np.c_[0.01 * x * z, 0.02 * y * x, 0.005 * z**2].ravel()  # strain linear in x, y, z
    sampler = StrainSampler(m, 0.75, 2.0, 0.25)
    a = sampler.axis
    gx, gy = np.meshgrid(a, a)
    exact_zz = 0.01 * 0.75 * np.ones_like(gx)
    exact_xy = 0.5 * 0.02 * gy
    eps = sampler.strain(u)
    tol = 1e-10 if m.order == 2 else 0.05 * 0.0075
    assert np.abs(eps[..., 2, 2] - exact_zz).max() < tol
    assert np.abs(eps[..., 0, 1] - exact_xy).max() < tol


def test_uniaxial_compression_matches_hookes_law():
    """The affine answer lies in the FE space, so the discrete solution is Hooke's law exactly; what
    remains is CG's error, bounded from the residual: |u - u*| <= |r| / lambda_min(A)."""
    from scipy.sparse.linalg import eigsh

    from roughness.simulate.linsolve import AMGCache, constrain

    m = build(SMALL)
    e, nu, strain = 0.042, 0.45, 0.02 / SMALL.tissue_mm
    k = stiffness(m, np.full(len(m.tets), e), np.full(len(m.tets), nu))
    fixed = np.zeros(k.shape[0], dtype=bool)
    fixed[3 * m.bottom + 2] = fixed[3 * m.top + 2] = True
    corner = m.bottom[np.argmin(np.abs(m.points[m.bottom, :2]).sum(axis=1))]
    fixed[3 * corner] = fixed[3 * corner + 1] = True
    x_axis = m.bottom[np.argmin(np.abs(m.points[m.bottom, 1]) + np.abs(m.points[m.bottom, 0] - 2.0))]
    fixed[3 * x_axis + 1] = True
    system = constrain(k, fixed, AMGCache(rigid_body_modes(m.points)), rtol=1e-10)
    values = np.zeros(k.shape[0])
    values[3 * m.top + 2] = -0.02
    sol = system.solve(values)
    assert sol.residual <= 1e-10
    residual = np.where(fixed, system.diag * (sol.u - values), sol.reaction)  # A (u - u*), from public quantities
    lam_min = eigsh(system.matrix, k=1, sigma=0, which="LM", return_eigenvectors=False)[0]
    error = np.linalg.norm(residual) / lam_min  # bound on |u - u*|
    top_z = np.zeros(k.shape[0])
    top_z[3 * m.top + 2] = 1.0
    force_error = np.linalg.norm(k @ top_z) * error  # |c.K(u - u*)| <= |K c| |u - u*|
    expected = e * strain * SMALL.width_mm**2
    assert force_error < 1e-4 * expected  # the bound is sharp enough to test the physics
    assert abs(sol.reaction @ top_z + expected) <= force_error
    lateral = sol.u.reshape(-1, 3)[:, 0] / m.points[:, 0].clip(1e-9)
    assert error < 1e-4 * nu * strain
    assert abs(np.median(lateral[m.points[:, 0] > 1]) - nu * strain) <= error  # |du_x / x| <= |e| for x > 1


def test_variation_of_constant_and_linear_fields():
    s = PairSampling(window_mm=8.0, distance_mm=0.8, radius_mm=0.8, pairs=8000, seed=3)
    axis = np.linspace(-4, 4, 161)
    assert variation(np.full((161, 161), 0.3), axis, s) == pytest.approx((0.0, 0.0), abs=1e-15)
    gx, _ = np.meshgrid(axis, axis)
    v, se = variation(2.0 * gx, axis, s)
    # E|x1 - x2| for the disk-pair construction, by direct Monte Carlo on the same points
    p1, p2 = s.points()
    assert v == pytest.approx(2.0 * np.abs(p1[:, 0] - p2[:, 0]).mean(), rel=1e-9)
    assert 0 < se < 0.05 * v
    assert variation(2.0 * gx, axis, s) == (v, se)
    assert variation(2.0 * gx, axis, PairSampling(seed=4))[0] != v


def test_pair_points_stay_in_window_with_the_stated_geometry():
    p1, p2 = PairSampling(pairs=20000, seed=1).points()
    assert np.abs(np.r_[p1, p2]).max() <= 4.0
    dist = np.linalg.norm(p1 - p2, axis=1)
    assert dist.max() <= 0.8 + 2 * 0.8
    assert 0.95 < dist.mean() < 1.3  # 0.72 if the centres were not 0.8 mm apart


def test_prescribed_values_hold_exactly_after_a_solve(mesh):
    """CG meets prescribed DOFs only to its tolerance (the preconditioner couples them to free ones); the
    solve returns them exactly, as a texture wall amplifies a lateral error of 1e-5 mm into a height
    mismatch beyond the contact's gap tolerance."""
    from roughness.simulate.linsolve import AMGCache, constrain

    k = stiffness(mesh, np.full(len(mesh.tets), 0.042), np.full(len(mesh.tets), 0.45))
    fixed = np.zeros(k.shape[0], dtype=bool)
    fixed[3 * mesh.top[:, None] + np.arange(3)] = True
    fixed[3 * mesh.bottom[:, None] + np.arange(3)] = True
    values = np.random.default_rng(0).uniform(-0.5, 0.5, k.shape[0])
    sol = constrain(k, fixed, AMGCache(rigid_body_modes(mesh.points))).solve(values)
    assert np.array_equal(sol.u[fixed], values[fixed])
    np.testing.assert_allclose(sol.reaction, k @ sol.u)  # no load: the reaction is K u of the returned u


def test_plate_solve_equals_two_held_solves_combined(mesh):
    """solve_plate (the bone as a force-controlled rigid plate, one solve) against the former scheme: a
    solve with the bone held, one with a unit bone displacement, combined so the plate carries the
    force. Both are solved to a relative residual of 1e-12; the small block's condition number (below
    1e5 with the bone and contact held) bounds their difference by 1e-7 of the displacements."""
    from roughness.simulate.linsolve import AMGCache, constrain

    k = stiffness(mesh, np.full(len(mesh.tets), 0.042), np.full(len(mesh.tets), 0.45))
    rng = np.random.default_rng(1)
    touching = mesh.bottom[rng.random(len(mesh.bottom)) < 0.6]
    fixed = np.zeros(k.shape[0], dtype=bool)
    fixed[3 * mesh.top[:, None] + np.arange(3)] = True
    fixed[3 * touching[:, None] + np.arange(3)] = True
    values = np.zeros(k.shape[0])
    values[3 * touching + 2] = rng.uniform(-0.1, 0.0, len(touching))
    unit = np.zeros(k.shape[0])
    unit[3 * mesh.top + 2] = -1.0
    force = 0.5
    system = constrain(k, fixed, AMGCache(rigid_body_modes(mesh.points)), rtol=1e-12)
    held, bone = system.solve(values), system.solve(unit)
    delta = (force - unit @ held.reaction) / (unit @ bone.reaction)
    combined = held.u + delta * bone.u
    for plate in (unit, bone.u):  # the plate's motion alone, or extended into the block by its response
        sol = system.solve_plate(values, plate, force)
        assert sol.plate_mm == pytest.approx(delta, rel=1e-7)
        assert np.abs(sol.u - combined).max() <= 1e-7 * np.abs(combined).max()
        assert unit @ sol.reaction == pytest.approx(force, rel=1e-7)  # the plate carries the force
        np.testing.assert_array_equal(sol.u[fixed], values[fixed] + sol.plate_mm * unit[fixed])  # held exactly

"""Principal curvatures of a base mesh at the skin footprint's scale, not the triangles'.

The surface is sampled densely (``SurfaceSamples``: points with their faces' normals). At a point, the
shape operator S (2 x 2, symmetric, in the tangent plane) is fitted by least squares to the change of the
normal over the neighbourhood within ``radius_mm`` (the footprint's half side, 5 mm): the tangential part of
n_i - n_0 ≈ S (p_i - p_0)_t. On a sphere, a cylinder and a plane this relation holds exactly
(n = (p - c) / R, and its projection off the axis), so the fit returns their curvatures exactly however
large the neighbourhood; on other shapes it averages the curvature over the footprint, as the skin does.
Signs: convex positive (a sphere seen from outside: +1/R), concave negative. Directions: d1 (of k1) on the
side of the fixed tangent t1 (``tangent_frame``), d2 = normal x d1, so that (d1, d2, normal) is right-handed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError
from roughness.core.limits import MAX_MAP_POSITIONS, check_size
from roughness.curvature_correction import FOOTPRINT_MM

FOOTPRINT_RADIUS_MM = FOOTPRINT_MM / 2  # the neighbourhood the curvature is fitted over (mm)
SAMPLE_SPACING_MM = 0.4  # mean distance between surface samples: ~500 within a 5 mm neighbourhood
MIN_NEIGHBOURS = 12
UMBILIC_PER_MM = 1e-4  # principal curvatures closer than this: no principal direction, the fixed frame's


@dataclass(frozen=True)
class SurfaceSamples:
    """Points on a mesh's surface (n, 3; mm), their unit normals (faces'), faces, and a KD-tree of the points."""

    points: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    tree: object  # scipy.spatial.cKDTree
    spacing_mm: float

    @classmethod
    def of(cls, mesh, spacing_mm: float = SAMPLE_SPACING_MM, seed: int = 0) -> SurfaceSamples:
        """About area / spacing^2 points spread over ``mesh`` (a trimesh.Trimesh), reproducibly."""
        from scipy.spatial import cKDTree

        count = int(np.ceil(mesh.area / spacing_mm**2))
        check_size(f"surface samples of a {mesh.area:.4g} mm^2 mesh at {spacing_mm:g} mm", count, MAX_MAP_POSITIONS,
                   "mesh")
        rng = np.random.default_rng(seed)
        areas = mesh.area_faces
        faces = rng.choice(len(areas), size=count, p=areas / areas.sum())
        r = rng.random((count, 2))
        flip = r.sum(axis=1) > 1
        r[flip] = 1 - r[flip]
        tri = mesh.triangles[faces]
        points = tri[:, 0] + r[:, :1] * (tri[:, 1] - tri[:, 0]) + r[:, 1:] * (tri[:, 2] - tri[:, 0])
        return cls(points, mesh.face_normals[faces], faces, cKDTree(points), spacing_mm)


@dataclass(frozen=True)
class Curvature:
    """Principal curvatures at points (1/mm, convex positive; k1 >= k2), their directions, normals, fit quality."""

    points: np.ndarray  # (n, 3) mm
    normals: np.ndarray  # (n, 3) unit, outward
    k1: np.ndarray  # (n,)
    k2: np.ndarray  # (n,)
    d1: np.ndarray  # (n, 3) unit tangent direction of k1
    d2: np.ndarray  # (n, 3) unit tangent direction of k2
    residual: np.ndarray  # (n,) rms misfit of the normal change (dimensionless): large across edges and corners
    neighbours: np.ndarray  # (n,) samples used


def tangent_frame(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents (t1, t2) with (t1, t2, normal) right-handed, fixed by the axes: on faces facing up or
    down t1 is x projected on the tangent plane, elsewhere the horizontal z x normal (around a vertical axis)."""
    if abs(normal[2]) > 0.9:
        t1 = np.array([1.0, 0, 0]) - normal[0] * normal
    else:
        t1 = np.cross([0, 0, 1.0], normal)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(normal, t1)


def principal_curvatures(samples: SurfaceSamples, points: np.ndarray, normals: np.ndarray,
                         radius_mm: float = FOOTPRINT_RADIUS_MM) -> Curvature:
    """Principal curvatures at ``points`` (n, 3) with unit outward ``normals`` (n, 3), fitted over the samples
    within ``radius_mm`` whose normals face the same side (module docstring)."""
    points, normals = np.atleast_2d(np.asarray(points, float)), np.atleast_2d(np.asarray(normals, float))
    n = len(points)
    k1, k2 = np.zeros(n), np.zeros(n)
    d1, d2 = np.zeros((n, 3)), np.zeros((n, 3))
    residual, used = np.zeros(n), np.zeros(n, dtype=int)
    for i, (p0, n0) in enumerate(zip(points, normals)):
        near = np.asarray(samples.tree.query_ball_point(p0, radius_mm), dtype=int)
        near = near[samples.normals[near] @ n0 > 0]  # not the far side of a thin wall
        used[i] = len(near)
        if len(near) < MIN_NEIGHBOURS:
            raise InputError(f"only {len(near)} surface samples within {radius_mm:g} mm of ({p0[0]:.3g}, {p0[1]:.3g}, "
                             f"{p0[2]:.3g}): the mesh is too small there to fit a curvature", parameter="mesh")
        t1, t2 = tangent_frame(n0)
        frame = np.stack([t1, t2])
        dp = (samples.points[near] - p0) @ frame.T  # (m, 2) tangent offsets
        dn = (samples.normals[near] - n0) @ frame.T  # (m, 2) tangent change of the normal
        # unknowns (s11, s12, s22): dn_x = s11 dp_x + s12 dp_y, dn_y = s12 dp_x + s22 dp_y
        zero = np.zeros(len(near))
        a = np.concatenate([np.stack([dp[:, 0], dp[:, 1], zero], 1), np.stack([zero, dp[:, 0], dp[:, 1]], 1)])
        b = np.concatenate([dn[:, 0], dn[:, 1]])
        s, *_ = np.linalg.lstsq(a, b, rcond=None)
        residual[i] = float(np.sqrt(np.mean((a @ s - b) ** 2)))
        values, vectors = np.linalg.eigh(np.array([[s[0], s[1]], [s[1], s[2]]]))
        k2[i], k1[i] = values  # eigh sorts ascending
        first = vectors[:, 1] if values[1] - values[0] > UMBILIC_PER_MM else np.array([1.0, 0])
        first = first if first[0] > 0 or (first[0] == 0 and first[1] > 0) else -first  # along t1's side
        d1[i] = first @ frame
        d2[i] = np.cross(n0, d1[i])  # right-handed: the unrolled texture is turned, never mirrored
    return Curvature(points, normals, k1, k2, d1, d2, residual, used)

"""The axis and radius a wrap is laid around, fitted to the textured faces of a mesh."""
from __future__ import annotations

import numpy as np

from roughness.core.errors import InputError

from .mapping import Axis, axis_of
from .normals import face_normals


def principal_axis(vertices: np.ndarray, faces: np.ndarray) -> Axis:
    """The surface's axis of symmetry: through its area-weighted centroid, along the principal direction of its
    second moments whose moment stands furthest from the other two (a cylinder's axis, long or flat)."""
    centre, weights, centroids = _surface(vertices, faces)
    r = centroids - centre
    moments = (r * weights[:, None]).T @ r / weights.sum()
    values, vectors = np.linalg.eigh(moments)
    gaps = [min(abs(values[k] - values[j]) for j in range(3) if j != k) for k in range(3)]
    return axis_of(centre, vectors[:, int(np.argmax(gaps))])


def centroid(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted centroid (mm) of the surface."""
    return _surface(vertices, faces)[0]


def wrap_radius(vertices: np.ndarray, faces: np.ndarray, axis: Axis, kind: str) -> float:
    """The radius (mm) to fit whole tiles around: a cylinder's, the area-weighted median distance from the axis of
    the faces that face away from it (the side; all faces if none does); a sphere's, the area-weighted median
    distance of the faces from ``axis.point``."""
    origin, _, _, a = axis.frame()
    _, weights, centroids = _surface(vertices, faces)
    r = centroids - origin
    if kind == "cylinder":
        side = np.abs(face_normals(vertices, faces) @ a) < np.sqrt(0.5)
        if side.any():
            r, weights = r[side], weights[side]
        distance = np.linalg.norm(r - np.outer(r @ a, a), axis=1)
    else:
        distance = np.linalg.norm(r, axis=1)
    order = np.argsort(distance)
    cumulative = np.cumsum(weights[order])
    radius = float(distance[order][np.searchsorted(cumulative, cumulative[-1] / 2)])
    if not radius > 0:
        raise InputError("the textured faces lie on the axis: no radius to wrap the texture around", parameter="axis")
    return radius


def _surface(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    tri = vertices[faces]
    weights = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    centroids = tri.mean(axis=1)
    return (centroids * weights[:, None]).sum(axis=0) / weights.sum(), weights, centroids

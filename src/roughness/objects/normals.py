"""Vertex normals of a mesh: area-weighted, optionally smoothed over a radius."""
from __future__ import annotations

import math

import numpy as np

from roughness.core.limits import Limit, check_size

CHUNK_FACES = 500_000
MAX_SMOOTHING_WORK = Limit(4_000_000_000, "MAX_SMOOTHING_WORK")
"""Rounds x edges of normal smoothing (about a minute of sparse products)."""


def face_normals(vertices: np.ndarray, faces: np.ndarray, unit: bool = True) -> np.ndarray:
    """(m, 3) face normals (right-hand rule); ``unit=False``: their length is twice the face's area (mm^2)."""
    tri = vertices[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    if unit:
        length = np.linalg.norm(n, axis=1, keepdims=True)
        n /= np.where(length > 0, length, 1.0)
    return n


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(n, 3) unit vertex normals: the area-weighted mean of the normals of the faces around each vertex."""
    total = np.zeros((len(vertices), 3))
    for start in range(0, len(faces), CHUNK_FACES):
        f = faces[start:start + CHUNK_FACES]
        n = face_normals(vertices, f, unit=False)
        for k in range(3):
            total[:, k] += np.bincount(f.ravel(), weights=np.repeat(n[:, k], 3), minlength=len(vertices))
    return _unit(total)


def smoothed(normals: np.ndarray, faces: np.ndarray, radius_mm: float, edge_mm: float) -> tuple[np.ndarray, int]:
    """``normals`` averaged over about ``radius_mm``: (radius / edge)^2 rounds of replacing each normal by the mean
    of itself and its neighbours (a diffusion whose reach grows as the square root of the rounds, times the edge
    length ``edge_mm``); returns the normals and the rounds."""
    rounds = math.ceil((radius_mm / edge_mm) ** 2) if radius_mm > 0 else 0
    if rounds == 0:
        return normals, 0
    check_size("normal-smoothing work (rounds x edges)", float(rounds) * 3 * len(faces), MAX_SMOOTHING_WORK,
               "normal_radius_mm")
    from scipy.sparse import coo_matrix

    n = len(normals)
    a, b = faces.ravel(), np.roll(faces, -1, axis=1).ravel()
    adjacency = coo_matrix((np.ones(2 * len(a)), (np.concatenate([a, b]), np.concatenate([b, a]))), shape=(n, n))
    adjacency = adjacency.tocsr()
    adjacency.data[:] = 1.0  # shared edges counted once
    out = normals
    for _ in range(rounds):
        out = _unit(out + adjacency @ out)
    return out, rounds


def _unit(v: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(v, axis=1, keepdims=True)
    return v / np.where(length > 0, length, 1.0)

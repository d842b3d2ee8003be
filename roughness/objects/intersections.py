"""Does a mesh intersect itself? Exact triangle-pair tests on the pairs whose bounding boxes overlap.

Method: the faces' axis-aligned bounding boxes are indexed in an R-tree (rtree, libspatialindex), slab by slab
along x so the index stays small (a face crossing a slab boundary is in both; a pair is counted in the slab where
the overlap of their boxes begins). Each pair of overlapping boxes whose faces share no vertex is tested exactly:
two triangles in general position intersect if and only if an edge of one crosses the other (Moeller-Trumbore
segment test, six per pair). Not seen by this test: coplanar overlaps, and pairs that share a vertex (neighbours);
a displacement that folds neighbours over each other turns a face over, which ``folded_faces`` catches.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SLAB_FACES = 2_000_000
"""Faces whose boxes start in one slab (the R-tree of a slab holds about this many: a few hundred MB)."""
PAIR_CHUNK = 2_000_000
"""Pairs tested at once."""


@dataclass(frozen=True)
class Intersections:
    """Pairs of faces (``pairs``, (k, 2)) that cross each other, of ``tested`` candidate pairs."""

    pairs: np.ndarray
    tested: int

    @property
    def count(self) -> int:
        return len(self.pairs)


def self_intersections(vertices: np.ndarray, faces: np.ndarray, moved: np.ndarray | None = None) -> Intersections:
    """The pairs of faces of (``vertices``, ``faces``) that cross each other (module docstring). ``moved``: a mask of
    the faces that may have moved; pairs of two unmoved faces are not tested (the input mesh is taken as sound)."""
    from rtree import index

    mins = np.empty((len(faces), 3))
    maxs = np.empty((len(faces), 3))
    for start in range(0, len(faces), SLAB_FACES):
        tri = vertices[faces[start:start + SLAB_FACES]]
        mins[start:start + SLAB_FACES] = tri.min(axis=1)
        maxs[start:start + SLAB_FACES] = tri.max(axis=1)
    moved = np.ones(len(faces), dtype=bool) if moved is None else np.asarray(moved, dtype=bool)
    order = np.argsort(mins[:, 0], kind="stable")
    bounds = [mins[order[k], 0] for k in range(0, len(order), SLAB_FACES)] + [np.inf]
    found, tested = [], 0
    prop = index.Property()
    prop.dimension = 3
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        members = np.flatnonzero((mins[:, 0] < hi) & (maxs[:, 0] >= lo))
        if len(members) < 2:
            continue
        tree = index.Index((np.arange(len(members), dtype=np.int64), mins[members], maxs[members]),
                           properties=prop, interleaved=False)
        queried = members[moved[members]]
        hits, counts = tree.intersection_v(mins[queried], maxs[queried])
        i = np.repeat(queried, counts.astype(np.int64))
        j = members[hits.astype(np.int64)]
        keep = (i != j) & ((i < j) | ~moved[j])
        start = np.maximum(mins[i, 0], mins[j, 0])
        keep &= (start >= lo) & (start < hi)
        i, j = i[keep], j[keep]
        shared = (faces[i][:, :, None] == faces[j][:, None, :]).any(axis=(1, 2))
        i, j = i[~shared], j[~shared]
        tested += len(i)
        for s in range(0, len(i), PAIR_CHUNK):
            a, b = i[s:s + PAIR_CHUNK], j[s:s + PAIR_CHUNK]
            cross = triangles_cross(vertices[faces[a]], vertices[faces[b]])
            found.append(np.stack([a[cross], b[cross]], axis=1))
    pairs = np.concatenate(found) if found else np.empty((0, 2), dtype=np.int64)
    return Intersections(pairs, tested)


def triangles_cross(t1: np.ndarray, t2: np.ndarray) -> np.ndarray:
    """(k,) bool: whether triangles t1[k] and t2[k] ((k, 3, 3) mm) cross: an edge of one passes through the
    other's interior."""
    out = np.zeros(len(t1), dtype=bool)
    for first, second in ((t1, t2), (t2, t1)):
        for e in range(3):
            out |= segment_hits(first[:, e], first[:, (e + 1) % 3], second)
    return out


def segment_hits(p0: np.ndarray, p1: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(k,) bool: whether the open segment p0[k]-p1[k] passes through the open triangle tri[k] (not parallel)."""
    a = tri[:, 0]
    e1, e2 = tri[:, 1] - a, tri[:, 2] - a
    d = p1 - p0
    h = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, h)
    scale = np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1) * np.linalg.norm(d, axis=1)
    ok = np.abs(det) > 1e-12 * scale
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = p0 - a
    u = inv * np.einsum("ij,ij->i", s, h)
    q = np.cross(s, e1)
    v = inv * np.einsum("ij,ij->i", d, q)
    t = inv * np.einsum("ij,ij->i", e2, q)
    return ok & (u > 0) & (v > 0) & (u + v < 1) & (t > 0) & (t < 1)


def folded_faces(base_normals: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(m,) bool: faces turned over by a displacement (their normal against ``base_normals``, the undisplaced
    faces' unit normals) or collapsed to no area."""
    tri = vertices[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    return np.einsum("ij,ij->i", n, base_normals) <= 0

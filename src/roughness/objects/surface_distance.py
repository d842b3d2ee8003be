"""The two-sided geometric distance between two triangle surfaces (mm), measured, not estimated: how far a decimated
mesh lies from the full one.

Each surface is sampled densely (``samples``: its vertices, and each triangle's points on a barycentric grid fine
enough that neighbouring samples are at most ``spacing_mm`` apart), and every sample's distance to the *other*
surface is computed exactly to its nearest triangle (``point_triangle_distance``): the candidates are the triangles
whose centroids are the ``CANDIDATES`` nearest to the sample (a KD-tree per group of triangles of about one size),
and a sample for which a triangle outside them might be nearer (its centroid's distance, less the largest
centroid-to-corner radius of its group, is below the distance found) is searched again over every triangle of the
group within that reach. So each sample's distance is exact (to
floating-point rounding); the maximum over the samples is the surface's distance up to the sampling: the distance
is 1-Lipschitz along the surface, so the true maximum exceeds the measured one by at most the samples' covering
radius (``SurfaceDistance.covering_mm``, reported).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

CANDIDATES = 8
"""Triangles (nearest by centroid) whose exact distance is computed for every sample before the certification step."""
GROUP_RATIO = 4.0
"""Triangles are grouped by centroid-to-corner radius, within this factor in a group (the largest group's takes the
rest)."""
MAX_GROUPS = 4
"""At most this many groups (every sample queries each)."""
CHUNK = 100_000
"""Samples handled at once (their candidates' corners: about 60 MB)."""


@dataclass(frozen=True)
class SurfaceDistance:
    """The distances (mm) from the samples of surface A to surface B and back: their maxima, the sample count, the
    point where the larger maximum was found (mm), and the samples' covering radius (mm: every point of a surface
    lies within it of a sample, so the true maximum is at most ``max_mm + covering_mm``)."""

    a_to_b_mm: float
    b_to_a_mm: float
    samples: int
    where: tuple[float, float, float]
    covering_mm: float

    @property
    def max_mm(self) -> float:
        """The two-sided (Hausdorff) distance measured at the samples."""
        return max(self.a_to_b_mm, self.b_to_a_mm)


class TriangleSurface:
    """A triangle surface (vertices (n, 3) mm, faces (m, 3)) indexed for nearest-triangle queries: its triangles
    grouped by their centroid-to-corner radius (``GROUP_RATIO``, ``MAX_GROUPS``), each group a KD-tree of centroids
    with its largest radius (so that a group of small triangles is not searched as widely as one of large ones)."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        from scipy.spatial import cKDTree

        self.vertices = np.asarray(vertices, dtype=float)
        self.faces = np.asarray(faces, dtype=np.int64)
        centroids, radius = np.empty((len(self.faces), 3)), np.empty(len(self.faces))
        for s in range(0, len(self.faces), CHUNK):
            tri = self.vertices[self.faces[s:s + CHUNK]]
            centroids[s:s + CHUNK] = tri.mean(axis=1)
            radius[s:s + CHUNK] = np.linalg.norm(tri - centroids[s:s + CHUNK, None], axis=2).max(axis=1)
        group = np.floor(np.log(np.maximum(radius, 1e-12) / max(float(radius.max()), 1e-12)) / np.log(GROUP_RATIO))
        group = np.maximum(group, -MAX_GROUPS + 1).astype(np.int64)
        self.groups = [(members, float(radius[members].max()), cKDTree(centroids[members]))
                       for members in (np.flatnonzero(group == g) for g in np.unique(group))]

    def distances(self, points: np.ndarray, progress: Callable[[float], object] | None = None) -> np.ndarray:
        """The exact distance (mm) from each of ``points`` (k, 3) to the nearest triangle (module docstring)."""
        out = np.empty(len(points))
        for s in range(0, len(points), CHUNK):
            p = points[s:s + CHUNK]
            best, farthest = np.full(len(p), np.inf), []
            for members, _, tree in self.groups:
                k = min(CANDIDATES, len(members))
                near, idx = tree.query(p, k=k)
                near, idx = near.reshape(len(p), k), idx.reshape(len(p), k)
                d = self._to(np.repeat(p, k, axis=0), members[idx.ravel()]).reshape(len(p), k)
                best = np.minimum(best, d.min(axis=1))
                farthest.append(near[:, -1] if k < len(members) else np.full(len(p), np.inf))
            for (members, radius, tree), far in zip(self.groups, farthest):
                unsure = np.flatnonzero(far - radius < best)
                if len(unsure):
                    best[unsure] = self._within(p[unsure], best[unsure], members, radius, tree)
            out[s:s + CHUNK] = best
            if progress is not None:
                progress(min(s + CHUNK, len(points)) / len(points))
        return out

    def _to(self, p: np.ndarray, faces: np.ndarray) -> np.ndarray:
        """Distance from each point ``p`` to the triangle ``faces`` (one each)."""
        tri = self.vertices[self.faces[faces]]
        return point_triangle_distance(p, tri[:, 0], tri[:, 1], tri[:, 2])

    def _within(self, p: np.ndarray, best: np.ndarray, members: np.ndarray, radius: float, tree) -> np.ndarray:
        """``best`` lowered to the distance to any triangle of a group whose centroid lies within ``best`` plus the
        group's ``radius`` of each point ``p``."""
        reach = tree.query_ball_point(p, best + radius)
        counts = np.fromiter((len(r) for r in reach), dtype=np.int64, count=len(reach))
        has = np.flatnonzero(counts)
        if not len(has):
            return best
        idx = np.concatenate([np.asarray(reach[i], dtype=np.int64) for i in has])
        d = self._to(np.repeat(p[has], counts[has], axis=0), members[idx])
        best = best.copy()
        best[has] = np.minimum(best[has], np.minimum.reduceat(d, np.r_[0, np.cumsum(counts[has])[:-1]]))
        return best


def longest_edges(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each triangle's longest edge (mm), computed CHUNK triangles at a time."""
    out = np.empty(len(faces))
    for s in range(0, len(faces), CHUNK):
        tri = vertices[faces[s:s + CHUNK]]
        out[s:s + CHUNK] = np.linalg.norm(tri[:, [1, 2, 0]] - tri, axis=2).max(axis=1)
    return out


def samples(vertices: np.ndarray, faces: np.ndarray, spacing_mm: float) -> tuple[np.ndarray, float]:
    """Points on the surface: its vertices, and on each triangle the points of a barycentric grid of m x m
    sub-triangles, m = ceil(longest edge / ``spacing_mm``) (none added where m is 1); with the covering radius
    (mm: the longest sub-triangle edge over sqrt(3): every point of a triangle lies within it of a corner)."""
    vertices, faces = np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64)
    longest = longest_edges(vertices, faces)
    m = np.maximum(np.ceil(longest / spacing_mm - 1e-9).astype(np.int64), 1)
    parts, covering = [vertices], float((longest / m).max()) / math.sqrt(3)
    for level in np.unique(m[m > 1]):
        i, j = np.meshgrid(np.arange(level + 1), np.arange(level + 1), indexing="ij")
        keep = (i + j <= level) & ~(((i == 0) | (i == level)) & ((j == 0) | (j == level)))  # corners are vertices
        wb, wc = i[keep] / level, j[keep] / level
        which = np.flatnonzero(m == level)
        step = CHUNK // len(wb) + 1
        for s in range(0, len(which), step):
            c = vertices[faces[which[s:s + step]]]
            parts.append((c[:, None, 0] * (1 - wb - wc)[:, None] + c[:, None, 1] * wb[:, None]
                          + c[:, None, 2] * wc[:, None]).reshape(-1, 3))
    return np.concatenate(parts), covering


def surface_distance(a: TriangleSurface, b: TriangleSurface, spacing_mm: float,
                     progress: Callable[[float], object] | None = None) -> SurfaceDistance:
    """The two-sided distance (module docstring) between surfaces ``a`` and ``b``, each sampled ``spacing_mm``
    apart (mm). ``progress``: the fraction of the samples measured."""
    pa, cover_a = samples(a.vertices, a.faces, spacing_mm)
    pb, cover_b = samples(b.vertices, b.faces, spacing_mm)
    total = len(pa) + len(pb)

    def part(offset: int, size: int) -> Callable[[float], object] | None:
        return None if progress is None else (lambda done: progress((offset + done * size) / total))

    da = b.distances(pa, part(0, len(pa)))
    db = a.distances(pb, part(len(pa), len(pb)))
    where = pa[int(np.argmax(da))] if da.max() >= db.max() else pb[int(np.argmax(db))]
    x, y, z = (float(c) for c in where)
    return SurfaceDistance(float(da.max()), float(db.max()), total, (x, y, z), max(cover_a, cover_b))


def point_triangle_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Distance (mm) from each point ``p`` (k, 3) to its triangle (corners ``a``, ``b``, ``c``, each (k, 3)): to its
    closest point, found by the Voronoi region of the triangle the point lies in (corner, edge or face; Ericson,
    Real-Time Collision Detection, 5.1.5), vectorised; a degenerate (zero-area) triangle by its edges."""
    ab, ac, ap, bp, cp = (np.asarray(x, dtype=float).T for x in (b - a, c - a, p - a, p - b, p - c))

    def dot(u, v):
        return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]

    d1, d2, d3, d4, d5, d6 = dot(ab, ap), dot(ac, ap), dot(ab, bp), dot(ac, bp), dot(ab, cp), dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        total = va + vb + vc
        s, t = vb / total, vc / total  # inside the face: barycentric weights of b and c
        regions = (  # later entries win: Ericson's order of tests, reversed
            ((va <= 0) & (d4 >= d3) & (d5 >= d6), 1 - (d4 - d3) / ((d4 - d3) + (d5 - d6)), (d4 - d3) / ((d4 - d3) + (d5 - d6))),
            ((vb <= 0) & (d2 >= 0) & (d6 <= 0), 0.0, d2 / (d2 - d6)),
            ((d6 >= 0) & (d5 <= d6), 0.0, 1.0),
            ((vc <= 0) & (d1 >= 0) & (d3 <= 0), d1 / (d1 - d3), 0.0),
            ((d3 >= 0) & (d4 <= d3), 1.0, 0.0),
            ((d1 <= 0) & (d2 <= 0), 0.0, 0.0))
        for mask, sr, tr in regions:
            s, t = np.where(mask, sr, s), np.where(mask, tr, t)
    d = np.sqrt(sum((ap[i] - np.nan_to_num(s) * ab[i] - np.nan_to_num(t) * ac[i]) ** 2 for i in range(3)))
    flat = np.flatnonzero(~(total > 0))  # total = |ab x ac|^2: zero for a degenerate triangle
    if len(flat):
        p, a, b, c = p[flat], a[flat], b[flat], c[flat]
        d[flat] = np.minimum(np.minimum(_segment_distance(p, a, b), _segment_distance(p, b, c)),
                             _segment_distance(p, c, a))
    return d


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each point ``p`` to the segment from ``a`` to ``b`` (rows)."""
    d = b - a
    dd = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    return np.linalg.norm(p - a - t[:, None] * d, axis=1)

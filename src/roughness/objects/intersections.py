"""Does a mesh intersect itself? Exact triangle-pair tests on the pairs whose bounding boxes overlap.

Method: candidate pairs are the faces whose axis-aligned bounding boxes overlap, found on a uniform grid (cell: the
90th percentile of the faces' box extents) where each face is entered in every cell its box touches and a pair is
counted only in the cell holding the corner where the overlap of their boxes begins (so once); the grid is built
slab by slab along x, so memory stays bounded for meshes of tens of millions of faces; the few faces
whose boxes span more than MAX_CELLS cells (large untextured faces, long transition slivers) are put in an R-tree
(rtree) queried with every face's box instead. Each candidate pair whose faces share no vertex is tested exactly: two
triangles in general position intersect if and only if an edge of one crosses the other (Moeller-Trumbore segment
test, six per pair). Not seen by this test: coplanar overlaps, and pairs that share a vertex (neighbours); a
displacement that folds neighbours over each other turns a face over, which ``folded_faces`` catches.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

MAX_CELLS = 64
"""Grid cells a face's box may span to be entered on the grid; larger faces go through the R-tree."""
SLAB_FACES = 500_000
"""Faces (by where their boxes begin along x) whose grid entries are made at once."""
CHUNK_ENTRIES = 200_000
"""Grid entries expanded into candidate pairs at once (a few million pairs)."""
PAIR_CHUNK = 2_000_000
"""Pairs tested exactly at once."""
QUERY_CHUNK = 500_000
"""Boxes queried against the R-tree of large faces at once."""


@dataclass(frozen=True)
class Intersections:
    """Pairs of faces (``pairs``, (k, 2)) that cross each other, of ``tested`` candidate pairs."""

    pairs: np.ndarray
    tested: int

    @property
    def count(self) -> int:
        return len(self.pairs)


def self_intersections(vertices: np.ndarray, faces: np.ndarray, moved: np.ndarray | None = None,
                       progress: Callable[[float], object] | None = None) -> Intersections:
    """The pairs of faces of (``vertices``, ``faces``) that cross each other (module docstring). ``moved``: a mask of
    the faces that may have moved; pairs of two unmoved faces are not tested (the input mesh is taken as sound).
    ``progress``: called after each slab with the fraction of the faces' slabs done (1 at the end)."""
    faces = np.asarray(faces, dtype=np.int64)
    moved = np.ones(len(faces), dtype=bool) if moved is None else np.asarray(moved, dtype=bool)
    mins = np.empty((len(faces), 3), dtype=np.float32)  # rounded outwards: boxes only grow
    maxs = np.empty((len(faces), 3), dtype=np.float32)
    for start in range(0, len(faces), PAIR_CHUNK):
        tri = vertices[faces[start:start + PAIR_CHUNK]]
        mins[start:start + PAIR_CHUNK] = np.nextafter(tri.min(axis=1).astype(np.float32), -np.inf)
        maxs[start:start + PAIR_CHUNK] = np.nextafter(tri.max(axis=1).astype(np.float32), np.inf)
    cell = max(float(np.percentile((maxs - mins).max(axis=1), 90)), 1e-6)
    origin = mins.min(axis=0).astype(float)
    grid = _Grid(origin, cell, int(np.floor((maxs[:, 1].max() - origin[1]) / cell)) + 2,
                 int(np.floor((maxs[:, 2].max() - origin[2]) / cell)) + 2)
    lo_x, hi_x = grid.cells(mins[:, 0], 0), grid.cells(maxs[:, 0], 0)
    large = np.zeros(len(faces), dtype=bool)
    for start in range(0, len(faces), PAIR_CHUNK):
        sl = slice(start, start + PAIR_CHUNK)
        span = [grid.cells(maxs[sl, k], k) - grid.cells(mins[sl, k], k) + 1 for k in range(3)]
        large[sl] = span[0] * span[1] * span[2] > MAX_CELLS
    found: list[np.ndarray] = []
    tested = 0
    small = np.flatnonzero(~large)
    order = small[np.argsort(lo_x[small], kind="stable")]
    cuts = [int(lo_x[order[k]]) for k in range(0, len(order), SLAB_FACES)] + [int(hi_x.max()) + 1]
    for slab, (x0, x1) in enumerate(zip(cuts[:-1], cuts[1:])):
        if progress is not None and slab:
            progress(slab / len(cuts))
        if x1 <= x0:
            continue
        members = small[(lo_x[small] < x1) & (hi_x[small] >= x0)]
        for i, j in _grid_pairs(grid, members, mins, maxs, x0, x1):
            t, hits = _test(vertices, faces, moved, mins, maxs, i, j)
            tested, found = tested + t, found + [hits]
    if large.any():
        for i, j in _tree_pairs(np.flatnonzero(large), mins, maxs):
            keep = ~large[i] | (i < j)  # a large-large pair once
            t, hits = _test(vertices, faces, moved, mins, maxs, i[keep], j[keep])
            tested, found = tested + t, found + [hits]
    pairs = np.concatenate(found) if found else np.empty((0, 2), dtype=np.int64)
    if progress is not None:
        progress(1.0)
    return Intersections(pairs, tested)


@dataclass(frozen=True)
class _Grid:
    """Cubic cells of side ``cell`` (mm) from ``origin``; ``ny``, ``nz`` cells along y and z (for keys)."""

    origin: np.ndarray
    cell: float
    ny: int
    nz: int

    def cells(self, coordinate: np.ndarray, axis: int) -> np.ndarray:
        return np.floor((coordinate - self.origin[axis]) / self.cell).astype(np.int64)

    def key(self, cx: np.ndarray, cy: np.ndarray, cz: np.ndarray) -> np.ndarray:
        return (cx * self.ny + cy) * self.nz + cz


def _grid_pairs(grid: _Grid, ids: np.ndarray, mins: np.ndarray, maxs: np.ndarray, x0: int, x1: int):
    """Chunks of (i, j), i < j, of faces ``ids`` sharing a grid cell whose x index lies in [x0, x1), each pair in
    one cell only."""
    if len(ids) < 2:
        return
    lo = np.stack([grid.cells(mins[ids, k], k) for k in range(3)], axis=1)
    span = np.stack([grid.cells(maxs[ids, k], k) for k in range(3)], axis=1) - lo + 1
    counts = span.prod(axis=1)
    # entries: (face, cell) for every cell of the face's box
    entry = np.repeat(np.arange(len(ids)), counts)
    offset = np.arange(len(entry)) - np.repeat(np.cumsum(counts) - counts, counts)
    sy, sz = span[entry, 1], span[entry, 2]
    cx = lo[entry, 0] + offset // (sy * sz)
    inside = (cx >= x0) & (cx < x1)
    key = grid.key(cx[inside], (lo[entry, 1] + (offset // sz) % sy)[inside], (lo[entry, 2] + offset % sz)[inside])
    entry_face = ids[entry[inside]]
    del entry, offset, sy, sz, cx, inside, lo, span
    order = np.argsort(key, kind="stable")
    key, entry_face = key[order], entry_face[order]
    del order
    after = np.searchsorted(key, key, side="right") - np.arange(len(key)) - 1  # later entries in the same cell
    for s in range(0, len(key), CHUNK_ENTRIES):
        positions = np.arange(s, min(s + CHUNK_ENTRIES, len(key)))
        n_after = after[positions]
        total = int(n_after.sum())
        if total == 0:
            continue
        first = np.repeat(positions, n_after)
        second = first + 1 + (np.arange(total) - np.repeat(np.cumsum(n_after) - n_after, n_after))
        i, j = entry_face[first], entry_face[second]
        # count the pair only in the cell that holds the start of the overlap of the two boxes
        corner = np.maximum(mins[i], mins[j])
        here = grid.key(*(grid.cells(corner[:, k], k) for k in range(3))) == key[first]
        i, j = i[here], j[here]
        yield np.minimum(i, j), np.maximum(i, j)


def _tree_pairs(large: np.ndarray, mins: np.ndarray, maxs: np.ndarray):
    """Chunks of (i, j): every face i with each large face j whose box overlaps its box (an R-tree of the large faces,
    queried with every face's box)."""
    from rtree import index

    prop = index.Property()
    prop.dimension = 3
    tree = index.Index((np.arange(len(large), dtype=np.int64), mins[large].astype(float), maxs[large].astype(float)),
                       properties=prop, interleaved=False)
    for s in range(0, len(mins), QUERY_CHUNK):
        q = np.arange(s, min(s + QUERY_CHUNK, len(mins)))
        hits, counts = tree.intersection_v(mins[q].astype(float), maxs[q].astype(float))
        i = np.repeat(q, counts.astype(np.int64))
        j = large[hits.astype(np.int64)]
        yield i[i != j], j[i != j]


def _test(vertices, faces, moved, mins, maxs, i, j) -> tuple[int, np.ndarray]:
    """(pairs tested, crossing pairs) among candidates (i, j): boxes overlapping, one face moved, no shared vertex."""
    keep = (moved[i] | moved[j]) & np.all((mins[i] <= maxs[j]) & (mins[j] <= maxs[i]), axis=1)
    i, j = i[keep], j[keep]
    shared = (faces[i][:, :, None] == faces[j][:, None, :]).any(axis=(1, 2))
    i, j = i[~shared], j[~shared]
    out = []
    for s in range(0, len(i), PAIR_CHUNK):
        a, b = i[s:s + PAIR_CHUNK], j[s:s + PAIR_CHUNK]
        cross = triangles_cross(vertices[faces[a]], vertices[faces[b]])
        out.append(np.stack([a[cross], b[cross]], axis=1))
    return len(i), (np.concatenate(out) if out else np.empty((0, 2), dtype=np.int64))


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

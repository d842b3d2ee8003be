"""Refine the textured faces of a mesh to a target edge length, conforming, so a closed mesh stays closed.

Each round splits, at its midpoint, the longest edge of every textured face whose longest edge exceeds the target
(longest-edge bisection, which keeps the triangles' angles bounded and does not over-refine long thin faces); each
face is then replaced by the template for its split edges (one, two or three: two, three or four triangles, the quad
of two split edges cut along its shorter diagonal). An edge is
split for both faces that share it, so no crack opens; untextured faces are only split where they share an edge
with a textured one (the transition), elsewhere they stay as they were. A new vertex is the midpoint of its edge,
so flat faces stay flat. Orientation is kept, so a consistently wound mesh stays so.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError
from roughness.core.limits import MAX_MESH_TRIANGLES, check_size

CHUNK = 1_000_000
"""Faces handled at once in a round (their edges, lengths and templates: about 200 MB)."""


@dataclass
class Refined:
    """A refined mesh: ``vertices`` (n, 3) mm, ``faces`` (m, 3), ``textured`` (m,) bool, the ``rounds`` of
    splitting it took, and the pieces of the input's ``creases`` (edges followed through the splitting: ``creases``
    (k, 2) vertex pairs, ``crease_of`` (k,) the index of the input edge each piece is part of)."""

    vertices: np.ndarray
    faces: np.ndarray
    textured: np.ndarray
    rounds: int
    creases: np.ndarray
    crease_of: np.ndarray


SAMPLE_FACES = 48
"""Textured faces refined alone to estimate how many triangles a refinement makes (drawn by area)."""
SAMPLE_BUDGET = 50_000
"""Triangles a sampled well-shaped face may make in the estimate; a larger face is refined at a coarser edge and its
count scaled. Needles make more than their area says; their refinement stops at SAMPLE_CAP."""
SAMPLE_CAP = 1_000_000
"""Triangles at which one sampled face's refinement stops (bounding the estimate's own time to seconds)."""


def predicted_triangles(vertices: np.ndarray, faces: np.ndarray, textured: np.ndarray, edge_mm: float,
                        seed: int = 0) -> float:
    """About how many triangles refinement will make: the textured faces' own refinement per mm^2, measured on up to
    SAMPLE_FACES of them refined alone (drawn with probability proportional to area, so the estimate of the total
    is unbiased), times the textured area, plus the untextured faces; checked against MAX_MESH_TRIANGLES before
    anything is refined. Measured, not assumed: longest-edge bisection makes about 0.17 edge_mm^2 triangles of a
    well-shaped face but many more of a needle (a 60 x 0.65 mm face of a 96-sided cylinder: 8 times as many at a
    0.225 mm edge; the count jumps with the number of halvings, so it is not a smooth function of the edge). A
    sampled face larger than SAMPLE_BUDGET well-shaped triangles is refined at a coarser edge and its count scaled by
    the squared ratio (bisection is self-similar on faces much larger than the edge). Joining neighbours adds the
    transition of the untextured faces beside the region, a few percent."""
    area = _areas(vertices, faces, textured)
    total = float(area.sum())
    if total == 0:
        return float((~textured).sum())
    rng = np.random.default_rng(seed)
    textured_ids = np.flatnonzero(textured)
    picked = rng.choice(len(textured_ids), size=min(SAMPLE_FACES, len(textured_ids)), p=area / total)
    counts: dict[tuple, float] = {}  # by shape: congruent faces (a cylinder's sides) refine alike
    per_mm2 = []
    for i in picked:
        corners = vertices[faces[textured_ids[i]]]
        shape = tuple(np.round(np.sort(np.linalg.norm(corners[[1, 2, 0]] - corners, axis=1)) / edge_mm, 6))
        if shape not in counts:
            counts[shape] = _alone(corners, edge_mm)
        per_mm2.append(counts[shape] / area[i])
    return total * float(np.mean(per_mm2)) + float((~textured).sum())


def _areas(vertices: np.ndarray, faces: np.ndarray, textured: np.ndarray) -> np.ndarray:
    """Areas (mm^2) of the textured faces, in order."""
    out = []
    for s in range(0, len(faces), CHUNK):
        tri = vertices[faces[s:s + CHUNK][textured[s:s + CHUNK]]]
        out.append(0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1))
    return np.concatenate(out) if out else np.empty(0)


def _alone(corners: np.ndarray, edge_mm: float) -> float:
    """Triangles longest-edge bisection makes of one triangle (corners (3, 3), mm) to ``edge_mm``, refined at a
    coarser edge (and scaled) where that would exceed SAMPLE_BUDGET."""
    area = 0.5 * float(np.linalg.norm(np.cross(corners[1] - corners[0], corners[2] - corners[0])))
    scale = max(1.0, math.sqrt(area / (edge_mm**2 / 8) / SAMPLE_BUDGET))  # well-shaped: about area / (edge^2 / 8)
    edge = edge_mm * scale
    v, f, tex = corners.astype(float), np.array([[0, 1, 2]]), np.array([True])
    while True:
        split = _edges_to_split(v, f, tex, edge)
        if split.size == 0 or len(f) > SAMPLE_CAP:
            return len(f) * scale**2
        n = len(v)
        v = np.concatenate([v, 0.5 * (v[split // n] + v[split % n])])
        f, tex = _split(v, f, tex, split, n)


def refine(vertices: np.ndarray, faces: np.ndarray, textured: np.ndarray, edge_mm: float,
           progress: Callable[[float], object] | None = None, creases: np.ndarray | None = None) -> Refined:
    """Split edges of textured faces until none is longer than ``edge_mm`` (mm) (module docstring). ``progress``:
    called after each round with the fraction done, the triangles so far over ``predicted_triangles`` (an estimate,
    so it may end below 1; 1 when done). ``creases``: (k, 2) vertex pairs, edges of the input whose pieces are
    followed through the splitting (``Refined.creases``: the sharp edges of a CAD part)."""
    if not edge_mm > 0:
        raise InputError(f"edge length must be positive, got {edge_mm!r}", parameter="edge_mm")
    expected = predicted_triangles(vertices, faces, textured, edge_mm)
    check_size("triangles after refinement (estimated)", expected, MAX_MESH_TRIANGLES, "edge_mm")
    v = np.ascontiguousarray(vertices, dtype=float)
    f = np.ascontiguousarray(faces, dtype=np.int64)
    tex = np.asarray(textured, dtype=bool).copy()
    crease_pieces = np.empty((0, 2), dtype=np.int64) if creases is None else np.asarray(creases, dtype=np.int64)
    crease_of = np.arange(len(crease_pieces))
    rounds = 0
    while True:
        split = _edges_to_split(v, f, tex, edge_mm)
        if split.size == 0:
            if progress is not None:
                progress(1.0)
            return Refined(v, f, tex, rounds, crease_pieces, crease_of)
        rounds += 1
        n = len(v)
        crease_pieces, crease_of = _split_creases(crease_pieces, crease_of, split, n)
        v = np.concatenate([v, 0.5 * (v[split // n] + v[split % n])])
        pieces = [_split(v, f[s:s + CHUNK], tex[s:s + CHUNK], split, n) for s in range(0, len(f), CHUNK)]
        del f, tex
        f = np.concatenate([p[0] for p in pieces])
        tex = np.concatenate([p[1] for p in pieces])
        del pieces
        check_size("triangles during refinement", len(f), MAX_MESH_TRIANGLES, "edge_mm")
        if progress is not None:
            progress(min(len(f) / max(expected, 1.0), 0.99))


def _split_creases(pieces: np.ndarray, crease_of: np.ndarray, split: np.ndarray, n: int):
    """The crease ``pieces`` ((k, 2) vertex pairs of a mesh of ``n`` vertices) and the crease each is part of
    (``crease_of``), after the edges ``split`` (sorted keys) are split at new vertices n, n + 1, ... in their order."""
    if len(pieces) == 0:
        return pieces, crease_of
    keys = np.minimum(pieces[:, 0], pieces[:, 1]) * n + np.maximum(pieces[:, 0], pieces[:, 1])
    where = np.searchsorted(split, keys)
    hit = split[np.minimum(where, len(split) - 1)] == keys
    mid = n + where[hit]
    a, b = pieces[hit, 0], pieces[hit, 1]
    return (np.concatenate([pieces[~hit], np.stack([a, mid], 1), np.stack([mid, b], 1)]),
            np.concatenate([crease_of[~hit], crease_of[hit], crease_of[hit]]))


def _edge_keys(f: np.ndarray, n_vertices: int) -> np.ndarray:
    """(m, 3) int64 keys of each face's edges (a, b), (b, c), (c, a), the same for both faces of an edge."""
    a, b = f, np.roll(f, -1, axis=1)
    return np.minimum(a, b) * n_vertices + np.maximum(a, b)


def _edges_to_split(v: np.ndarray, f: np.ndarray, tex: np.ndarray, edge_mm: float) -> np.ndarray:
    """Sorted unique keys of the longest edges of textured faces, where longer than ``edge_mm``."""
    keys = []
    for s in range(0, len(f), CHUNK):
        ft = f[s:s + CHUNK][tex[s:s + CHUNK]]
        length = np.linalg.norm(v[np.roll(ft, -1, axis=1)] - v[ft], axis=2)
        longest = np.argmax(length, axis=1) if len(ft) else np.empty(0, dtype=np.int64)
        rows = np.flatnonzero(length[np.arange(len(ft)), longest] > edge_mm)
        keys.append(_edge_keys(ft[rows], len(v))[np.arange(len(rows)), longest[rows]])
    return np.unique(np.concatenate(keys)) if keys else np.empty(0, dtype=np.int64)


def _split(v: np.ndarray, f: np.ndarray, tex: np.ndarray, split: np.ndarray, n: int):
    """Faces ``f`` (of a mesh of ``n`` vertices before this round; ``v`` holds the midpoints of ``split`` after them)
    replaced by their templates, and their textured flags."""
    keys = _edge_keys(f, n)
    where = np.searchsorted(split, keys)
    hit = split[np.minimum(where, len(split) - 1)] == keys
    mid = np.where(hit, n + where, -1)  # (m, 3) new vertex on each edge, or -1
    del keys, where
    pattern = hit.sum(axis=1)
    out_f, out_t = [f[pattern == 0]], [tex[pattern == 0]]
    for count in (1, 2, 3):
        sel = pattern == count
        if not sel.any():
            continue
        fs, ms, hs = f[sel], mid[sel], hit[sel]
        if count == 1:
            roll = np.argmax(hs, axis=1)  # the split edge first
        elif count == 2:
            roll = (np.argmin(hs, axis=1) + 1) % 3  # the unsplit edge last
        else:
            roll = np.zeros(len(fs), dtype=np.int64)
        idx = (np.arange(3)[None, :] + roll[:, None]) % 3
        fs = np.take_along_axis(fs, idx, axis=1)
        ms = np.take_along_axis(ms, idx, axis=1)
        new = _template(v, fs, ms, count)
        out_f.append(new)
        out_t.append(np.tile(tex[sel], len(new) // len(fs)))
    return np.concatenate(out_f), np.concatenate(out_t)


def _template(v: np.ndarray, fs: np.ndarray, ms: np.ndarray, count: int) -> np.ndarray:
    """The faces replacing faces ``fs`` (a, b, c) with midpoints ``ms`` (on ab, bc, ca), rolled so that the split
    edge comes first (1) or the unsplit one last (2); stacked template by template."""
    a, b, c = fs.T
    m0, m1, m2 = ms.T
    if count == 1:
        return np.concatenate([np.stack([a, m0, c], 1), np.stack([m0, b, c], 1)])
    if count == 2:
        short = np.linalg.norm(v[a] - v[m1], axis=1) <= np.linalg.norm(v[m0] - v[c], axis=1)
        first = np.where(short[:, None], np.stack([a, m0, m1], 1), np.stack([a, m0, c], 1))
        second = np.where(short[:, None], np.stack([a, m1, c], 1), np.stack([m0, m1, c], 1))
        return np.concatenate([np.stack([m0, b, m1], 1), first, second])
    return np.concatenate([np.stack([a, m0, m2], 1), np.stack([m0, b, m1], 1), np.stack([m2, m1, c], 1),
                           np.stack([m0, m1, m2], 1)])

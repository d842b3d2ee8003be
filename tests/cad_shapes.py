"""Closed meshes of CAD parts made in the tests (issue 41), and an independent self-intersection check.

``engraved_block``: a block whose top carries an engraved (or pocketed) pattern of cells, built cell by cell with
exact coordinates (every edge shared by two triangles, no T-junction). ``crossing_pairs``: a check of faces crossing
each other that shares nothing with roughness.objects.intersections: candidate pairs from trimesh's R-tree of the
triangles' bounds, each tested with signs of orientation determinants (a segment crosses a triangle where its ends
lie strictly on both sides of the triangle's plane and it passes strictly inside the triangle's three edges).
"""
from __future__ import annotations

import numpy as np
import trimesh

GLYPHS = {  # 5 x 7 cells, rows from the top; no two cells touching at a corner only (a non-manifold edge)
    "T": ["11111", "..1..", "..1..", "..1..", "..1..", "..1..", "..1.."],
    "E": ["11111", "1....", "1....", "1111.", "1....", "1....", "11111"],
}


def text_mask(text: str, shape: tuple[int, int], stroke: int = 2, at: tuple[int, int] = (4, 4)) -> np.ndarray:
    """(nx, ny) bool cells: ``text`` in GLYPHS, each glyph cell ``stroke`` x ``stroke`` cells, from cell ``at``."""
    mask = np.zeros(shape, dtype=bool)
    x0, y0 = at
    for k, letter in enumerate(text):
        for row, line in enumerate(GLYPHS[letter]):
            for col, c in enumerate(line):
                if c == "1":
                    x = x0 + (k * 6 + col) * stroke
                    y = y0 + (6 - row) * stroke
                    mask[x:x + stroke, y:y + stroke] = True
    return mask


def engraved_block(mask: np.ndarray, cell_mm: float = 0.5, height_mm: float = 4.0, depth_mm: float = 0.5):
    """A block of mask.shape cells of ``cell_mm`` (x, y), ``height_mm`` tall, with the ``mask`` cells sunk by
    ``depth_mm`` into its top; the mask must not touch the block's sides."""
    assert not (mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())
    nx, ny = mask.shape
    top = np.where(mask, height_mm - depth_mm, height_mm)
    quads = []

    def p(i, j, z):
        return (i * cell_mm, j * cell_mm, z)

    for i in range(nx):
        for j in range(ny):
            z = top[i, j]
            quads.append([p(i, j, z), p(i + 1, j, z), p(i + 1, j + 1, z), p(i, j + 1, z)])  # top, facing +z
            quads.append([p(i, j, 0), p(i, j + 1, 0), p(i + 1, j + 1, 0), p(i + 1, j, 0)])  # bottom, facing -z
            for di, dj in ((1, 0), (0, 1)):  # the wall to the next cell along x, along y, or the block's side
                a, b = (p(i + 1, j, 0), p(i + 1, j + 1, 0)) if di else (p(i, j + 1, 0), p(i + 1, j + 1, 0))
                inside = i + di < nx and j + dj < ny
                low, high = (min(z, top[i + di, j + dj]), max(z, top[i + di, j + dj])) if inside else (0.0, z)
                if low < high:
                    quads.append([(a[0], a[1], low), (b[0], b[1], low), (b[0], b[1], high), (a[0], a[1], high)])
            if i == 0:
                quads.append([p(0, j, 0), p(0, j + 1, 0), p(0, j + 1, z), p(0, j, z)])
            if j == 0:
                quads.append([p(i, 0, 0), p(i + 1, 0, 0), p(i + 1, 0, z), p(i, 0, z)])
    corners = np.array(quads, dtype=float)
    triangles = np.concatenate([corners[:, [0, 1, 2]], corners[:, [0, 2, 3]]])
    mesh = trimesh.Trimesh(*trimesh.triangles.to_kwargs(triangles).values(), process=True)
    trimesh.repair.fix_normals(mesh)
    volume = nx * ny * cell_mm**2 * height_mm - mask.sum() * cell_mm**2 * depth_mm
    assert mesh.is_watertight and mesh.is_winding_consistent and abs(mesh.volume - volume) < 1e-9 * volume, (
        mesh.is_watertight, mesh.is_winding_consistent, mesh.volume, volume)
    return mesh


def _orient(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Sign of the volume of the tetrahedra (a, b, c, d) ((k, 3) each)."""
    return np.sign(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a))


def _segment_crosses(p: np.ndarray, q: np.ndarray, tri: np.ndarray) -> np.ndarray:
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    sides = _orient(a, b, c, p) * _orient(a, b, c, q) < 0
    s1, s2, s3 = _orient(p, q, a, b), _orient(p, q, b, c), _orient(p, q, c, a)
    return sides & (s1 != 0) & (s1 == s2) & (s2 == s3)


def crossing_pairs(mesh) -> int:
    """Pairs of faces of ``mesh`` sharing no vertex whose interiors cross (module docstring)."""
    tri = np.asarray(mesh.triangles)
    faces = np.asarray(mesh.faces)
    hits, counts = mesh.triangles_tree.intersection_v(tri.min(axis=1), tri.max(axis=1))
    i, j = np.repeat(np.arange(len(tri)), counts.astype(np.int64)), hits.astype(np.int64)
    i, j = i[i < j], j[i < j]
    apart = ~(faces[i][:, :, None] == faces[j][:, None, :]).any(axis=(1, 2))
    i, j = i[apart], j[apart]
    crossed = np.zeros(len(i), dtype=bool)
    for one, other in ((i, j), (j, i)):
        for e in range(3):
            crossed |= _segment_crosses(tri[one, e], tri[one, (e + 1) % 3], tri[other])
    return int(crossed.sum())

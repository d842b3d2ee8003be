"""Printable plates: a heightmap as a watertight solid, written as binary STL (millimetres).

The plate's top is the heightmap's surface through the pixel centres (two triangles per cell),
raised so that its lowest point stands ``base_mm`` above the flat bottom at z = 0; vertical walls
close the four sides, and the bottom is a fan from its centre to the boundary vertices, so every
edge is shared by exactly two triangles. Triangles wind counter-clockwise seen from outside.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughness.core.checks import positive

from .heightmap import Heightmap

DEFAULT_BASE_MM = 2.0  # plate thickness below the texture's lowest point (mm)
STL_RECORD = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])


@dataclass(frozen=True)
class Plate:
    """A closed triangle mesh: vertices (n, 3) in mm and triangles (m, 3) as vertex indices."""

    vertices: np.ndarray
    triangles: np.ndarray


def plate(hm: Heightmap, base_mm: float = DEFAULT_BASE_MM) -> Plate:
    """The watertight plate of ``hm``: top surface, four walls and a flat bottom (mm)."""
    base_mm = positive("base_mm", base_mm)
    ny, nx = hm.shape
    x = (np.arange(nx) + 0.5) * hm.pixel_mm
    y = (np.arange(ny) + 0.5) * hm.pixel_mm
    gx, gy = np.meshgrid(x, y)
    top = np.column_stack([gx.ravel(), gy.ravel(), (hm.heights - hm.heights.min() + base_mm).ravel()])
    index = np.arange(ny * nx).reshape(ny, nx)
    a, b = index[:-1, :-1].ravel(), index[:-1, 1:].ravel()  # cell corners: a b (row i), c d (row i + 1)
    c, d = index[1:, :-1].ravel(), index[1:, 1:].ravel()
    top_triangles = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    ring = np.concatenate([index[0, :-1], index[:-1, -1], index[-1, :0:-1], index[:0:-1, 0]])  # counter-clockwise
    n_top, n_ring = len(top), len(ring)
    bottom = top[ring] * [1, 1, 0]
    centre = [[x.mean(), y.mean(), 0.0]]
    t, t_next = ring, np.roll(ring, -1)
    bt = n_top + np.arange(n_ring)
    bt_next = np.roll(bt, -1)
    walls = np.concatenate([np.column_stack([t, bt, bt_next]), np.column_stack([t, bt_next, t_next])])
    fan = np.column_stack([np.full(n_ring, n_top + n_ring), bt_next, bt])
    vertices = np.concatenate([top, bottom, centre])
    return Plate(vertices, np.concatenate([top_triangles, walls, fan]).astype(np.int64))


def stl_bytes(mesh: Plate) -> bytes:
    """Binary STL: an 80-byte header, the triangle count, one 50-byte record per triangle."""
    corners = mesh.vertices[mesh.triangles]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    records = np.zeros(len(corners), dtype=STL_RECORD)
    records["normal"], records["vertices"] = normals, corners
    header = b"roughness plate, units: mm".ljust(80, b" ")
    return header + np.uint32(len(records)).tobytes() + records.tobytes()

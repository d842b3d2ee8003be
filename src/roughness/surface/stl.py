"""Printable plates: a heightmap as a watertight solid, written as binary STL (millimetres).

The plate's top is the heightmap's surface through the pixel centres (two triangles per cell),
raised so that its lowest point stands ``base_mm`` above the flat bottom at z = 0; vertical walls
close the four sides, and the bottom is a fan from its centre to the boundary vertices, so every
edge is shared by exactly two triangles. Triangles wind counter-clockwise seen from outside. Every mesh written
is first checked as a reader will see it (``roughness.surface.solid``).
"""
from __future__ import annotations

import io
from collections.abc import Callable
from dataclasses import dataclass
from typing import BinaryIO

import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import SimulationError

from .heightmap import Heightmap
from .solid import SolidCheck, check_solid

DEFAULT_BASE_MM = 2.0  # plate thickness below the texture's lowest point (mm)
STL_RECORD = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
STL_CHUNK_FACES = 1_000_000
"""Faces packed at once when writing a binary STL (50 MB)."""


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
    """Binary STL of a plate, checked as written (``solid.check_solid``; SimulationError if it is not a closed solid,
    e.g. pixels so small beside the plate's coordinates that float32 corners weld together)."""
    require_solid(mesh.vertices, mesh.triangles, "the plate")
    out = io.BytesIO()
    write_stl(out, mesh.vertices, mesh.triangles, b"roughness plate, units: mm")
    return out.getvalue()


def require_solid(vertices: np.ndarray, faces: np.ndarray, what: str, precision: type = np.float32) -> SolidCheck:
    """The independent check of a mesh about to be written (``check_solid``); SimulationError naming its defects
    unless it is a closed solid: the product made it, so a defect is the product's failure, not bad input."""
    check = check_solid(vertices, faces, precision)
    if not check.closed:
        raise SimulationError(f"{what} was not written: it is {check.line()}")
    return check


def write_stl(f: BinaryIO, vertices: np.ndarray, faces: np.ndarray, header: bytes,
              progress: Callable[[float], object] | None = None) -> None:
    """Binary STL (mm) of ``faces`` over ``vertices`` to ``f``: an 80-byte header, the triangle count, one 50-byte
    record per triangle, packed STL_CHUNK_FACES at a time (``progress``: called with the fraction written after
    each chunk)."""
    f.write(header.ljust(80, b" ")[:80])
    f.write(np.uint32(len(faces)).tobytes())
    for start in range(0, len(faces), STL_CHUNK_FACES):
        corners = vertices[faces[start:start + STL_CHUNK_FACES]]
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
        records = np.zeros(len(corners), dtype=STL_RECORD)
        records["normal"], records["vertices"] = normals, corners
        f.write(records.tobytes())
        if progress is not None:
            progress(min(start + STL_CHUNK_FACES, len(faces)) / max(len(faces), 1))

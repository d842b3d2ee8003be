"""Read a textured mesh back as a heightmap: rays cast along -normal over a square grid in a plane."""
from __future__ import annotations

import math

import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, check_size
from roughness.surface.heightmap import Heightmap

from .mapping import axis_of

DEFAULT_REACH_MM = 10.0
"""How far above the plane the rays start (mm): the first surface below that height is the one read."""
CHUNK_FACES = 2_000_000
"""Faces projected at once."""
WINDOW = 6
"""Triangles spanning up to this many grid pixels are rasterised together; larger ones one by one."""


def sample_heightmap(textured, origin: object, normal: object, size_mm: float, pixel_mm: float,
                     reach_mm: float = DEFAULT_REACH_MM) -> Heightmap:
    """The heights (mm, along ``normal``, above the plane through ``origin``) of the first surface of ``textured``
    (a TexturedMesh or trimesh) met by rays cast along -``normal`` from ``reach_mm`` above the plane, over a square of
    ``size_mm`` centred on ``origin`` sampled at ``pixel_mm``. Pixel (i, j) lies at origin + (j + 0.5 - n/2) pixel
    e1 + (i + 0.5 - n/2) pixel e2, with (e1, e2, normal) the frame of ``Axis.frame``. InputError if a ray misses."""
    mesh = getattr(textured, "mesh", textured)
    size, pixel = positive("size_mm", size_mm), positive("pixel_mm", pixel_mm)
    reach = positive("reach_mm", reach_mm)
    n = math.ceil(size / pixel - 1e-9)
    check_size("pixels of the sampled heightmap", float(n) ** 2, MAX_HEIGHTMAP_PIXELS, "pixel_mm")
    best = first_hits(mesh, origin, normal, n, pixel, reach)
    if not np.all(np.isfinite(best)):
        missing = int((~np.isfinite(best)).sum())
        raise InputError(f"{missing:,} of {n * n:,} rays met no surface within {reach:g} mm above the plane: the "
                         "square does not lie over the mesh", parameter="origin")
    return Heightmap(best, pixel)


def first_hits(mesh, origin: object, normal: object, n: int, pixel_mm: float, reach_mm: float,
               up: object | None = None) -> np.ndarray:
    """(n, n) heights (mm along ``normal`` above the plane through ``origin``) of the first surface of ``mesh`` met
    by rays along -``normal`` from ``reach_mm`` above the plane, on the grid of ``sample_heightmap``; -inf where a
    ray meets nothing. ``up``: a direction (not along ``normal``) that rows should follow (e2), instead of the frame
    of ``Axis.frame``."""
    pixel, reach = pixel_mm, reach_mm
    o, e1, e2, a = axis_of(origin, normal).frame()
    if up is not None:
        e2 = np.asarray(up, dtype=float) - (np.asarray(up, dtype=float) @ a) * a
        e2 /= np.linalg.norm(e2)
        e1 = np.cross(e2, a)
    r = np.asarray(mesh.vertices, dtype=float) - o
    s, t, w = r @ e1, r @ e2, r @ a
    del r
    return highest_surface(s, t, w, np.asarray(mesh.faces), n, pixel, reach)


def highest_surface(s: np.ndarray, t: np.ndarray, w: np.ndarray, faces: np.ndarray, n: int, pixel_mm: float,
                    reach_mm: float) -> np.ndarray:
    """(n, n) heights ``w`` (mm), linear over each face of ``faces`` (indices into the per-vertex ``s``, ``t``, ``w``),
    of the highest surface at or below ``reach_mm`` over each point of an n x n grid of ``pixel_mm`` centred on
    s = t = 0 (pixel (i, j) at s = (j + 0.5 - n/2) pixel, t = (i + 0.5 - n/2) pixel); -inf where none is."""
    pixel, reach = pixel_mm, reach_mm
    half = n * pixel / 2
    best = np.full(n * n, -np.inf)
    for chunk in range(0, len(faces), CHUNK_FACES):
        f = faces[chunk:chunk + CHUNK_FACES]
        fs, ft, fw = s[f], t[f], w[f]
        near = ((fs.max(1) >= -half) & (fs.min(1) <= half) & (ft.max(1) >= -half) & (ft.min(1) <= half)
                & (fw.min(1) <= reach))
        fs, ft, fw = fs[near], ft[near], fw[near]
        c0 = np.clip(np.ceil((fs.min(1) + half) / pixel - 0.5), 0, n).astype(np.int64)
        c1 = np.clip(np.floor((fs.max(1) + half) / pixel - 0.5), -1, n - 1).astype(np.int64)
        r0 = np.clip(np.ceil((ft.min(1) + half) / pixel - 0.5), 0, n).astype(np.int64)
        r1 = np.clip(np.floor((ft.max(1) + half) / pixel - 0.5), -1, n - 1).astype(np.int64)
        span = np.maximum(c1 - c0, r1 - r0) + 1
        small = span <= WINDOW
        _raster(best, n, pixel, half, fs[small], ft[small], fw[small], c0[small], r0[small], c1[small], r1[small],
                WINDOW, reach)
        for k in np.flatnonzero(~small & (span > 0)):
            one = slice(k, k + 1)
            _raster(best, n, pixel, half, fs[one], ft[one], fw[one], c0[one], r0[one], c1[one], r1[one], int(span[k]),
                    reach)
    return best.reshape(n, n)


def _raster(best: np.ndarray, n: int, pixel: float, half: float, s: np.ndarray, t: np.ndarray, w: np.ndarray,
            c0: np.ndarray, r0: np.ndarray, c1: np.ndarray, r1: np.ndarray, window: int, reach: float) -> None:
    """Highest surface (w <= reach) under each grid point, for triangles whose boxes span <= ``window`` pixels."""
    for chunk in range(0, len(s), max(1, 4_000_000 // (window * window))):
        sl = slice(chunk, chunk + max(1, 4_000_000 // (window * window)))
        dj, di = np.meshgrid(np.arange(window), np.arange(window))
        col = c0[sl, None] + dj.ravel()[None, :]
        row = r0[sl, None] + di.ravel()[None, :]
        inside = (col <= c1[sl, None]) & (row <= r1[sl, None])
        ps = (col + 0.5) * pixel - half
        pt = (row + 0.5) * pixel - half
        s0, s1, s2 = s[sl, 0:1], s[sl, 1:2], s[sl, 2:3]
        t0, t1, t2 = t[sl, 0:1], t[sl, 1:2], t[sl, 2:3]
        det = (s1 - s0) * (t2 - t0) - (s2 - s0) * (t1 - t0)
        ok = np.abs(det) > 1e-15
        det = np.where(ok, det, 1.0)
        l1 = ((ps - s0) * (t2 - t0) - (s2 - s0) * (pt - t0)) / det
        l2 = ((s1 - s0) * (pt - t0) - (ps - s0) * (t1 - t0)) / det
        l0 = 1 - l1 - l2
        eps = -1e-9
        hit = inside & ok & (l0 >= eps) & (l1 >= eps) & (l2 >= eps)
        height = l0 * w[sl, 0:1] + l1 * w[sl, 1:2] + l2 * w[sl, 2:3]
        hit &= height <= reach
        np.maximum.at(best, (row * n + col)[hit], height[hit])

"""A 3MF file (3MF core specification 1.3, unit mm) written compactly and streamed: coordinates to 4 decimals (more
where rounding would break the mesh), triangles in space-filling-curve order, vertices numbered as the triangles first
use them.

A 3MF's mesh is XML text in a deflate-compressed zip. Written with every digit of a float64 (17 significant, as
trimesh writes them) a coordinate is noise to the compressor, and triangles in the order a decimator leaves them name
vertices scattered over the whole part. Rounded to 0.0001 mm (a vertex moves by at most ``ROUNDING_MM``, a hundredth
of a 0.01 mm tolerance and far under any printer's resolution), with neighbouring triangles written together and
naming nearby vertex numbers, the same surface packs to about half (a 3.1 M triangle knob: 78.7 MB by trimesh's
writer, 34.4 MB here; ``benchmarks/results/slicer_size.md``).

Rounding can break a mesh where a decimator left an edge shorter than the rounding (two corners onto one point, a
needle onto a line): those vertices alone (``solid.fragile_vertices``) take the next of ``DECIMALS`` until none is
left (``None``: every digit); the writer (``meshes.write_mesh``) then checks the whole mesh as rounded.
"""
from __future__ import annotations

import math
import zipfile
from collections.abc import Callable

import numpy as np

from roughness.surface.solid import fragile_vertices

DECIMALS = (4, 6, 9, None)
"""Decimals of a vertex's coordinates (mm) in the file, in the order tried (None: all 17 significant digits)."""
ROUNDING_MM = 0.5 * 10.0 ** -DECIMALS[0] * math.sqrt(3.0)
"""The most a vertex (so any point of a triangle) moves by rounding its three coordinates (mm; at the fewest
decimals, the most rounding)."""
CHUNK = 65_536
"""Vertices or triangles formatted at a time (also the progress step)."""
MORTON_BITS = 10
"""Cells per axis of the space-filling curve that orders the triangles: 2**MORTON_BITS across the part."""
COMPRESS_LEVEL = 6

MODEL = "3D/3dmodel.model"
CONTENT_TYPES = ('<?xml version="1.0" encoding="UTF-8"?>\n'
                 '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
                 '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
                 '<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
                 '</Types>\n')
RELS = ('<?xml version="1.0" encoding="UTF-8"?>\n'
        '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
        f'<Relationship Target="/{MODEL}" Id="rel0" '
        'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>\n')
MODEL_HEAD = ('<?xml version="1.0" encoding="UTF-8"?>\n'
              '<model unit="millimeter" xml:lang="en-US" '
              'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">'
              '<metadata name="Application">roughness</metadata>'
              '<resources><object id="1" type="model"><mesh><vertices>')
MODEL_MIDDLE = "</vertices><triangles>"
MODEL_TAIL = '</triangles></mesh></object></resources><build><item objectid="1"/></build></model>\n'


def ordered(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mesh (``vertices`` (n, 3) mm, ``faces`` (m, 3)) in the file's order: triangles along a space-filling
    curve, vertices renumbered in the order the triangles first name them (those no triangle names left out)."""
    vertices, faces = np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64)
    faces = faces[_curve_order(vertices[faces].mean(axis=1))]
    named = faces.ravel()
    _, first = np.unique(named, return_index=True)
    old_of_new = named[np.sort(first)]
    new_of_old = np.empty(len(vertices), dtype=np.int64)
    new_of_old[old_of_new] = np.arange(len(old_of_new))
    return vertices[old_of_new], new_of_old[faces]


def decimals_needed(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each vertex's decimals, as an index into ``DECIMALS``: the first, but for vertices that rounding to it would
    weld onto another or leave at a corner of a zero-area triangle, which take the next until none does (or every
    digit)."""
    level = np.zeros(len(vertices), dtype=np.int64)
    for _ in range(len(DECIMALS) - 1):
        fragile = fragile_vertices(rounded(vertices, level), faces) & (level < len(DECIMALS) - 1)
        if not fragile.any():
            break
        level[fragile] += 1
    return level


def rounded(vertices: np.ndarray, level: np.ndarray) -> np.ndarray:
    """``vertices`` (mm) as the file holds them, each to its ``DECIMALS[level]``."""
    out = np.array(vertices, dtype=float)
    for k, decimals in enumerate(DECIMALS):
        chosen = level == k
        if decimals is not None and chosen.any():
            out[chosen] = np.round(out[chosen], decimals)
    return out


def write_3mf(path: str, vertices: np.ndarray, faces: np.ndarray, level: np.ndarray,
              progress: Callable[[float], object] | None = None) -> None:
    """The 3MF of a mesh (``vertices`` (n, 3) mm, ``faces`` (m, 3), already ``ordered``) to ``path``, each vertex's
    coordinates to its ``DECIMALS[level]``, streamed a ``CHUNK`` at a time (``progress``: called with the fraction
    written after each)."""
    steps = max(math.ceil(len(vertices) / CHUNK) + math.ceil(len(faces) / CHUNK), 1)
    written = iter(range(1, steps + 1))

    def rows(model, array: np.ndarray, lines: list[str], which: np.ndarray | None = None) -> None:
        """``array``'s rows, each formatted by ``lines[which[row]]`` (``lines[0]`` if ``which`` is None)."""
        for start in range(0, len(array), CHUNK):
            chunk = array[start:start + CHUNK].tolist()
            picks = [0] * len(chunk) if which is None else which[start:start + CHUNK].tolist()
            model.write("".join(lines[k] % tuple(r) for r, k in zip(chunk, picks)).encode())
            if progress is not None:
                progress(next(written) / steps)

    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=COMPRESS_LEVEL) as z:
        z.writestr("[Content_Types].xml", CONTENT_TYPES)
        z.writestr("_rels/.rels", RELS)
        with z.open(MODEL, "w", force_zip64=True) as model:
            model.write(MODEL_HEAD.encode())
            numbers = ["%.17g" if d is None else f"%.{d}f" for d in DECIMALS]
            rows(model, vertices, [f'<vertex x="{n}" y="{n}" z="{n}"/>' for n in numbers], level)
            model.write(MODEL_MIDDLE.encode())
            rows(model, faces, ['<triangle v1="%d" v2="%d" v3="%d"/>'])
            model.write(MODEL_TAIL.encode())

def _curve_order(points: np.ndarray) -> np.ndarray:
    """The order of ``points`` (m, 3) along a Morton (Z-order) curve over their bounding box, ``MORTON_BITS`` per
    axis: points close in space come close in the order."""
    if not len(points):
        return np.zeros(0, dtype=np.int64)
    low, span = points.min(axis=0), float(np.ptp(points, axis=0).max())
    cells = (points - low) / max(span, 1e-300) * (2 ** MORTON_BITS - 1)
    code = np.zeros(len(points), dtype=np.uint64)
    for axis in range(3):
        code |= _spread(np.round(cells[:, axis]).astype(np.uint64)) << np.uint64(axis)
    return np.argsort(code, kind="stable")


def _spread(x: np.ndarray) -> np.ndarray:
    """The bits of ``x`` (< 2**10) spread to every third bit."""
    x = x & np.uint64(0x3FF)
    for shift, mask in ((16, 0x30000FF), (8, 0x300F00F), (4, 0x30C30C3), (2, 0x9249249)):
        x = (x | (x << np.uint64(shift))) & np.uint64(mask)
    return x

"""Is a triangle mesh, as it will be written, a closed solid? An independent check of every mesh the product writes.

The check sees the mesh the way a slicer reading the file does, not the way the code that built it does: corners
rounded to the file's precision (float32 in a binary STL), then welded where their coordinates are equal (an STL
has no shared vertices; a reader merges equal positions). It then counts:

- zero-area triangles: two corners welded together, or the three in a line within the rounding of the file's
  numbers (area below ``ZERO_AREA_ULPS`` units in the last place of the coordinates, times the longest edge);
- open edges (used by one triangle) and over-shared edges (by more than two): not manifold, not watertight;
- misoriented edges: two triangles that run a shared edge the same way (inconsistent winding).

A mesh with none of these is closed and consistently wound; ``SolidCheck.line`` says so, and only that check may say
so. Self-intersection is a separate check (``roughness.objects.intersections``), run by the texturing itself.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

ZERO_AREA_ULPS = 8.0
"""A triangle is zero-area if twice its area is below this many units in the last place of its largest coordinate,
times its longest edge: collinear corners rounded to the file's precision land within a few of them."""
CHUNK = 1_000_000
"""Triangles whose areas are computed at once (their corners in float64: 72 MB)."""


@dataclass(frozen=True)
class SolidCheck:
    """What the check found in a mesh (module docstring); counts of triangles and of welded edges."""

    triangles: int
    zero_area: int
    open_edges: int
    overshared_edges: int
    misoriented_edges: int
    precision: str  # the coordinates' type the check rounded to ("float32": binary STL)

    @property
    def closed(self) -> bool:
        """Watertight, manifold, consistently wound and without zero-area triangles."""
        return not (self.zero_area or self.open_edges or self.overshared_edges or self.misoriented_edges)

    def as_dict(self) -> dict:
        """JSON-ready, with the verdict (``closed``)."""
        return {**asdict(self), "closed": self.closed}

    def defects(self) -> list[str]:
        """Each defect found, in words (empty if closed)."""
        found = [(self.zero_area, "zero-area triangles"),
                 (self.open_edges, "open edges (used by one triangle: not watertight)"),
                 (self.overshared_edges, "edges shared by more than two triangles (not manifold)"),
                 (self.misoriented_edges, "edges whose two triangles run them the same way (inconsistent winding)")]
        return [f"{count:,} {what}" for count, what in found if count]

    def line(self) -> str:
        """The check's result in one line."""
        if self.closed:
            return (f"checked as written ({self.precision} corners, welded): closed, every edge shared by exactly two "
                    "triangles, consistently wound, no zero-area triangle")
        return f"NOT a closed solid as written ({self.precision} corners, welded): " + "; ".join(self.defects())


def check_solid(vertices: np.ndarray, faces: np.ndarray, precision: type = np.float32) -> SolidCheck:
    """Check ``faces`` (m, 3) over ``vertices`` (n, 3, mm) as a file of ``precision`` coordinates holds them."""
    faces = np.asarray(faces, dtype=np.int64)
    rounded = np.asarray(vertices, dtype=float).astype(precision) + precision(0)  # -0.0 -> 0.0, as readers compare
    welded = _weld(rounded)[faces]
    zero_area = sum(_zero_area(rounded[faces[s:s + CHUNK]], welded[s:s + CHUNK]) for s in range(0, len(faces), CHUNK))
    return SolidCheck(len(faces), zero_area, *_edge_defects(welded), np.dtype(precision).name)


def _weld(points: np.ndarray) -> np.ndarray:
    """An index per point (n, 3), equal for equal coordinates (as an STL reader merges them)."""
    bits = np.ascontiguousarray(points).view(np.uint32 if points.dtype.itemsize == 4 else np.uint64)
    order = np.lexsort(bits.T[::-1])
    ranked = bits[order]
    new = np.r_[True, np.any(ranked[1:] != ranked[:-1], axis=1)]
    index = np.empty(len(points), dtype=np.int64)
    index[order] = np.cumsum(new) - 1
    return index


def fragile_vertices(vertices: np.ndarray, faces: np.ndarray, precision: type = np.float64) -> np.ndarray:
    """Which vertices (a boolean mask) the file's ``precision`` welds onto another one or leaves at a corner of a
    zero-area triangle: where the mesh as written stops being the mesh (``vertices`` (n, 3) mm as the file holds
    them, ``faces`` (m, 3))."""
    faces = np.asarray(faces, dtype=np.int64)
    rounded = np.asarray(vertices, dtype=float).astype(precision) + precision(0)
    weld = _weld(rounded)
    fragile = np.bincount(weld, minlength=len(rounded))[weld] > 1
    for s in range(0, len(faces), CHUNK):
        part = faces[s:s + CHUNK]
        fragile[part[_zero_area_mask(rounded[part], weld[part])].ravel()] = True
    return fragile


def _zero_area(corners: np.ndarray, welded: np.ndarray) -> int:
    return int(np.count_nonzero(_zero_area_mask(corners, welded)))


def _zero_area_mask(corners: np.ndarray, welded: np.ndarray) -> np.ndarray:
    """Triangles (corners (m, 3, 3) at the file's precision) with welded corners, or collinear ones within the
    rounding of their coordinates."""
    c = corners.astype(float)
    twice_area = np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
    longest = np.linalg.norm(c[:, [1, 2, 0]] - c, axis=2).max(axis=1)
    ulp = np.spacing(np.abs(corners).max(axis=(1, 2))).astype(float)
    collapsed = (welded[:, 0] == welded[:, 1]) | (welded[:, 1] == welded[:, 2]) | (welded[:, 2] == welded[:, 0])
    return collapsed | (twice_area <= ZERO_AREA_ULPS * ulp * longest)


def _edge_defects(faces: np.ndarray) -> tuple[int, int, int]:
    """(open, over-shared, misoriented) undirected edges of ``faces`` (welded indices)."""
    a, b = faces.ravel(), np.roll(faces, -1, axis=1).ravel()
    keep = a != b  # a collapsed edge is counted as a zero-area triangle, not as an edge
    a, b = a[keep], b[keep]
    n = int(faces.max()) + 1 if faces.size else 1
    key = np.minimum(a, b) * n + np.maximum(a, b)
    forward = (a < b).astype(np.int64)
    order = np.argsort(key, kind="stable")
    key, forward = key[order], forward[order]
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    uses = np.diff(np.r_[starts, len(key)])
    forwards = np.add.reduceat(forward, starts) if len(key) else np.zeros(0, dtype=np.int64)
    return (int(np.count_nonzero(uses == 1)), int(np.count_nonzero(uses > 2)),
            int(np.count_nonzero((uses == 2) & (forwards != 1))))

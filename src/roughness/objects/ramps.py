"""How the texture's heights ramp to 0 at the borders of the textured faces: a smoothstep of the distance to the
nearest vertex on a border, and the width a concave sharp edge needs so that its two faces do not move into each
other."""
from __future__ import annotations

import math

import numpy as np

SMOOTHSTEP_SLOPE = 9 / 8
"""The largest s(t) / t of the smoothstep s(t) = t^2 (3 - 2 t) (at t = 3/4)."""
CONCAVE_RAMP_MARGIN = 4 / 3
"""Widening of the ramp at concave sharp edges beyond the exact bound (``concave_ramp_mm``), for the distance to
the nearest vertex on the edge being up to half an edge more than the distance to the edge's line."""

def ramp(vertices: np.ndarray, anchors: np.ndarray, where: np.ndarray, width_mm: float) -> np.ndarray | None:
    """Factors in [0, 1] for the heights at vertices ``where``: 0 on the ``anchors`` (bool per vertex), a
    smoothstep of the distance to the nearest anchor, 1 from ``width_mm`` on; None if there is no anchor or the
    width is 0."""
    if width_mm == 0 or not anchors.any():
        return None
    from scipy.spatial import cKDTree

    distance, _ = cKDTree(vertices[anchors]).query(vertices[where], distance_upper_bound=width_mm)
    t = np.clip(distance / width_mm, 0.0, 1.0)  # inf (beyond width_mm) -> 1
    return t * t * (3 - 2 * t)


def concave_ramp_mm(depth_mm: float, turn_deg: float) -> float:
    """The ramp width (mm) at a concave sharp edge whose faces' normals turn by ``turn_deg`` for a texture
    ``depth_mm`` deep. Each face moves along its own normal by h(x) at distance x from the edge; the two displaced
    faces cannot meet while each stays on its side of the plane bisecting the edge, h(x) < x tan(a / 2), a = 180 -
    turn the opening angle. With h = depth s(x / w) (a smoothstep) this holds for every x if w > depth (9/8) /
    tan(a / 2); the width returned is CONCAVE_RAMP_MARGIN times that."""
    opening = math.radians(180.0 - turn_deg) / 2
    return CONCAVE_RAMP_MARGIN * SMOOTHSTEP_SLOPE * depth_mm / max(math.tan(opening), 1e-9)

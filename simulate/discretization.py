"""Discretization error of V: two-level Richardson estimate, calibrated on the convergence panel.

V at contact spacing h is compared with V at a coarser spacing H of the same element order:

    error(V_h) ~ SAFETY * |V_h - V_H| / ((H / h)^ORDER - 1)        (absolute; relative: / V_h)

the Richardson estimate with an assumed order and a factor of safety, as in Roache's grid
convergence index. ORDER and SAFETY were chosen by measurement on the 24-texture panel
(studies/convergence_panel.py, studies/results/convergence_panel.md): with them the interval
V_h (1 +- error) holds the h = 0.1 mm reference for 22 of 24 textures at ``default`` and all 24 at
``fine``. The estimate assumes V_H and V_h lie in the asymptotic range (it fails when the two
levels agree by accident, as for an isolated dome whose rim neither mesh resolves) and that the
mesh error dominates the two levels' difference (they share the disk-pair sample, so the Monte
Carlo error largely cancels).
"""
from __future__ import annotations

import math

ORDER = 2.0  # assumed order of convergence of V in the contact spacing (observed 2-3 on the panel)
SAFETY = 1.25  # factor of safety on the Richardson estimate
# Contact spacings (mm) of the refinement ladder, coarsest first; a result's error is estimated
# against the next coarser rung (beyond the coarsest: 1.5 times its spacing).
LADDER_MM = (0.3, 0.2, 0.14, 0.1)
COARSER_RATIO = 1.5
# Below the standard scale V is judged in absolute terms: a relative tolerance applies to
# max(V, V_FLOOR). V_FLOOR is about V of the smoothest standard texture (lambda 0.625 mm: 0.033).
V_FLOOR = 0.03


def coarser_spacing(h_mm: float) -> float:
    """The spacing (mm) a result at ``h_mm`` is compared with: the next coarser ladder rung."""
    above = [h for h in LADDER_MM if h > h_mm * 1.2]
    return min(above) if above else round(COARSER_RATIO * h_mm, 6)


def richardson(v_fine: float, v_coarse: float, h_fine_mm: float, h_coarse_mm: float,
               order: float = ORDER, safety: float = SAFETY) -> float:
    """Estimated relative error of ``v_fine`` from the same quantity at a coarser spacing."""
    if not h_coarse_mm > h_fine_mm > 0:
        raise ValueError(f"need h_coarse > h_fine > 0, got {h_coarse_mm} and {h_fine_mm}")
    if v_fine == 0:
        return math.inf if v_coarse != 0 else 0.0
    return safety * abs(v_fine - v_coarse) / ((h_coarse_mm / h_fine_mm) ** order - 1) / abs(v_fine)


def within(v: float, relative_error: float, tolerance: float) -> bool:
    """Whether an estimated error meets ``tolerance``, relative to max(V, V_FLOOR)."""
    return relative_error * abs(v) <= tolerance * max(abs(v), V_FLOOR)

"""Footprint positions on a heightmap and the map of V over them, shared by every engine's roughness maps.

Positions are footprint centres from half a footprint inside one edge to half a footprint inside
the other (the whole map, wrapping, if ``tile``), ``step_mm`` apart.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.limits import MAX_MAP_POSITIONS, check_size
from roughness.core.reprs import shape_text, short_repr


@dataclass
class RoughnessMap:
    x_mm: np.ndarray  # footprint centres along x (columns)
    y_mm: np.ndarray  # footprint centres along y (rows)
    roughness: np.ndarray  # (len(y_mm), len(x_mm)) V
    in_domain: np.ndarray  # same shape, bool
    roughness_std: np.ndarray | None = None  # same shape, spread of V (ensemble models; None: a single network)

    def __repr__(self) -> str:
        s = self.summary()
        step = "" if s["step_mm"] is None else f"step {s['step_mm']:g} mm"
        return short_repr(self, f"{shape_text(self.roughness.shape)} positions", step,
                          f"V {s['roughness_min']:.4g}..{s['roughness_max']:.4g} (median {s['roughness_median']:.4g})",
                          f"{100 * s['in_domain_fraction']:.0f}% in domain")

    def summary(self) -> dict:
        v = self.roughness
        return {"positions": int(v.size), "step_mm": float(self.x_mm[1] - self.x_mm[0]) if len(self.x_mm) > 1 else None,
                "roughness_min": float(v.min()), "roughness_median": float(np.median(v)),
                "roughness_max": float(v.max()), "in_domain_fraction": float(self.in_domain.mean()),
                "roughness_std_median": None if self.roughness_std is None else float(np.median(self.roughness_std))}


def centres(size_mm: float, footprint_mm: float, step_mm: float, tile: bool) -> np.ndarray:
    """Footprint centres (mm) along a side of ``size_mm``, ``step_mm`` apart (``centre_count`` of them)."""
    if tile:
        return np.arange(0.0, size_mm, step_mm) + step_mm / 2
    span = size_mm - footprint_mm
    return footprint_mm / 2 + np.arange(0.0, span + 1e-9, step_mm) + (span % step_mm) / 2


def centre_count(size_mm: float, footprint_mm: float, step_mm: float, tile: bool) -> float:
    """How many ``centres`` there are (np.arange's length; inf if the step is too small to count in floats),
    computed without making them, to check the count first."""
    steps = (size_mm if tile else size_mm - footprint_mm + 1e-9) / step_mm
    return math.ceil(steps) if math.isfinite(steps) else math.inf


def map_positions(size_mm: tuple[float, float], footprint_mm: float, step_mm: float, tile: bool) -> int:
    """How many footprint positions a map of (width, height) ``size_mm`` has (``centres`` along x times along y),
    counted without making them; InputError (parameter ``step_mm``) above MAX_MAP_POSITIONS."""
    width, height = size_mm
    count = centre_count(width, footprint_mm, step_mm, tile) * centre_count(height, footprint_mm, step_mm, tile)
    return check_size(f"footprint positions on a {width:g} mm x {height:g} mm map in steps of {step_mm:g} mm", count,
                      MAX_MAP_POSITIONS, "step_mm")

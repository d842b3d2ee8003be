"""How densely a feel map samples an object: within a stated budget, so that a large part is mapped coarser, not
refused.

Two spacings are chosen from the areas (mm^2) alone, before anything is sampled:

- the surface samples (curvature at the footprint's scale, footprints on the surface): ``SAMPLE_SPACING_MM`` (0.4 mm),
  widened until the whole mesh holds at most ``MAX_SAMPLES`` of them (a 300 mm square plate: 0.85 mm). The curvature
  fit then still has about 100 samples within the footprint's 5 mm radius (it needs ``MIN_NEIGHBOURS``);
- the evaluation points: ``DEFAULT_SPACING_MM`` (5 mm, half a footprint) unless given, widened until the mapped area
  holds at most ``MAX_POINTS`` footprints (area / spacing^2: the points placed, one per cube of that side, can be a
  few % more) (a texture mapped onto the mesh, judged in tens of milliseconds each) or
  ``MAX_RELIEF_POINTS`` (a mesh's own relief, rasterised from its triangles: a second or two each). A spacing
  given explicitly is kept (up to MAX_MAP_POSITIONS: ``feel_map`` checks it).

Every widening is said in a note.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .curvature import SAMPLE_SPACING_MM

DEFAULT_SPACING_MM = 5.0  # half a footprint: neighbouring footprints overlap by half
MAX_SAMPLES = 250_000
"""Surface samples over the whole mesh (about 6 s to sample and index, 100 MB)."""
MAX_POINTS = 2_000
"""Footprints of a mapped texture judged (about a minute with the spectral engine)."""
MAX_RELIEF_POINTS = 200
"""Footprints of a mesh's own relief judged (a 30 mm knob textured to 3 million triangles: 4 minutes)."""


@dataclass(frozen=True)
class FeelBudget:
    """The spacings a feel map uses (mm) and notes on any widened to fit the budget."""

    sample_spacing_mm: float
    point_spacing_mm: float
    notes: tuple[str, ...] = ()


def feel_budget(mesh_area_mm2: float, mapped_area_mm2: float, spacing_mm: float | None = None,
                relief: bool = False) -> FeelBudget:
    """Spacings for a mesh of ``mesh_area_mm2`` whose ``mapped_area_mm2`` is mapped (module docstring);
    ``spacing_mm``: the evaluation points' spacing if given; ``relief``: the mesh's own relief is judged."""
    notes = []
    samples = max(SAMPLE_SPACING_MM, _rounded_up(math.sqrt(mesh_area_mm2 / MAX_SAMPLES)))
    if samples > SAMPLE_SPACING_MM:
        notes.append(f"surface samples {samples:g} mm apart (not {SAMPLE_SPACING_MM:g}): the mesh's "
                     f"{mesh_area_mm2:,.0f} mm^2 would take more than the budget of {MAX_SAMPLES:,} samples at "
                     f"{SAMPLE_SPACING_MM:g} mm")
    if spacing_mm is not None:
        return FeelBudget(samples, spacing_mm, tuple(notes))
    most = MAX_RELIEF_POINTS if relief else MAX_POINTS
    points = max(DEFAULT_SPACING_MM, _rounded_up(math.sqrt(mapped_area_mm2 / most)))
    if points > DEFAULT_SPACING_MM:
        notes.append(f"evaluation points {points:g} mm apart (not {DEFAULT_SPACING_MM:g}): the mapped "
                     f"{mapped_area_mm2:,.0f} mm^2 would take more than the budget of {most:,} footprints (area / spacing^2)"
                     f"{' of the mesh' + chr(39) + 's own relief' if relief else ''}; --spacing-mm sets it")
    return FeelBudget(samples, points, tuple(notes))


def _rounded_up(spacing_mm: float) -> float:
    """``spacing_mm`` rounded up to two significant figures (a spacing worth printing)."""
    if spacing_mm <= 0:
        return 0.0
    step = 10 ** (math.floor(math.log10(spacing_mm)) - 1)
    return math.ceil(spacing_mm / step - 1e-9) * step

"""Whether a decimated mesh feels as the full one does: both judged as they are (their own relief, ``relief``) by
``feel.feel_map`` at the same points, and V compared point by point in JNDs on the engine's standard scale.

The points are those of the full mesh's base (``relief.base_samples``: the mesh smoothed at 1 mm, which the
decimation, within micrometres, does not move): the same footprints are placed on both meshes, and only the relief
under them differs. Each point's change carries its uncertainty (both V's, ``perceptual_scale.jnd_distance``).
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError
from roughness.perceptual_scale import StandardScale, jnd_distance

from .feel import feel_map
from .feel_budget import feel_budget
from .relief import base_samples

SAME_FEEL_JND = 0.1
"""A decimated mesh feels the same if no point's V moves by more than this many JNDs (issue 41)."""


@dataclass(frozen=True)
class FeelChange:
    """V of the decimated mesh against the full one at the same ``points`` points (those judged on both): the
    largest and median absolute change (JND), the standard error of the largest (JND, from both V's), and the
    median V of the full mesh with its uncertainty."""

    points: int
    refused: int
    max_jnd: float
    max_jnd_stderr: float
    median_jnd: float
    median_v: float
    median_v_stderr: float
    spacing_mm: float

    @property
    def same(self) -> bool:
        """No point moved by more than SAME_FEEL_JND."""
        return self.max_jnd <= SAME_FEEL_JND

    def line(self) -> str:
        verdict = "feels the same" if self.same else "does NOT feel the same"
        return (f"feel: V of the decimated against the full mesh at {self.points} points {self.spacing_mm:g} mm apart "
                f"(as they are, the relief over the base): changes by {self.max_jnd:.3f} +/- {self.max_jnd_stderr:.3f} "
                f"JND at most (median {self.median_jnd:.3f}; V {self.median_v:.4g} +/- {self.median_v_stderr:.2g} median): "
                f"{verdict} (within {SAME_FEEL_JND:g} JND)"
                + (f"; {self.refused} points refused on either" if self.refused else ""))

    def as_dict(self) -> dict:
        return {**dataclasses.asdict(self), "same": self.same, "within_jnd": SAME_FEEL_JND}


def feel_change(full, decimated, spacing_mm: float | None = None, engine: str = "spectral",
                progress: Callable[[int, int], None] | None = None) -> FeelChange:
    """V of ``decimated`` against ``full`` (trimeshes, mm) at the same points, about ``spacing_mm`` apart (default:
    ``feel_budget``'s for a mesh's own relief) (module docstring); ``progress(done, total)`` over both maps.
    InputError (parameter ``spacing_mm``) if no footprint is judged on both."""
    from scipy.spatial import cKDTree

    budget = feel_budget(float(full.area), float(full.area), spacing_mm, relief=True)
    samples = base_samples(full, budget.sample_spacing_mm)
    nearest = cKDTree(decimated.triangles_center).query(samples.points)[1]
    on_decimated = dataclasses.replace(samples, faces=np.asarray(nearest, dtype=np.int64))
    maps = []
    for k, (mesh, s) in enumerate(((full, samples), (decimated, on_decimated))):
        told = None if progress is None else (lambda done, total, k=k: progress(k * total + done, 2 * total))
        maps.append(feel_map(mesh, None, spacing_mm=budget.point_spacing_mm, engine=engine, samples=s,
                             progress=told))
    a, b = maps
    both = np.flatnonzero(np.isfinite(a.roughness) & np.isfinite(b.roughness))
    if not len(both):
        raise InputError(f"no footprint {budget.point_spacing_mm:g} mm apart could be judged on both meshes (reasons on "
                         f"the full one: {'; '.join(sorted(set(a.reasons)))[:300]}): the part is too small or too "
                         "curved to compare how it feels", parameter="spacing_mm")
    scale: StandardScale = a.scale  # type: ignore[assignment]  # FeelMap keeps it untyped
    changes = [jnd_distance(scale, float(b.roughness[i]), float(a.roughness[i]), float(b.uncertainty[i]),
                            float(a.uncertainty[i])) for i in both]
    sizes = np.array([abs(c.jnd) if c.jnd is not None else 0.0 for c in changes])  # None: both below the scale
    worst = changes[int(np.argmax(sizes))]
    return FeelChange(len(both), len(a.roughness) - len(both), float(sizes.max()),
                      math.nan if worst.jnd_stderr is None else float(worst.jnd_stderr), float(np.median(sizes)),
                      float(np.median(a.roughness[both])), float(np.median(a.uncertainty[both])),
                      budget.point_spacing_mm)

"""Tune a texture so that it feels as wanted on the object's curved parts, not only as a flat plate.

The object's curvature changes how the texture feels (``feel``): on a convex knob it is rougher than flat. So the
flat target is moved by the object's own correction: the median V over the curved points of the map (those the
curvature study's correction applies to; all judged points where none is curved) over the flat tile's V as
``design.tune`` verifies it (at the tile's centre).
``design.tune`` then scales the texture (height or lateral size, spectral engine verifying) to that flat target,
the object is mapped again with the tuned texture, and while the curved parts' median misses the target by more
than ``tolerance_jnd`` the flat target is moved by the ratio of the target to the curved parts' median
(``MAX_ROUNDS``).

With a ``printer``, curvature and printer are corrected in one tune: every texture is judged as printed (the flat
tile by the evaluator's printer, the object's map with the tile printed before it is mapped: ``printed``), so the
tuned digital texture is the one whose print feels as wanted on the curved object.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from roughness.core.errors import InputError
from roughness.core.reprs import short_repr
from roughness.perceptual_scale import jnd
from roughness.surface.heightmap import Heightmap

from .feel import FeelMap, feel_map

MAX_ROUNDS = 3
FLAT_SHARE = 3  # the flat tune aims within tolerance / FLAT_SHARE, so its own error leaves room for the object's
TOLERANCE_JND = 0.1


@dataclass(frozen=True)
class ObjectResult:
    """The felt roughness on the object's curved parts: median V, its equivalent wavelength and JND from the target."""

    points: int  # curved points (or all mapped points where none is curved)
    curved: bool  # False: no point needed the correction, the median is over the flat points
    roughness: float
    lambda_mm: float
    jnd_error: float
    correction: float  # median V on the object / V flat over those points


@dataclass(frozen=True)
class ObjectTuneResult:
    heightmap: Heightmap  # the tuned texture
    flat: object  # design.tune's TuneResult: the flat texture's result
    on_object: ObjectResult
    feel: FeelMap  # the object's map with the tuned texture
    target_lambda_mm: float
    target_roughness: float
    rounds: int
    tolerance_jnd: float
    notes: tuple[str, ...] = field(default=())

    def __repr__(self) -> str:
        o = self.on_object
        return short_repr(self, f"{self.flat.by} x {self.flat.factor:.4g}", f"target lambda {self.target_lambda_mm:.3f} mm",
                          f"flat {self.flat_jnd_error:+.2f} JND", f"on the object {o.jnd_error:+.2f} JND",
                          "reached" if self.reached else "NOT reached", f"{self.rounds} round(s)")

    @property
    def reached(self) -> bool:
        return abs(self.on_object.jnd_error) <= self.tolerance_jnd

    @property
    def flat_jnd_error(self) -> float:
        """The tuned texture as a flat plate, in JND from the object's target (what tuning it flat would aim at)."""
        return jnd(self.flat.achieved.equivalent_lambda_mm, self.target_lambda_mm)

    def summary(self) -> dict:
        o = self.on_object
        return {"target_lambda_mm": self.target_lambda_mm, "target_roughness": self.target_roughness,
                "rounds": self.rounds, "reached": self.reached, "tolerance_jnd": self.tolerance_jnd,
                "flat": self.flat.summary(), "flat_jnd_from_target": self.flat_jnd_error,
                "on_object": {"points": o.points, "curved": o.curved, "roughness_median": o.roughness,
                              "lambda_median_mm": o.lambda_mm, "jnd_error": o.jnd_error, "correction": o.correction},
                "notes": list(self.notes)}


def object_result(feel: FeelMap, target_lambda_mm: float) -> ObjectResult:
    """The median felt roughness over the map's curved points (all judged points if none is curved)."""
    method = np.array(feel.method)
    curved = np.isin(method, ("corrected", "fem"))
    use = curved if curved.any() else np.isin(method, ("flat",))
    if not use.any():
        raise InputError("no footprint of the textured region could be judged (every point refused): nothing to tune "
                         "on this object", parameter="regions")
    v = float(np.median(feel.roughness[use]))
    lam = feel.scale.floored_lambda(v)
    judged = use & (feel.flat_roughness > 0)  # a zero flat V has no ratio
    ratio = float(np.median(feel.roughness[judged] / feel.flat_roughness[judged])) if judged.any() else math.nan
    return ObjectResult(int(use.sum()), bool(curved.any()), v, lam, jnd(lam, target_lambda_mm),
                        ratio)


def tune_on_object(mesh, texture: Heightmap, mapping_for: Callable[[Heightmap], object], target_lambda_mm: float,
                   regions: dict[str, np.ndarray] | None = None, by: str = "height", spacing_mm: float = 5.0,
                   tolerance_jnd: float = TOLERANCE_JND, progress: Callable[[str], None] | None = None,
                   printer=None, **tune_options) -> ObjectTuneResult:
    """Scale ``texture`` so that the object's curved parts feel like equivalent wavelength ``target_lambda_mm``
    (module docstring). ``mapping_for(heightmap)`` lays a texture on the object; the spectral engine judges and
    verifies throughout (its standard scale); ``printer`` (a ``PrintProfile``): judge every texture as printed."""
    from roughness.design.evaluation import Evaluator
    from roughness.design.tune import Target, tune

    from .printed import printed_mappings

    if printer is not None:
        mapping_for = printed_mappings(mapping_for, printer)
    evaluator = Evaluator(fidelity="spectral", printer=printer)
    scale = evaluator.scale
    target_v = scale.roughness_at(target_lambda_mm)
    flat_tile = evaluator.verify(texture, tile=True).roughness
    if not flat_tile > 0:
        raise InputError(f"the texture has no roughness to scale (V {flat_tile:.3g} as a flat tile, spectral engine): "
                         "tuning scales a texture's relief or size, so give one with relief", parameter="texture")
    feel = feel_map(mesh, mapping_for(texture), regions, spacing_mm, "spectral")
    before = object_result(feel, target_lambda_mm)
    if not before.roughness > 0:
        raise InputError("the texture has no roughness on the object's judged parts (V 0 under every footprint): "
                         "nothing to scale", parameter="texture")
    # the object's correction as tune sees the texture: the curved parts' median over the flat tile's V (at its
    # centre, as tune verifies it): curvature and the texture's own variation over the object together
    correction, notes = before.roughness / flat_tile, []
    if not before.curved:
        notes.append("no judged part of the object is curved enough to need the correction: tuned as flat")
    say = progress or (lambda message: None)
    as_printed = "" if printer is None else f" as printed by {printer.name}"
    say(f"as given{as_printed}, the curved parts feel like lambda {before.lambda_mm:.3f} mm ({before.jnd_error:+.2f} JND from the "
        f"target); the object's correction x {correction:.3f}")
    for rounds in range(1, MAX_ROUNDS + 1):
        flat_v = target_v / correction
        flat_target = Target(flat_v, scale.equivalent_lambda(flat_v)[0], "lambda")
        flat = tune(texture, flat_target, by, evaluator, tolerance_jnd=tolerance_jnd / FLAT_SHARE, tile=True,
                    **tune_options)
        feel = feel_map(mesh, mapping_for(flat.heightmap), regions, spacing_mm, "spectral")
        result = object_result(feel, target_lambda_mm)
        say(f"round {rounds}: flat target lambda {flat_target.lambda_mm:.3f} mm, {by} x {flat.factor:.4g}: on the "
            f"object{as_printed} lambda {result.lambda_mm:.3f} mm, {result.jnd_error:+.2f} JND from the target")
        if abs(result.jnd_error) <= tolerance_jnd or rounds == MAX_ROUNDS:
            break
        # the next flat target is this one moved by the object's miss: that takes out the object's correction at
        # the tuned scale and the flat tune's own error within its tolerance (which a correction over the flat
        # tile's achieved V leaves in, so the same flat target and the same miss would come back)
        correction = result.roughness / flat_target.roughness
    return ObjectTuneResult(flat.heightmap, flat, result, feel, target_lambda_mm, target_v, rounds, tolerance_jnd,
                            tuple(notes + list(flat.notes)))

"""How a slicer's fuzzy skin will feel: the printed wall (``roughness.surface.fuzzy_skin``) judged by ``predict``.

The wall is judged flat (a finger on a wall) as one period of a periodic texture (``tile``). The slicers draw new
random numbers at every slice, so one wall is one draw: a setting is judged on ``draws`` walls (seeds ``seed``,
``seed`` + 1, ...) and its V is their mean, sure to the larger of the spread over draws (standard deviation) and
the engine's own error (ensemble spread, Monte Carlo error), placed on the engine's standard scale.

On a cylinder (``radius_mm``: a round handle or knob, the wall curved along it; convex > 0, concave < 0) the flat
wall's V is corrected as ``predict --curvature-mm`` corrects a flat engine's answer (``curvature_correction``: the
curvature study's measured factor for a cylinder), and the correction's error joins V's uncertainty.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from roughness.curvature_correction import Correction, for_base, measured_ranges, restable
from roughness.perceptual_scale import Placement, load_scale
from roughness.prediction import Prediction, PredictOptions, predict
from roughness.surface.fuzzy_skin import FuzzySkin, FuzzyWall, fuzzy_wall
from roughness.surface.printing import FdmProfile, PrintProfile, printer_profile

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class FuzzyFeel:
    """The predicted feel of one fuzzy-skin setting on one printer, over several draws of the slicer's noise."""

    skin: FuzzySkin
    profile: FdmProfile
    walls: tuple[FuzzyWall, ...]
    predictions: tuple[Prediction, ...]  # one per wall, of the flat wall
    radius_mm: float | None = None  # a cylinder's signed radius (mm, convex > 0); None: a flat wall
    curvature: Correction | None = None  # the correction of the flat V on that cylinder

    @property
    def factor(self) -> float:
        """The curvature correction's factor on the flat wall's V (1 on a flat wall)."""
        return 1.0 if self.curvature is None else self.curvature.factor

    @property
    def roughness(self) -> float:
        """Mean V over the draws (corrected for a cylinder)."""
        return self.factor * sum(p.roughness for p in self.predictions) / len(self.predictions)

    @property
    def draw_std(self) -> float | None:
        """Standard deviation of V over the draws (None for one draw): how much one print differs from the next."""
        n = len(self.predictions)
        if n < 2:
            return None
        mean = self.roughness / self.factor
        return self.factor * math.sqrt(sum((p.roughness - mean) ** 2 for p in self.predictions) / (n - 1))

    @property
    def engine_error(self) -> float | None:
        """The largest error the engine gave a draw (Monte Carlo error or ensemble spread; None if it gave none)."""
        errors = [e for p in self.predictions for e in (p.roughness_stderr, p.roughness_std) if e is not None]
        return self.factor * max(errors) if errors else None

    @property
    def curvature_error(self) -> float | None:
        """The curvature correction's error in V (None on a flat wall)."""
        return None if self.curvature is None else self.roughness / self.factor * self.curvature.error

    @property
    def engines(self) -> tuple[str, ...]:
        """The engine (and fidelity) that answered each draw, once each."""
        return tuple(dict.fromkeys(_scale_name(p) for p in self.predictions))

    @property
    def placement(self) -> Placement | None:
        """The mean V on the standard scale of the engine that answered (None if draws were answered by different
        engines, whose scales differ)."""
        engines = self.engines
        return load_scale(engines[0]).place(self.roughness) if len(engines) == 1 else None

    @property
    def uncertainty(self) -> float | None:
        """How sure V is: the larger of the spread over draws and the engine's error, with a cylinder's correction
        error added in quadrature (None if none is known)."""
        known = [e for e in (self.draw_std, self.engine_error) if e is not None]
        flat = max(known) if known else None
        if self.curvature_error is None:
            return flat
        return math.hypot(flat or 0.0, self.curvature_error)

    @property
    def lambda_range_mm(self) -> tuple[float, float] | None:
        """Equivalent wavelengths (mm) of V -/+ its ``uncertainty`` on the standard scale (the lower end at the
        scale's floor if V - uncertainty is below it); None if V is not placed or its uncertainty unknown."""
        placement, sure = self.placement, self.uncertainty
        if placement is None or placement.below_scale or sure is None:
            return None
        scale = load_scale(self.engines[0])
        return scale.floored_lambda(max(self.roughness - sure, 0.0)), scale.equivalent_lambda(self.roughness + sure)[0]

    def as_dict(self) -> dict:
        placement = self.placement
        return {"fuzzy_skin": asdict(self.skin), "printer": self.profile.as_dict(),
                "seeds": [w.seed for w in self.walls], "tile_mm": self.walls[0].heightmap.size_mm[0],
                "roughness": self.roughness, "roughness_draw_std": self.draw_std, "engine_error": self.engine_error,
                "equivalent_lambda_range_mm": self.lambda_range_mm, "radius_mm": self.radius_mm,
                **({} if self.curvature is None else {"curvature_factor": self.curvature.factor,
                                                      "curvature_error": self.curvature_error,
                                                      "curvature_note": self.curvature.note}),
                "scales": list(self.engines), **({} if placement is None else placement.as_dict()),
                "draws": [p.as_dict() for p in self.predictions]}


def _scale_name(p: Prediction) -> str:
    """The standard scale a prediction was placed on: the spectral engine's, or the FEM fidelity's."""
    if p.engine == "spectral":
        return "spectral"
    return "fine" if p.fidelity == "converged" else p.fidelity


def fuzzy_skin_feel(skin: FuzzySkin, printer: PrintProfile | str = "fdm-0.4-0.2", engine: str = "auto",
                    seed: int = 0, draws: int = 3, tile_mm: float = 12.0, pixel_mm: float = 0.05,
                    radius_mm: float | None = None) -> FuzzyFeel:
    """The feel of ``skin`` printed by ``printer`` (a profile or its name) on ``draws`` walls (seeds ``seed``...):
    V, its uncertainty and its place on the standard scale, from ``engine`` (auto, surrogate, spectral, fem); on a
    cylinder of signed ``radius_mm`` (convex > 0) corrected as ``predict --curvature-mm`` does."""
    from roughness.core.checks import integer, real

    profile = printer_profile(printer) if isinstance(printer, str) else printer
    draws = integer("draws", draws, 1)
    curvature = None if radius_mm is None else cylinder(real("radius_mm", radius_mm))
    walls = tuple(fuzzy_wall(skin, profile, tile_mm, pixel_mm, seed + k) for k in range(draws))
    named = {f"{skin.describe()} (seed {w.seed})": w.heightmap for w in walls}
    predictions = predict(named, engine=engine, options=PredictOptions(tile=True))
    return FuzzyFeel(skin, walls[0].profile, walls, tuple(predictions), radius_mm, curvature)


def cylinder(radius_mm: float) -> Correction:
    """The curvature study's correction of a flat wall's V on a cylinder of signed radius (mm, convex > 0)."""
    from roughness.core.errors import InputError

    if radius_mm == 0:
        raise InputError("radius_mm is a signed radius (> 0 convex, < 0 concave); leave it out for a flat wall",
                         parameter="radius_mm")
    why = restable(1 / radius_mm, 0.0)
    if why:
        raise InputError(why, parameter="radius_mm")
    try:
        return for_base(radius_mm, "cylinder")
    except InputError:
        raise InputError(f"a cylinder of radius {radius_mm:g} mm is beyond the curvature study's measured range "
                         f"({measured_ranges()}): no measured correction for it", parameter="radius_mm") from None


def fuzzy_skin_sweep(skin: FuzzySkin, thicknesses_mm: Sequence[float], point_distances_mm: Sequence[float],
                     printer: FdmProfile | str = "fdm-0.4-0.2", engine: str = "auto", seed: int = 0, draws: int = 3,
                     tile_mm: float = 12.0, pixel_mm: float = 0.05, radius_mm: float | None = None,
                     on_result: Callable[[FuzzyFeel], None] | None = None) -> list[FuzzyFeel]:
    """``fuzzy_skin_feel`` of ``skin`` over thickness x point distance (mm), thickness outermost; ``on_result``
    is called with each as it is ready."""
    feels = []
    for thickness in thicknesses_mm:
        for distance in point_distances_mm:
            feel = fuzzy_skin_feel(replace(skin, fuzzy_skin_thickness=thickness, fuzzy_skin_point_distance=distance),
                                   printer, engine, seed, draws, tile_mm, pixel_mm, radius_mm)
            feels.append(feel)
            if on_result is not None:
                on_result(feel)
    return feels


def plot_sweep(feels: Sequence[FuzzyFeel], out: Path | None = None, ax: Axes | None = None) -> Figure:
    """V against point distance, one line per thickness, with V's uncertainty as error bars and the line width
    marked; on ``ax`` if given (its figure is returned), else on a new figure (saved to ``out`` if given)."""
    from roughness.core.figures import new_figure, save_figure

    own = ax is None
    fig = new_figure(figsize=(7, 4.5)) if own else ax.figure
    ax = fig.subplots() if own else ax
    for thickness in dict.fromkeys(f.skin.fuzzy_skin_thickness for f in feels):
        row = [f for f in feels if f.skin.fuzzy_skin_thickness == thickness]
        ax.errorbar([f.skin.fuzzy_skin_point_distance for f in row], [f.roughness for f in row],
                    yerr=[f.uncertainty or 0.0 for f in row], marker="o", ms=3, capsize=2, label=f"{thickness:g} mm")
    width = feels[0].profile.line_width_mm
    ax.axvline(width, color="grey", ls=":", lw=1)
    ax.annotate("line width", (width, 1), xycoords=("data", "axes fraction"), xytext=(3, -3),
                textcoords="offset points", color="grey", fontsize=8, va="top")
    engines = ", ".join(dict.fromkeys(e for f in feels for e in f.engines))
    ax.set(xlabel="fuzzy_skin_point_distance (mm)", ylabel=f"V ({engines} scale)",
           title=f"{feels[0].skin.fuzzy_skin_noise_type} fuzzy skin, {feels[0].profile.name}")
    ax.legend(title="thickness", fontsize=8)
    if own:
        fig.tight_layout()
    return save_figure(fig, out, 120)

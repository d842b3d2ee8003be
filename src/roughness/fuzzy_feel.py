"""How a slicer's fuzzy skin will feel: the printed wall (``roughness.surface.fuzzy_skin``) judged by ``predict``.

The wall is judged flat (a finger on a wall) as one period of a periodic texture (``tile``). V's uncertainty is
the engine's own (ensemble spread, Monte Carlo error), with the equivalent wavelength and JND on the engine's
standard scale (``Prediction.placement``). One wall is one draw of the slicer's random numbers.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, replace

from roughness.prediction import Prediction, PredictOptions, predict
from roughness.surface.fuzzy_skin import FuzzySkin, FuzzyWall, fuzzy_wall
from roughness.surface.printing import FdmProfile, PrintProfile, printer_profile


@dataclass(frozen=True)
class FuzzyFeel:
    """The predicted feel of one fuzzy-skin setting on one printer."""

    wall: FuzzyWall
    prediction: Prediction

    def as_dict(self) -> dict:
        return {"fuzzy_skin": asdict(self.wall.skin), "printer": self.wall.profile.as_dict(),
                "seed": self.wall.seed, "tile_mm": self.wall.heightmap.size_mm[0], **self.prediction.as_dict()}


def fuzzy_skin_feel(skin: FuzzySkin, printer: PrintProfile | str = "fdm-0.4-0.2", engine: str = "auto",
                    seed: int = 0, tile_mm: float = 12.0, pixel_mm: float = 0.05) -> FuzzyFeel:
    """The feel of ``skin`` printed by ``printer`` (a profile or its name): V, its uncertainty and its place on
    the standard scale, from ``engine`` (auto, surrogate, spectral, fem)."""
    profile = printer_profile(printer) if isinstance(printer, str) else printer
    wall = fuzzy_wall(skin, profile, tile_mm, pixel_mm, seed)
    name = skin.describe()
    (prediction,) = predict({name: wall.heightmap}, engine=engine, options=PredictOptions(tile=True))
    return FuzzyFeel(wall, prediction)


def fuzzy_skin_sweep(skin: FuzzySkin, thicknesses_mm: Sequence[float], point_distances_mm: Sequence[float],
                     printer: FdmProfile | str = "fdm-0.4-0.2", engine: str = "auto", seed: int = 0,
                     on_result: Callable[[FuzzyFeel], None] | None = None) -> list[FuzzyFeel]:
    """``fuzzy_skin_feel`` of ``skin`` over thickness x point distance (mm), thickness outermost; ``on_result``
    is called with each as it is ready."""
    feels = []
    for thickness in thicknesses_mm:
        for distance in point_distances_mm:
            feel = fuzzy_skin_feel(replace(skin, fuzzy_skin_thickness=thickness, fuzzy_skin_point_distance=distance),
                                   printer, engine, seed)
            feels.append(feel)
            if on_result is not None:
                on_result(feel)
    return feels

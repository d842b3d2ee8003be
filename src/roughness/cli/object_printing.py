"""--printer in the `roughness object` actions: what the printer keeps of the texture, as flat V digital beside
printed (the texture tile printed periodically, both answered by the surrogate as `roughness predict` does)."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TexturePrint:
    """The texture tile digital and as printed by ``result.profile`` (``result``: its ``PrintResult``), with the
    surrogate's flat ``Prediction`` of each."""

    result: object  # PrintResult
    digital: object  # Prediction
    printed: object  # Prediction

    def difference(self):
        """The ``PrintDifference`` of the two V."""
        from .printer import PrintDifference

        return PrintDifference(self.digital.roughness, self.printed.roughness,
                               self.digital.placement.equivalent_lambda_mm, self.printed.placement.equivalent_lambda_mm)

    def lines(self) -> list[str]:
        """The texture's V as printed (PROFILE) with digital beside it, how sure each is, and the print's steps."""
        name = self.result.profile.name
        return [f"texture as printed ({name}), flat: {_v(self.printed)}; digital: {_v(self.digital)}",
                f"  printer {self.result.profile.describe()}: {self.difference().describe()}",
                *(f"  print: {step}" for step in self.result.steps),
                *(f"  print note: {note}" for note in self.result.notes)]

    def as_dict(self) -> dict:
        return {**self.result.as_dict(), "digital": self.digital.as_dict(), "printed": self.printed.as_dict(),
                "difference": self.difference().as_dict()}


def texture_print(texture, profile, surface_pixel_mm: float | None = None) -> TexturePrint:
    """The texture tile (a ``Heightmap``, periodic) at its pixel on the surface (``surface_pixel_mm``, mm: a
    mapping's stretch; default its own) printed by ``profile``, and both V, flat (InputError naming --printer if
    the pixel is too coarse for the printer)."""
    from roughness.prediction import PredictOptions, predictions
    from roughness.surface.heightmap import Heightmap
    from roughness.surface.printing import printed

    laid = texture if surface_pixel_mm is None else Heightmap(texture.heights, surface_pixel_mm)
    result = printed(laid, profile, periodic=True)
    digital, as_printed = predictions([("texture", laid), ("texture printed", result.heightmap)], "surrogate",
                                      None, PredictOptions(tile=True))
    return TexturePrint(result, digital, as_printed)


def _v(p) -> str:
    """V of a prediction with how sure it is (ensemble spread when the model has one) and its domain."""
    from roughness.prediction import domain_words

    sure = f" ± {p.roughness_std:.4f} (ensemble spread)" if p.roughness_std is not None else " (no error estimate)"
    return f"V = {p.roughness:.4f}{sure} ({p.engine}, {domain_words(p)})"

"""The Object page's printer, as ``--printer`` in `roughness object feel` and `object texture`: the feel map of the
printed object with the digital object's beside it, and the texture's V as printed beside digital for the
full-resolution mesh (whose default edge ``objects.print_plan.chosen_edge`` takes from the printer).

The same library calls as the commands: ``objects.printed.printed_tile`` prints the tile at its pixel on the
surface before ``objects.feel.feel_map`` maps it, ``cli.object_feel.map_lines`` words the map,
``cli.object_printing.texture_print`` answers for the tile flat.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from roughness.cli.object_feel import PrintedFeel, map_lines
from roughness.objects.feel import FeelMap
from roughness.surface.heightmap import Heightmap
from roughness.surface.printing import PrintProfile

Judge = Callable[[object, float, str], FeelMap]
"""``judge(mapping, start, what)``: the object's feel map with the texture laid by ``mapping``, its progress
reported from ``start`` (0..1) as ``what``."""


@dataclass(frozen=True)
class ObjectFeel:
    """The feel map the page shows (of the printed object if a printer was chosen) and, with a printer, the tile's
    print and the digital object's map (``printing``)."""

    feel: FeelMap
    printing: PrintedFeel | None = None

    def lines(self, mesh: str) -> list[str]:
        """The map in the command's words (``map_lines``)."""
        return map_lines(self.feel, mesh, self.printing)

    def shows(self) -> str:
        """What the coloured map is of, in words."""
        return "the object" if self.printing is None else f"the object as printed by {self.printing.result.profile.name}"


def printed_feel(texture: Heightmap, mapping, mapping_of: Callable[[Heightmap], object], profile: PrintProfile,
                 judge: Judge) -> ObjectFeel:
    """The map of the object as ``profile`` prints ``texture`` (its tile printed at its pixel on the surface,
    ``mapping.pixel_mm``; InputError first if too coarse for the printer), laid by ``mapping_of``; the digital
    object (laid by ``mapping``) judged before it, as `object feel --printer` does."""
    from roughness.objects.printed import printed_tile

    result = printed_tile(texture, profile, mapping.pixel_mm)
    digital = judge(mapping, 0.0, "the digital object")
    printed = judge(mapping_of(result.heightmap), 0.5, f"the object as printed by {profile.name}")
    return ObjectFeel(printed, PrintedFeel(result, digital))


def print_lines(texture: Heightmap, profile: PrintProfile | None, surface_pixel_mm: float) -> tuple[str, ...]:
    """`object texture --printer`'s report: the tile's flat V as printed beside digital, each with its ensemble
    spread, and the print's steps (empty without a printer; InputError if the pixel on the surface, mm, is too
    coarse for the printer)."""
    from roughness.cli.object_printing import texture_print

    return () if profile is None else tuple(texture_print(texture, profile, surface_pixel_mm).lines())

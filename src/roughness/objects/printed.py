"""The texture of an object as a printer makes it: the periodic tile printed at the size it has on the surface,
before it is mapped on the object (so the feel map, the tune and the table are of the printed object).

The printer works in mm on the object, so a tile a mapping stretches (a wrap fitting whole tiles around, a UV
scale) is printed at its stretched pixel (``mapping.pixel_mm``), then handed back at the texture's own pixel for
the mapping to stretch as before. Printing the tile, not the curved surface, models the printer as it prints a
flat plate texture up (``roughness.surface.printing``): layer steps on a curved or tilted surface (the staircase
of a slope) are not modelled.
"""
from __future__ import annotations

from collections.abc import Callable

from roughness.surface.heightmap import Heightmap
from roughness.surface.printing import PrintProfile, PrintResult, printed


def printed_tile(texture: Heightmap, profile: PrintProfile, surface_pixel_mm: float | None = None) -> PrintResult:
    """``texture`` (a periodic tile) printed by ``profile`` at ``surface_pixel_mm`` (mm: its pixel on the surface;
    default its own), the printed heightmap at the texture's own pixel (InputError if the pixel is too coarse for
    the printer)."""
    pixel = texture.pixel_mm if surface_pixel_mm is None else surface_pixel_mm
    result = printed(Heightmap(texture.heights, pixel), profile, periodic=True)
    return PrintResult(Heightmap(result.heightmap.heights, texture.pixel_mm), result.profile, result.steps,
                       result.notes)


def printed_mappings(mapping_for: Callable[[Heightmap], object],
                     profile: PrintProfile) -> Callable[[Heightmap], object]:
    """``mapping_for`` (a texture -> its mapping on the object) laying each texture as ``profile`` prints it."""
    def lay(texture: Heightmap):
        digital = mapping_for(texture)
        return mapping_for(printed_tile(texture, profile, digital.pixel_mm).heightmap)

    return lay

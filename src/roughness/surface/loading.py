"""One input file to a Heightmap, as every command that reads heightmaps loads it, and the record of it.

The steps, in order, each recorded in ``Loaded``:

1. read (``io.read_heights``: the formats of io and the scans of SurfaceTopography), missing
   points kept as NaN;
2. units: what the file states (a scan's units, a TIFF's resolution tags, the tool's own
   metadata), else the units given for this file (``FILE:pixel-mm=..,height-mm=..``), else the
   command's (``--pixel-mm``, ``--height-mm``); a given unit that contradicts the file's is
   refused, except that with several inputs a given height is for the inputs that hold grey
   levels (files that hold mm, scans among them, keep theirs, noted);
3. non-square pixels resampled to square if asked (``resample_square``), else refused;
4. clean-up (roughness.surface.cleanup: fill, despike, level), each step only when asked;
5. size and unit check, on the map the engines will see (holes filled, spikes out, tilt off, so
   none of them sways the relief), before any engine work: a scan, whose units its file states,
   narrower than 1 mm is refused as too small to feel (roughness.surface.tiling.check_touchable),
   not as a unit mistake; then the plausibility of the numbers as mm (roughness.surface.units);
6. tiling check (roughness.surface.tiling) where the map will be tiled under a footprint.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

from .cleanup import Cleaned, Cleanup, clean
from .heightmap import Heightmap
from .io import Reading, read_heights
from .tiling import TileFit, check_tile, check_touchable
from .units import FileUnits, Plausibility, check_units


@dataclass(frozen=True)
class Loaded:
    """What loading did to one input file: how it was read (format, units, pixel size, resampling), the
    clean-up steps, what the unit check saw, and the measures of a patch tiled under a larger footprint."""

    reading: Reading
    cleaned: Cleaned
    units: Plausibility
    tile: TileFit | None = None

    def lines(self, tile: bool = True) -> list[str]:
        """The record in words, each naming the file; ``tile``: with the tiled patch's notes (else the caller
        shows them, e.g. as reasons for an answer out of domain)."""
        path = self.reading.path
        steps = [f"{path}: {line}" for line in self.cleaned.lines()]
        tiling = [f"{path}: {note}" for note in self.tile.notes()] if self.tile and tile else []
        return [*self.reading.notes, *steps, *tiling]

    def as_dict(self) -> dict:
        """The record for JSON output (the key ``readings`` of every command's JSON)."""
        return {**self.reading.as_dict(), "steps": self.cleaned.as_dict(), "units": asdict(self.units),
                "tile": None if self.tile is None else asdict(self.tile) | {"notes": self.tile.notes()},
                "notes": self.lines()}


def load_surface(path: str | Path, units: FileUnits = FileUnits(), resample_square: bool = False,
                 spec: Cleanup = Cleanup(), units_ok: bool = False, several: bool = False,
                 dataset: str | None = None, tile_footprint_mm: float | None = None) -> tuple[Heightmap, Loaded]:
    """The heightmap of one input file after the steps of the module docstring, and their record.

    ``units``: the pixel size and full-scale height (mm) to use where the file states none;
    ``several``: the command reads other inputs too, so ``units.height_mm`` applies only where this file's heights
    need it (grey levels; a file that holds mm keeps its heights, noted);
    ``tile_footprint_mm``: the map will be tiled under a footprint of this side (mm), so a patch smaller than
    it is measured as a tile.
    """
    heights, reading = read_heights(path, units.pixel_mm, units.height_mm, dataset, resample_square,
                                    height_for_others=several)
    hm, cleaned = clean(heights, reading.pixel_mm, spec, reading.path)
    if reading.unit is not None:  # a scan states its units: a tiny one is tiny, not in metres
        check_touchable(hm, reading.path)
    found = check_units(hm, reading.path, units_ok, reading.unit)
    tile = None if tile_footprint_mm is None else check_tile(hm, reading.path, tile_footprint_mm)
    return hm, Loaded(reading, cleaned, found, tile)

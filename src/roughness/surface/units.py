"""Are a heightmap's numbers millimetres? A plausibility check of relief, slope and pixel size.

A touchable texture in mm has a relief (peak to valley) and an RMS slope within what a
fingertip can feel and the model answers for. The product's own textures (dataset.textures,
dataset.natural at their parameter ranges, 0.05 mm pixels) span relief 0.05 to 1.6 mm and RMS
slope 0.017 (fBm, RMS 0.02 mm, Hurst 0.9) to 7.2 (a 1 mm square grating of period 0.3 mm).
The bounds below sit about ten times outside that span on each side, so a map in metres (all
numbers 1000 times smaller) or micrometres (1000 times larger) falls outside at least one of
them, while any texture the product makes or a plausible scan of one falls inside:

- metres: a 1 mm texture reads as 0.001 mm relief and slope ~0.001; the issue's "all heights
  below 1e-4 mm" would miss it (only textures under 0.1 mm real relief fall below 1e-4 in metres).
- micrometres: a 0.05 mm texture reads as 50 mm relief; slopes of 17 to 7,000.
- the pixel size: below 1e-4 mm (0.1 um, finer than optical profilers resolve) or above 1 mm
  (no feature under the 10 mm fingertip footprint resolved).

A flat map (no relief) says nothing about its unit and passes. ``units_ok`` confirms numbers
that fail the check (e.g. a polished sample with 1 um of relief, in mm).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError

from .heightmap import TOLERANCE_MM, Heightmap

MIN_RELIEF_MM = 5e-3  # peak to valley; the product's textures: 0.05 .. 1.6 mm
MAX_RELIEF_MM = 20.0
MIN_RMS_SLOPE = 1.7e-3  # the product's textures: 0.017 .. 7.2
MAX_RMS_SLOPE = 100.0
MIN_PIXEL_MM = 1e-4
MAX_PIXEL_MM = 1.0
CONFIRM = "units_ok"  # the parameter (flag --units-ok) that confirms implausible numbers are mm


@dataclass(frozen=True)
class Plausibility:
    """A map's relief (mm, peak to valley), RMS slope (dimensionless) and pixel size (mm)."""

    relief_mm: float
    rms_slope: float
    pixel_mm: float

    def problems(self) -> list[tuple[str, str]]:
        """(what is implausible, what it suggests) for each bound the map falls outside. A slope outside
        its bounds is put down to the heights only when the pixel size is plausible (else to the pixel)."""
        out = []
        pixel_off = not MIN_PIXEL_MM <= self.pixel_mm <= MAX_PIXEL_MM
        if self.pixel_mm < MIN_PIXEL_MM:
            out.append((f"pixel size {self.pixel_mm:.3g} mm is below {MIN_PIXEL_MM:g} mm", "pixel size in metres"))
        if self.pixel_mm > MAX_PIXEL_MM:
            out.append((f"pixel size {self.pixel_mm:.3g} mm is above {MAX_PIXEL_MM:g} mm",
                        "pixel size in micrometres"))
        if self.relief_mm <= TOLERANCE_MM:  # a flat map says nothing about its heights' unit
            return out
        if self.relief_mm < MIN_RELIEF_MM:
            out.append((f"relief {self.relief_mm:.3g} mm is below {MIN_RELIEF_MM:g} mm", "heights in metres"))
        if self.relief_mm > MAX_RELIEF_MM:
            out.append((f"relief {self.relief_mm:.3g} mm is above {MAX_RELIEF_MM:g} mm", "heights in micrometres"))
        if self.rms_slope < MIN_RMS_SLOPE and not pixel_off:
            out.append((f"RMS slope {self.rms_slope:.3g} is below {MIN_RMS_SLOPE:g}",
                        "heights in metres (or a pixel size in micrometres)"))
        if self.rms_slope > MAX_RMS_SLOPE and not pixel_off:
            out.append((f"RMS slope {self.rms_slope:.3g} is above {MAX_RMS_SLOPE:g}",
                        "heights in micrometres (or a pixel size in metres)"))
        return out


def plausibility(hm: Heightmap) -> Plausibility:
    """Relief, RMS slope (np.gradient at the map's pixel size) and pixel size of ``hm``."""
    gy, gx = np.gradient(hm.heights, hm.pixel_mm)
    return Plausibility(float(np.ptp(hm.heights)), math.sqrt(float(np.mean(gx**2 + gy**2))), hm.pixel_mm)


def check_units(hm: Heightmap, source: str, units_ok: bool = False, stated_unit: str | None = None) -> Plausibility:
    """``hm``'s plausibility, or InputError (parameter ``units_ok``) naming the likely unit unless ``units_ok``;
    ``stated_unit``: the length unit the file states (a scan), so the numbers are the surface's, not a unit guess."""
    found = plausibility(hm)
    problems = found.problems()
    if problems and not units_ok and stated_unit is not None:
        raise InputError(
            f"{source}: {'; '.join(what for what, _ in problems)}: implausible for a touchable texture in mm (the "
            f"bounds lie 10 times beyond the product's textures; see roughness.surface.units). The file states its "
            f"unit ({stated_unit}{'' if stated_unit == 'mm' else ', converted to mm'}), so these are the surface's own "
            f"numbers, not a unit mistake: pass {CONFIRM} to judge it anyway", parameter=CONFIRM)
    if problems and not units_ok:
        units = list(dict.fromkeys(unit for _, unit in problems))
        likely = "; ".join(u for u in units if not any(u != v and u.startswith(v) for v in units))  # one reading
        raise InputError(
            f"{source}: {'; '.join(what for what, _ in problems)}: implausible for a touchable texture in mm "
            f"(the bounds lie 10 times beyond the product's textures; see roughness.surface.units). It looks like "
            f"{likely}: convert the file to mm (metres x 1000, micrometres / 1000; a pixel size can be given as "
            f"pixel_mm=MM or FILE:pixel-mm=MM), or pass {CONFIRM} if the numbers really are mm", parameter=CONFIRM)
    return found


FILE_UNIT_KEYS = {"pixel-mm": "pixel_mm", "height-mm": "height_mm"}


@dataclass(frozen=True)
class FileUnits:
    """The units given for one input file (mm; None: not given here)."""

    pixel_mm: float | None = None
    height_mm: float | None = None

    def over(self, pixel_mm: float | None, height_mm: float | None) -> FileUnits:
        """These units where given, else the command's (``--pixel-mm``, ``--height-mm``)."""
        return FileUnits(pixel_mm if self.pixel_mm is None else self.pixel_mm,
                         height_mm if self.height_mm is None else self.height_mm)


def split_input(text: str) -> tuple[str, FileUnits]:
    """``FILE`` or ``FILE:pixel-mm=P,height-mm=H`` (either key, each at most once, in any order) as the path and its
    units.

    An existing path is always taken whole (a file whose name has a colon); otherwise the part
    after the last colon is units if it is ``key=value`` pairs, and an InputError names a bad one.
    """
    path, colon, tail = text.rpartition(":")
    if not colon or "=" not in tail or _exists(text):
        return text, FileUnits()
    values: dict[str, float] = {}
    for pair in tail.split(","):
        key, _, value = pair.partition("=")
        if key not in FILE_UNIT_KEYS:
            raise InputError(f"{text}: unknown unit {key!r} after the colon; expected FILE:pixel-mm=MM,height-mm=MM")
        if FILE_UNIT_KEYS[key] in values:
            raise InputError(f"{text}: {key} is given twice after the colon; give each unit once")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not (math.isfinite(number) and number > 0):
            raise InputError(f"{text}: {key} must be a positive finite number of mm, got {value!r}")
        values[FILE_UNIT_KEYS[key]] = number
    return path, FileUnits(**values)


def _exists(text: str) -> bool:
    from pathlib import Path

    return Path(text).exists()

"""A tactile plate checked against the tactile-graphics guidelines: each rule, pass or fail, and where.

Rules and their sources:

- at most ``MAX_TEXTURES`` area textures in one graphic (BANA/CBA *Guidelines and Standards for Tactile Graphics*,
  2010, as summarised in the tactile-graphics design considerations: "no more than 5 different textures");
- every textured area at least ``readability.MIN_TEXTURE_WIDTH_MM`` across (tactilegraphics.org, "Keys to
  readability" 1);
- neighbouring regions (sharing an edge or a line) at least ``min_jnd`` apart on the plate's roughness map, as
  printed when a printer is given (this tool's measure of "adjacent textures significantly different"); a flat
  region counts as the standard scale's floor, the smoothest the scale tells apart, and so does a texture below it;
- raised lines ``MIN_LINE_WIDTH_MM`` to ``MAX_LINE_WIDTH_MM`` wide and at least ``MIN_LINE_HEIGHT_MM`` high (Round
  Table guidelines for 3D-printed models, 1.5);
- separate raised lines (their bars as made), and a braille label and its sample, at least ``MIN_SPACING_MM``
  apart (tactilegraphics.org, "Keys to readability" 2: 1/8 inch between any two elements).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from roughness.perceptual_scale import jnd

from .colours import hex_colour
from .key import LABEL_GAP_MM
from .layout import FLAT
from .readability import MIN_TEXTURE_WIDTH_MM

MAX_TEXTURES = 5
MIN_LINE_WIDTH_MM, MAX_LINE_WIDTH_MM = 1.1, 3.0
MIN_LINE_HEIGHT_MM = 0.5  # a faint line; 1 mm a definite one
MIN_SPACING_MM = 3.175  # 1/8 inch


@dataclass(frozen=True)
class Check:
    """One rule: whether the plate passes it, the value found, and where it fails."""

    rule: str
    passed: bool
    value: str
    where: str = ""

    def describe(self) -> str:
        return f"{'PASS' if self.passed else 'FAIL'} {self.rule}: {self.value}" + (f" ({self.where})" if self.where
                                                                                   else "")

    def as_dict(self) -> dict:
        return {"rule": self.rule, "passed": self.passed, "value": self.value, "where": self.where}


def check_plate(plate, min_jnd: float = 2.0) -> list[Check]:
    """The guideline checks of a ``TactilePlate`` (module docstring); ``min_jnd``: the neighbours' least distance."""
    checks = [_texture_count(plate), _region_size(plate), _contrast(plate, min_jnd)]
    layout = plate.layout
    if layout is not None and plate.line_mask is not None and layout.lines.colours:
        checks += _lines(plate)
    if plate.key:
        checks.append(Check(f"braille label >= {MIN_SPACING_MM:g} mm from its sample", LABEL_GAP_MM >= MIN_SPACING_MM,
                            f"{LABEL_GAP_MM:g} mm"))
    return checks


def _texture_count(plate) -> Check:
    textures = sorted({r.texture for r in plate.regions if r.texture != FLAT})
    return Check(f"at most {MAX_TEXTURES} area textures", len(textures) <= MAX_TEXTURES, f"{len(textures)}")


def _region_size(plate) -> Check:
    small = plate.small_areas
    where = "; ".join(f"{a.colour} at ({a.centre_mm[0]:.0f}, {a.centre_mm[1]:.0f}) mm: {a.width_mm:.1f} mm"
                      for a in small[:5]) + ("; ..." if len(small) > 5 else "")
    return Check(f"textured areas >= {MIN_TEXTURE_WIDTH_MM:g} mm across", not small,
                 f"{len(small)} narrower" if small else "all wide enough", where)


def _contrast(plate, min_jnd: float) -> Check:
    labels = plate.labels
    pairs = set()
    for a, b in ((labels[:, 1:], labels[:, :-1]), (labels[1:], labels[:-1])):
        touch = (a != b) & (a >= 0) & (b >= 0)
        pairs |= {tuple(sorted(p)) for p in np.unique(np.stack([a[touch], b[touch]], axis=1), axis=0).tolist()}
    lam = plate.felt_lambdas_mm("plate")
    worst, closest, failing, unmeasured = np.inf, "", [], []
    for i, j in sorted(pairs):
        name = f"{hex_colour(plate.regions[i].colour)}/{hex_colour(plate.regions[j].colour)}"
        if lam[i] is None or lam[j] is None:
            unmeasured.append(name)
            continue
        d = abs(jnd(lam[i], lam[j]))
        if d < worst:
            worst, closest = d, name
        if d < min_jnd:
            failing.append(f"{name} {d:.2f} JND")
    value = f"closest neighbours {closest} {worst:.2f} JND" if np.isfinite(worst) else "no neighbours measured"
    where = "; ".join(failing + [f"{n} not measured (no footprint fits)" for n in unmeasured])
    return Check(f"neighbours >= {min_jnd:g} JND apart on the plate", not failing and not unmeasured, value, where)


def _lines(plate) -> list[Check]:
    from .lines import line_relief

    style = plate.layout.style
    checks = [Check(f"line width {MIN_LINE_WIDTH_MM:g}-{MAX_LINE_WIDTH_MM:g} mm",
                    MIN_LINE_WIDTH_MM <= style.width_mm <= MAX_LINE_WIDTH_MM, f"{style.width_mm:g} mm"),
              Check(f"line height >= {MIN_LINE_HEIGHT_MM:g} mm", style.height_mm >= MIN_LINE_HEIGHT_MM,
                    f"{style.height_mm:g} mm")]
    pixel = plate.heightmap.pixel_mm
    bars = line_relief(plate.line_mask, pixel, style)[0] > 0
    pieces, n = ndimage.label(bars, structure=np.ones((3, 3)))
    closest, where = np.inf, ""
    for k in range(1, n):
        others = pieces > k
        if others.any():
            gap = np.where(others, ndimage.distance_transform_edt(pieces != k) * pixel, np.inf)
            row, col = np.unravel_index(np.argmin(gap), gap.shape)
            if gap[row, col] < closest:
                closest, where = float(gap[row, col]), f"at ({col * pixel:.0f}, {row * pixel:.0f}) mm"
    value = f"closest {closest:.1f} mm" if np.isfinite(closest) else f"{n} line(s), none near another"
    ok = closest >= MIN_SPACING_MM
    checks.append(Check(f"separate lines >= {MIN_SPACING_MM:g} mm apart", ok, value, "" if ok else where))
    return checks

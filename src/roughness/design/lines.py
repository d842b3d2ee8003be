"""Lines are lines: a picture's thin strokes (outlines, arrows, borders) become smooth raised lines, not a region.

A stroke is *thin* where an opening of its colour's mask with a disk as wide as the threshold removes it (a
stroke survives the opening only where the disk fits inside it, i.e. where it is at least the threshold wide);
removed pieces smaller than half the threshold squared are a thick shape's corners, not strokes. A colour is a
line colour when at least ``LINE_SHARE`` of its pixels are thin (or when the user names it); all its pixels are
then drawn as lines and the regions are the areas the lines enclose (each line pixel joins the nearest region).
The default threshold is the narrowest area a finger reads a texture in (``readability.MIN_TEXTURE_WIDTH_MM``):
a narrower stroke could not carry one anyway.

On the plate a line is a smooth raised bar along the strokes' centre line (their skeleton): a half cosine of
``width_mm`` at its foot and ``height_mm`` tall, textures kept ``gap_mm`` clear of its foot. Default dimensions
follow the Round Table's guidelines for 3D-printed models for touch readers (printdisability.org, section 1.5):
lines 0.5 mm high for faint lines and 1 mm for definite ones, 1.1 to 3 mm wide.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from roughness.core.checks import length, positive
from roughness.core.errors import InputError

from .readability import MIN_TEXTURE_WIDTH_MM

LINE_HEIGHT_MM = 1.0  # a definite line (Round Table 3D-printing guidelines, 1.5: min 0.5 faint, 1 definite)
LINE_WIDTH_MM = 1.5  # within the guidelines' 1.1 to 3 mm
LINE_GAP_MM = 1.0  # textures stop this far from a line's foot (our choice: a line stays a line to the finger)
MAX_STROKE_MM = MIN_TEXTURE_WIDTH_MM  # strokes narrower than this on the plate are lines: too narrow for a texture
LINE_SHARE = 0.5  # a colour whose pixels are at least this share thin is a line colour


@dataclass(frozen=True)
class LineStyle:
    """How lines are made on the plate (mm)."""

    width_mm: float = LINE_WIDTH_MM
    height_mm: float = LINE_HEIGHT_MM
    gap_mm: float = LINE_GAP_MM

    def __post_init__(self) -> None:
        positive("line_bar_mm", self.width_mm)
        positive("line_height_mm", self.height_mm)
        length("line_gap_mm", self.gap_mm, zero=True)


@dataclass(frozen=True)
class Lines:
    """A picture's line pixels and what was measured of its colours' strokes (picture pixels)."""

    mask: np.ndarray  # (h, w) bool: pixels drawn as lines
    colours: tuple[int, ...]  # indices of the line colours
    threshold_px: float  # strokes narrower than this are lines
    thin_share: tuple[float, ...]  # per colour: share of its pixels in thin strokes
    stroke_px: tuple[float | None, ...]  # per line colour: mean stroke width

    def summary(self, mm_per_px: float, names: list[str]) -> dict:
        """What was found, the colours by ``names`` (their #rrggbb), widths in mm on the plate."""
        return {"line_colours": [names[i] for i in self.colours], "threshold_mm": self.threshold_px * mm_per_px,
                "line_pixels": int(self.mask.sum()),
                "thin_share": {name: round(s, 3) for name, s in zip(names, self.thin_share)},
                "stroke_width_mm": [None if s is None else round(s * mm_per_px, 3) for s in self.stroke_px]}


def disk(diameter_px: float) -> np.ndarray:
    """A disk that fits in a stroke at least ``diameter_px`` wide but not in a narrower one (whole pixels):
    ``ceil(diameter)`` pixels across."""
    n = max(1, math.ceil(diameter_px - 1e-9))
    c = (n - 1) / 2
    i, j = np.mgrid[:n, :n]
    return (i - c) ** 2 + (j - c) ** 2 <= (n / 2) ** 2


def thin_pixels(mask: np.ndarray, threshold_px: float) -> np.ndarray:
    """Pixels of ``mask`` in strokes narrower than ``threshold_px`` (module docstring)."""
    padded = np.pad(mask, math.ceil(threshold_px), mode="edge")  # strokes reaching the border are not cut there
    pad = math.ceil(threshold_px)
    opened = ndimage.binary_opening(padded, structure=disk(threshold_px))[pad:-pad, pad:-pad]
    removed = mask & ~opened
    pieces, n = ndimage.label(removed, structure=np.ones((3, 3)))
    if n == 0:
        return removed
    sizes = np.bincount(pieces.ravel(), minlength=n + 1)
    keep = sizes >= threshold_px ** 2 / 2
    keep[0] = False
    return keep[pieces]


def stroke_width(mask: np.ndarray) -> float | None:
    """Mean width (pixels) of ``mask``'s strokes: 4 (mean d - 1/2), d each pixel's distance from the outside (a
    straight stroke w pixels wide: exact for even w, within 1/3 pixel for odd w >= 3)."""
    if not mask.any():
        return None
    inside = ndimage.distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
    return float(4 * (inside[mask].mean() - 0.5))


def detect_lines(labels: np.ndarray, n_colours: int, threshold_px: float, line_colours: tuple[int, ...] | None = None
                 ) -> Lines:
    """The line pixels of a picture of ``n_colours`` flat colours (``labels``: each pixel's colour index): those of
    the colours whose strokes are mostly narrower than ``threshold_px``, or of ``line_colours`` if given."""
    positive("line_width_mm", threshold_px)
    shares = []
    for i in range(n_colours):
        mask = labels == i
        shares.append(float(thin_pixels(mask, threshold_px).sum() / max(mask.sum(), 1)))
    chosen = tuple(i for i, s in enumerate(shares) if s >= LINE_SHARE) if line_colours is None else line_colours
    strokes = tuple(stroke_width(labels == i) for i in chosen)
    if len(chosen) >= n_colours:
        raise InputError(f"every colour of the picture would be a line (strokes narrower than {threshold_px:.1f} "
                         "picture pixels): no region is left; lower --line-width-mm or name --line-colour",
                         parameter="line_width_mm")
    return Lines(np.isin(labels, chosen), tuple(chosen), threshold_px, tuple(shares), strokes)


def fill_lines(labels: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """``labels`` with every line pixel given the label of the nearest pixel that is not a line."""
    if not lines.any():
        return labels
    _, (rows, cols) = ndimage.distance_transform_edt(lines, return_indices=True)
    return labels[rows, cols]


def line_relief(plate_lines: np.ndarray, pixel_mm: float, style: LineStyle) -> tuple[np.ndarray, np.ndarray]:
    """Raised lines (mm) along the centre lines of ``plate_lines`` (plate pixels) and the pixels kept clear of
    textures (within half the width plus the gap of a centre line)."""
    from skimage.morphology import skeletonize

    centre = skeletonize(plate_lines)
    d = ndimage.distance_transform_edt(~centre) * pixel_mm
    half = style.width_mm / 2
    relief = np.where(d < half, style.height_mm * np.cos(math.pi / 2 * d / half), 0.0)
    return relief, d < half + style.gap_mm

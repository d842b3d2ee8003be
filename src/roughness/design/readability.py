"""Readable regions: textured areas too small for a finger to read a texture in, with their size and what helps.

An area's size is the width of the widest disk that fits inside it (twice its largest distance from its edge,
lines and their clearance counting as edge), in mm on the plate. Tactile-graphics practice asks at least 1/4 inch
(6.35 mm) for a component to be read as a texture (tactilegraphics.org, "Keys to readability", 1, after the
BANA/CBA guidelines); the plate's roughness map measures an area only where a whole 10 mm skin footprint lies in
it. Areas narrower than ``MIN_TEXTURE_WIDTH_MM`` are reported with what helps: a larger plate (the width at which
the area reaches the minimum), filling it flat (``--assign COLOUR=flat``) or merging it into a neighbour
(``merge_small_areas``, ``--merge-small``: the region nearest to most of its pixels). Specks under ``MIN_AREA_MM2`` (clustering's leftovers at edges) are counted, not listed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

MIN_TEXTURE_WIDTH_MM = 6.35  # 1/4 inch (tactilegraphics.org, Keys to readability 1)
MIN_AREA_MM2 = 1.0


@dataclass(frozen=True)
class SmallArea:
    """A connected textured area narrower than the minimum (mm)."""

    colour: str
    centre_mm: tuple[float, float]  # x, y of its widest point
    width_mm: float  # widest disk inside it
    area_mm2: float
    plate_width_mm: float  # the plate width at which it would be about MIN_TEXTURE_WIDTH_MM wide (lines' widths do
    # not scale with the plate: an estimate)

    def describe(self) -> str:
        x, y = self.centre_mm
        return (f"{self.colour} area at ({x:.0f}, {y:.0f}) mm is {self.width_mm:.1f} mm across ({self.area_mm2:.0f} "
                f"mm^2), under the {MIN_TEXTURE_WIDTH_MM:g} mm a finger needs to read a texture: a plate about "
                f"{self.plate_width_mm:.0f} mm wide (--size-mm or --page) makes it wide enough, or fill it flat "
                f"(--assign {self.colour}=flat), or merge it into its neighbour (--merge-small)")

    def as_dict(self) -> dict:
        return {"colour": self.colour, "centre_mm": [round(c, 2) for c in self.centre_mm],
                "width_mm": round(self.width_mm, 3), "area_mm2": round(self.area_mm2, 2),
                "plate_width_mm_needed": round(self.plate_width_mm, 1)}


def merge_small_areas(labels: np.ndarray, clear: np.ndarray, pixel_mm: float, textured: list[int],
                      min_width_mm: float = MIN_TEXTURE_WIDTH_MM) -> tuple[np.ndarray, int]:
    """``labels`` with each textured area narrower than ``min_width_mm`` (as ``small_areas`` finds them) given the
    region nearest to most of its pixels (a neighbour, across a line if there is one), and how many were merged."""
    out = labels.copy()
    merged = 0
    for index in textured:
        inside = (labels == index) & ~clear
        pieces, n = ndimage.label(inside)
        if n == 0:
            continue
        depth = ndimage.distance_transform_edt(np.pad(inside, 1))[1:-1, 1:-1] * pixel_mm
        widths = 2 * ndimage.maximum(depth, pieces, np.arange(1, n + 1))
        narrow = np.flatnonzero(np.asarray(widths) < min_width_mm) + 1
        if not len(narrow):
            continue
        _, (rows, cols) = ndimage.distance_transform_edt(labels == index, return_indices=True)
        for piece in narrow:
            where = pieces == piece
            others = labels[rows[where], cols[where]]
            if others.size and (others != index).any():
                out[where] = np.bincount(others[others != index]).argmax()
                merged += 1
    return out, merged


def small_areas(labels: np.ndarray, clear: np.ndarray, pixel_mm: float, textured: dict[int, str],
                min_width_mm: float = MIN_TEXTURE_WIDTH_MM) -> tuple[list[SmallArea], int]:
    """The textured areas (connected, of the regions ``textured``: index -> colour) narrower than ``min_width_mm``,
    widest first, and how many specks under MIN_AREA_MM2 were left out; ``clear``: pixels no texture may cover."""
    plate_width = labels.shape[1] * pixel_mm
    found, specks = [], 0
    for index, colour in textured.items():
        inside = (labels == index) & ~clear
        pieces, n = ndimage.label(inside)
        if n == 0:
            continue
        depth = ndimage.distance_transform_edt(np.pad(inside, 1))[1:-1, 1:-1] * pixel_mm
        areas = ndimage.sum_labels(inside, pieces, np.arange(1, n + 1)) * pixel_mm ** 2
        deepest = ndimage.maximum_position(depth, pieces, np.arange(1, n + 1))
        for area, (row, col) in zip(areas, deepest):
            width = 2 * float(depth[row, col])
            if width >= min_width_mm:
                continue
            if area < MIN_AREA_MM2:
                specks += 1
                continue
            found.append(SmallArea(colour, ((col + 0.5) * pixel_mm, (row + 0.5) * pixel_mm), width, float(area),
                                   math.ceil(plate_width * min_width_mm / width)))
    return sorted(found, key=lambda a: -a.width_mm), specks

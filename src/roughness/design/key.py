"""A key strip under a tactile plate: each texture's sample beside its braille label.

Tactile graphics explain their textures in a key (BANA/CBA guidelines; tactilegraphics.org, "Labels and keys":
texture samples large enough for the reading finger to move across, the explanations in braille). Here each
textured region gets a ``SWATCH_MM`` square of its texture (wider than the 10 mm skin footprint, so that the
plate's roughness map measures the sample as it measures the region) and, ``LABEL_GAP_MM`` to its right, its label
in braille (``roughness.design.braille``), centred on the sample. Entries run left to right, ``KEY_GAP_MM`` apart,
wrapping onto a new row when the plate is too narrow; the strip starts ``KEY_GAP_MM`` under the picture.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from .braille import BrailleStyle, braille_relief, cells_of
from .colours import PictureColours
from .plate_relief import compose

SWATCH_MM = 15.0
LABEL_GAP_MM = 3.5  # at least the 1/8 inch (3.2 mm) between elements (guidelines.MIN_SPACING_MM)
KEY_GAP_MM = 5.0
DEFAULT_LABELS = "abcdefghijklmnopqrstuvwxyz"


@dataclass(frozen=True)
class KeySpec:
    """What the key says: a label per colour index (default: a, b, c, ... in region order), the liblouis table
    (None: grade 1 English, built in) and the cells' dimensions."""

    labels: dict[int, str] = field(default_factory=dict)  # by colour index
    table: str | None = None
    style: BrailleStyle = field(default_factory=BrailleStyle)


@dataclass(frozen=True)
class KeyEntry:
    """One line of the key: the region it explains, its label and braille cells, where its sample is (mm)."""

    region: int
    label: str
    cells: tuple[tuple[int, ...], ...]
    swatch_mm: tuple[float, float, float, float]  # x0, y0, x1, y1 on the whole plate

    def braille(self) -> str:
        """The cells as Unicode braille."""
        return "".join(chr(0x2800 + sum(1 << (d - 1) for d in c)) for c in self.cells)


def key_spec(found: PictureColours, labels: Mapping[str, str] | str | None = None, table: str | None = None,
             style: BrailleStyle | None = None) -> KeySpec:
    """A key's spec from labels by colour (``{"#dc781e": "sun"}`` or ``"#dc781e=sun,#1e286e=sea"``), each colour
    one of the picture's flat colours (``layout.colour_index``); InputError otherwise."""
    from .layout import colour_index

    if isinstance(labels, str):
        pairs = {}
        for item in labels.split(","):
            colour, sep, text = item.partition("=")
            if not sep or not text.strip():
                raise InputError(f"key labels: {item.strip()!r} is not COLOUR=TEXT", parameter="key_labels")
            pairs[colour.strip()] = text.strip()
        labels = pairs
    if labels is not None and not isinstance(labels, Mapping):
        raise InputError(f"key labels must map colours '#rrggbb' to text, got {type(labels).__name__}",
                         parameter="key_labels")
    by_colour = {colour_index(c, found, "key_labels"): str(t) for c, t in (labels or {}).items()}
    for text in by_colour.values():
        cells_of(text, table)  # refused now, before any palette is made, if it cannot be written
    return KeySpec(by_colour, table, style or BrailleStyle())


def key_entries(regions: list[int], labels: dict[int, str], table: str | None
                ) -> list[tuple[int, str, list[tuple[int, ...]]]]:
    """(region, label, cells) of each of ``regions``: its label from ``labels`` (by region), else a, b, c, ..."""
    out = []
    for n, region in enumerate(regions):
        label = labels.get(region, DEFAULT_LABELS[n] if n < len(DEFAULT_LABELS) else str(n + 1))
        out.append((region, label, cells_of(label, table)))
    return out


def key_height_mm(entries: list[tuple[int, str, list[tuple[int, ...]]]], width_mm: float, style: BrailleStyle) -> float:
    """Height (mm) of the key strip of ``entries`` (``key_entries``) on a plate ``width_mm`` wide."""
    return _placed(entries, width_mm, style)[1]


def _placed(entries: list[tuple[int, str, list[tuple[int, ...]]]], width_mm: float, style: BrailleStyle
            ) -> tuple[list[tuple[int, str, list[tuple[int, ...]], float, float]], float]:
    """Each entry with the corner of its sample (mm from the strip's corner), in rows across the plate, and the
    strip's height (mm); InputError if an entry is wider than the plate."""
    placed, x, y = [], KEY_GAP_MM, KEY_GAP_MM
    for region, label, cells in entries:
        wide = SWATCH_MM + LABEL_GAP_MM + style.width_mm(len(cells))
        if wide > width_mm - 2 * KEY_GAP_MM:
            raise InputError(f"the key entry {label!r} ({wide:.0f} mm) does not fit across a {width_mm:g} mm plate: "
                             "shorten the label or widen the plate", parameter="key_labels")
        if x + wide > width_mm - KEY_GAP_MM:
            x, y = KEY_GAP_MM, y + SWATCH_MM + KEY_GAP_MM
        placed.append((region, label, cells, x, y))
        x += wide + KEY_GAP_MM
    return placed, y + SWATCH_MM + KEY_GAP_MM


def key_strip(entries: list[tuple[int, str, list[tuple[int, ...]]]], textures: list[Heightmap | None],
              width_mm: float, top_mm: float, pixel_mm: float, background: int,
              style: BrailleStyle) -> tuple[np.ndarray, np.ndarray, list[KeyEntry]]:
    """The key strip's relief (mm) and region labels (``background`` between entries, -1 under the braille: no
    region's footprint) for a plate ``width_mm`` wide whose picture ends at ``top_mm``, and where each entry went;
    InputError if an entry is wider than the plate."""
    nx = round(width_mm / pixel_mm)
    placed, height_mm = _placed(entries, width_mm, style)
    ny = math.ceil(height_mm / pixel_mm)
    labels = np.full((ny, nx), background)
    swatch = round(SWATCH_MM / pixel_mm)
    for region, _, _, x0, y0 in placed:
        i, j = round(y0 / pixel_mm), round(x0 / pixel_mm)
        labels[i:i + swatch, j:j + swatch] = region
    relief = compose(labels, textures, pixel_mm).heights.copy()  # a Heightmap's heights are read-only
    out = []
    for region, label, cells, x0, y0 in placed:
        dots = braille_relief(cells, pixel_mm, style)
        i = round((y0 + (SWATCH_MM - style.height_mm) / 2) / pixel_mm)
        j = round((x0 + SWATCH_MM + LABEL_GAP_MM) / pixel_mm)
        view = relief[i:i + dots.shape[0], j:j + dots.shape[1]]
        view[:] = np.maximum(view, dots[:view.shape[0], :view.shape[1]])
        labels[i:i + dots.shape[0], j:j + dots.shape[1]] = -1
        out.append(KeyEntry(region, label, tuple(cells), (x0, top_mm + y0, x0 + SWATCH_MM, top_mm + y0 + SWATCH_MM)))
    return relief, labels, out

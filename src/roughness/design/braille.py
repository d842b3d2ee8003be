"""Braille labels for tactile plates: uncontracted (grade 1) English built in, liblouis for the rest, cells as relief.

Dimensions from the 2010 ADA Standards for Accessible Design, Table 703.3.1 (braille on signs, which are made
rather than embossed, as a print is): dot base diameter 1.5 to 1.6 mm, distance between two dots in the same cell
2.3 to 2.5 mm, between corresponding dots in adjacent cells 6.1 to 7.6 mm, dot height 0.6 to 0.9 mm, between
corresponding dots of a cell and the one directly below 10 to 10.2 mm (centre to centre), dots domed or rounded.
The values chosen sit inside those ranges (``BrailleStyle``); a dot is a spherical cap.

Grade 1 follows Unified English Braille: letters a-z, the capital indicator (dot 6) before a capital letter, the
numeric indicator (dots 3456) before a run of digits (1-9, 0 as a-j), and a few punctuation signs. Contracted
braille and other languages need liblouis (its Python module ``louis``) and a table name, e.g. ``en-ueb-g2.ctb``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError

LETTERS = {  # dots of a-z (UEB grade 1)
    "a": (1,), "b": (1, 2), "c": (1, 4), "d": (1, 4, 5), "e": (1, 5), "f": (1, 2, 4), "g": (1, 2, 4, 5),
    "h": (1, 2, 5), "i": (2, 4), "j": (2, 4, 5), "k": (1, 3), "l": (1, 2, 3), "m": (1, 3, 4), "n": (1, 3, 4, 5),
    "o": (1, 3, 5), "p": (1, 2, 3, 4), "q": (1, 2, 3, 4, 5), "r": (1, 2, 3, 5), "s": (2, 3, 4), "t": (2, 3, 4, 5),
    "u": (1, 3, 6), "v": (1, 2, 3, 6), "w": (2, 4, 5, 6), "x": (1, 3, 4, 6), "y": (1, 3, 4, 5, 6), "z": (1, 3, 5, 6)}
DIGITS = {d: LETTERS["jabcdefghi"[int(d)]] for d in "0123456789"}
PUNCTUATION = {" ": (), ",": (2,), ".": (2, 5, 6), "-": (3, 6), "'": (3,), ";": (2, 3), ":": (2, 5),
               "!": (2, 3, 5), "?": (2, 3, 6)}
CAPITAL = (6,)
NUMERIC = (3, 4, 5, 6)


@dataclass(frozen=True)
class BrailleStyle:
    """Cell dimensions (mm), within ADA 2010 Table 703.3.1's ranges."""

    dot_diameter_mm: float = 1.5  # 1.5-1.6
    dot_height_mm: float = 0.7  # 0.6-0.9 (below the dot's radius: a cap, no overhang)
    dot_spacing_mm: float = 2.5  # 2.3-2.5, within a cell
    cell_spacing_mm: float = 6.2  # 6.1-7.6, corresponding dots of adjacent cells
    line_spacing_mm: float = 10.0  # 10-10.2, corresponding dots of a cell and the one below

    def dot_centres(self, dots: tuple[int, ...], cell: int = 0) -> list[tuple[float, float]]:
        """(x, y) mm of ``dots`` (1-3 down the left column, 4-6 down the right) of the ``cell``-th cell in a line,
        dot 1 of the first cell at (0, 0), y downwards."""
        return [(cell * self.cell_spacing_mm + (d > 3) * self.dot_spacing_mm, ((d - 1) % 3) * self.dot_spacing_mm)
                for d in dots]

    def width_mm(self, cells: int) -> float:
        """Width of a line of ``cells`` cells, dot edge to dot edge."""
        return (cells - 1) * self.cell_spacing_mm + self.dot_spacing_mm + self.dot_diameter_mm if cells else 0.0

    @property
    def height_mm(self) -> float:
        """Height of a cell, dot edge to dot edge."""
        return 2 * self.dot_spacing_mm + self.dot_diameter_mm


def grade1(text: str) -> list[tuple[int, ...]]:
    """The cells of ``text`` in uncontracted English braille (module docstring); InputError naming any character
    it cannot write."""
    cells: list[tuple[int, ...]] = []
    digits = False
    for ch in text:
        if ch.isdigit() and ch in DIGITS:
            if not digits:
                cells.append(NUMERIC)
            cells.append(DIGITS[ch])
            digits = True
            continue
        if digits and ch.lower() in "abcdefghij":  # a letter a-j after digits would read as a digit
            cells.append((5, 6))  # grade 1 indicator
        digits = False
        if ch.lower() in LETTERS:
            if ch.isupper():
                cells.append(CAPITAL)
            cells.append(LETTERS[ch.lower()])
        elif ch in PUNCTUATION:
            cells.append(PUNCTUATION[ch])
        else:
            raise InputError(f"braille label {text!r}: {ch!r} is not in the built-in grade 1 English braille (letters, "
                             f"digits, space and {''.join(sorted(set(PUNCTUATION) - {' '}))}); other characters need "
                             "liblouis (--braille-table)", parameter="braille_table")
    return cells


def louis_cells(text: str, table: str) -> list[tuple[int, ...]]:
    """The cells of ``text`` translated by liblouis with ``table`` (e.g. en-ueb-g2.ctb); InputError if liblouis is
    not installed or the table is unknown."""
    try:
        import louis
    except ImportError:
        raise InputError(f"braille table {table!r} needs liblouis, which is not installed (its Python module "
                         "'louis': e.g. apt install python3-louis, or liblouis's python bindings); without "
                         "--braille-table the labels are grade 1 English, built in", parameter="braille_table") from None
    try:
        unicode = louis.translateString(["unicode.dis", table], text)
    except Exception as err:  # liblouis raises a bare RuntimeError for an unknown table
        raise InputError(f"liblouis cannot translate with table {table!r}: {err}", parameter="braille_table") from None
    return [tuple(d + 1 for d in range(8) if (ord(ch) - 0x2800) >> d & 1) for ch in unicode if 0x2800 <= ord(ch) < 0x2900]


def cells_of(text: str, table: str | None = None) -> list[tuple[int, ...]]:
    """The braille cells of a label: grade 1 English built in, or liblouis with ``table``."""
    return grade1(text) if table is None else louis_cells(text, table)


def braille_relief(cells: list[tuple[int, ...]], pixel_mm: float, style: BrailleStyle = BrailleStyle()
                   ) -> np.ndarray:
    """Heights (mm) of a line of braille ``cells`` on ``pixel_mm`` pixels: each dot a spherical cap of the style's
    base diameter and height; the array spans the dots' extent, dot edges on its border."""
    radius = style.dot_diameter_mm / 2
    h = style.dot_height_mm
    sphere = (radius ** 2 + h ** 2) / (2 * h)
    ny = max(1, math.ceil(style.height_mm / pixel_mm))
    nx = max(1, math.ceil(style.width_mm(len(cells)) / pixel_mm))
    y = ((np.arange(ny) + 0.5) * pixel_mm - radius)[:, None]
    x = ((np.arange(nx) + 0.5) * pixel_mm - radius)[None, :]
    relief = np.zeros((ny, nx))
    for i, dots in enumerate(cells):
        for cx, cy in style.dot_centres(dots, i):
            r2 = (x - cx) ** 2 + (y - cy) ** 2
            cap = np.sqrt(np.maximum(sphere ** 2 - r2, 0)) - (sphere - h)
            relief = np.maximum(relief, np.where(r2 < radius ** 2, cap, 0.0))
    return relief

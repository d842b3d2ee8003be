"""What each of a picture's flat colours becomes on a tactile plate: a raised line, the flat background, or a texture.

The background (by default the colour with the most pixels on the picture's border, ties to the larger) stays
flat, as tactile graphics leave it. Textures go to the other colours either as the user assigns them (colour ->
palette member, smoothest first, or "flat") or by the rule: the lightest colour gets the smoothest texture used,
the darkest the roughest; with more members than colours, the members used are spread evenly over the palette
and, beside a flat background, counted from its rough end (the flat background is the smoothest "texture").
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from roughness.core.errors import InputError

from .colours import PictureColours, hex_colour, lab
from .lines import Lines, LineStyle

FLAT = "flat"


@dataclass(frozen=True)
class Layout:
    """Per flat colour of a picture: a line colour, flat, or textured (``assign``: colour index -> palette member
    number from 1, smoothest first, or FLAT), with the lines found and how they are made."""

    n_colours: int
    lines: Lines | None = None
    style: LineStyle = field(default_factory=LineStyle)
    background: int | None = None  # colour index of the flat background
    assign: Mapping[int, int | str] = field(default_factory=dict)

    @property
    def line_colours(self) -> tuple[int, ...]:
        return self.lines.colours if self.lines else ()

    @property
    def regions(self) -> list[int]:
        """Colour indices that are regions (not lines), lightest first."""
        return [i for i in range(self.n_colours) if i not in self.line_colours]

    @property
    def flat(self) -> list[int]:
        """Colour indices left flat: the background unless a texture is assigned to it, and those assigned FLAT."""
        return [i for i in self.regions if self.assign.get(i) == FLAT
                or (i == self.background and i not in self.assign)]

    @property
    def textured(self) -> list[int]:
        return [i for i in self.regions if i not in self.flat]

    def members(self, n_textures: int) -> tuple[dict[int, int], str]:
        """Per textured colour, its texture's index among ``n_textures`` (smoothest first), and the rule used in
        words; InputError if they are too few or an assignment names a member beyond them."""
        textured = self.textured
        if n_textures < len(textured):
            rest = self.n_colours - len(textured)
            what = f" to texture ({rest} of {self.n_colours} flat or lines)" if rest else ""
            raise InputError(f"the picture has {len(textured)} flat colours{what} but only {n_textures} "
                             "textures were given", parameter="textures")
        chosen = {i: m - 1 for i, m in self.assign.items() if m != FLAT}
        for i, member in chosen.items():
            if member >= n_textures:
                raise InputError(f"colour {i + 1} is assigned texture {member + 1} but there are only {n_textures}",
                                 parameter="assign")
        if chosen:
            missing = [i for i in textured if i not in chosen]
            if missing:
                raise InputError(f"--assign gives textures to {len(chosen)} colours but not to colour(s) "
                                 f"{', '.join(str(i + 1) for i in missing)}: assign every textured colour (or "
                                 "'flat'), or leave the choice to the rule", parameter="assign")
            return chosen, "as assigned"
        n = len(textured)
        if self.flat:  # the flat background counts as the smoothest: spread from the palette's rough end
            pick = np.round(np.linspace(0, n_textures, n + 1)).astype(int)[1:] - 1
        else:
            pick = np.round(np.linspace(0, n_textures - 1, n)).astype(int)
        rule = "the lightest colour gets the smoothest texture, the darkest the roughest"
        if n_textures > n:
            rule += f" (palette members {', '.join(str(m + 1) for m in pick)} of {n_textures} used)"
        return dict(zip(textured, (int(m) for m in pick))), rule


def border_colour(labels: np.ndarray, candidates: list[int]) -> int:
    """The candidate colour with the most pixels on the picture's border (ties: the most pixels overall)."""
    border = np.concatenate([labels[0], labels[-1], labels[1:-1, 0], labels[1:-1, -1]])
    on_border = np.bincount(border, minlength=labels.max() + 1)
    overall = np.bincount(labels.ravel(), minlength=labels.max() + 1)
    return max(candidates, key=lambda i: (on_border[i], overall[i]))


def colour_index(spec: str, found: PictureColours, parameter: str) -> int:
    """The index of the picture's flat colour nearest ``spec`` (#rrggbb), within the clustering's tolerance
    (Delta E); InputError naming the found colours otherwise."""
    text = spec.strip().lower() if isinstance(spec, str) else ""
    if not (len(text) == 7 and text[0] == "#" and all(c in "0123456789abcdef" for c in text[1:])):
        raise InputError(f"{parameter}: {spec!r} is not a colour #rrggbb", parameter=parameter)
    rgb = np.array([int(text[k:k + 2], 16) for k in (1, 3, 5)], dtype=np.uint8)
    distance = np.linalg.norm(lab(found.colours) - lab(rgb[None])[0], axis=1)
    nearest = int(np.argmin(distance))
    if distance[nearest] > found.tolerance:
        raise InputError(f"{parameter}: {text} is not one of the picture's flat colours "
                         f"({', '.join(hex_colour(c) for c in found.colours)}; nearest {hex_colour(found.colours[nearest])}, "
                         f"Delta E {distance[nearest]:.0f} > {found.tolerance:g})", parameter=parameter)
    return nearest


def parse_assign(text: str) -> dict[str, int | str]:
    """``#rrggbb=N,#rrggbb=flat,...`` (N: palette member from 1, smoothest first) as a mapping; InputError if
    malformed. A file's content may be given the same way, one pair a line."""
    out: dict[str, int | str] = {}
    for item in text.replace("\n", ",").split(","):
        if not item.strip():
            continue
        colour, sep, value = item.partition("=")
        value = value.strip().lower()
        if not sep or not (value == FLAT or value.isdigit() and int(value) >= 1):
            raise InputError(f"--assign: {item.strip()!r} is not COLOUR=N (N from 1, smoothest first) or "
                             "COLOUR=flat", parameter="assign")
        out[colour.strip()] = value if value == FLAT else int(value)
    if not out:
        raise InputError("--assign names no colour (give #rrggbb=N,...)", parameter="assign")
    return out


MAX_ASSIGN_BYTES = 65536  # a mapping file: a few lines; anything larger is not one


def assign_argument(text: str) -> dict[str, int | str]:
    """``parse_assign`` of ``text``, or of the file it names after ``@``; InputError if unreadable or too large."""
    if not text.startswith("@"):
        return parse_assign(text)
    from pathlib import Path

    path = Path(text[1:])
    if not path.is_file():
        raise InputError(f"--assign: {path} is not a file", parameter="assign")
    if path.stat().st_size > MAX_ASSIGN_BYTES:
        raise InputError(f"--assign: {path} is larger than {MAX_ASSIGN_BYTES:,} bytes: not a colour mapping",
                         parameter="assign")
    try:
        return parse_assign(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"--assign: {path} cannot be read as text: {err}", parameter="assign") from None


def plan_layout(found: PictureColours, mm_per_px: float, line_width_mm: float | None = None,
                line_colour: str | None = None, background: str | None = "auto",
                assign: Mapping[str, int | str] | None = None, style: LineStyle | None = None) -> Layout:
    """The layout of a picture's colours on a plate at ``mm_per_px`` (plate mm per picture pixel): lines (strokes
    narrower than ``line_width_mm`` on the plate, or the colour ``line_colour``; None and None: no lines), the
    background ("auto": the border colour, "#rrggbb", or None: none left flat) and explicit assignments."""
    from .lines import detect_lines

    n = len(found.colours)
    lines = None
    if line_width_mm is not None or line_colour is not None:
        from .lines import MAX_STROKE_MM

        threshold = (line_width_mm or MAX_STROKE_MM) / mm_per_px
        named = None if line_colour is None else (colour_index(line_colour, found, "line_colour"),)
        lines = detect_lines(found.labels, n, threshold, named)
    candidates = [i for i in range(n) if lines is None or i not in lines.colours]
    if background is None:
        back = None
    elif background == "auto":
        back = border_colour(found.labels, candidates)
    else:
        back = colour_index(background, found, "background")
        if back not in candidates:
            raise InputError(f"background: {background} is a line colour", parameter="background")
    if assign is not None and not isinstance(assign, Mapping):
        raise InputError(f"assign must map colours '#rrggbb' to palette members (from 1) or 'flat', got "
                         f"{type(assign).__name__}", parameter="assign")
    for c, m in (assign or {}).items():
        if not (m == FLAT or isinstance(m, int) and not isinstance(m, bool) and m >= 1):
            raise InputError(f"assign: {c!r} -> {m!r}: a palette member is a number from 1 (or 'flat')",
                             parameter="assign")
    chosen = {colour_index(c, found, "assign"): m for c, m in (assign or {}).items()}
    for i in chosen:
        if i not in candidates:
            raise InputError(f"assign: {hex_colour(found.colours[i])} is a line colour, not a region",
                             parameter="assign")
    return Layout(n, lines, style or LineStyle(), back, chosen)

"""Page presets for tactile plates and the scale bar drawn on their pictures.

Sheets (portrait width x height, mm): ISO A4 and A3, US Letter and Tabloid (the sizes swell paper is sold in) and
the 11 x 11.5 inch braille embosser page. A picture is fitted inside the page less ``MARGIN_MM`` on every side,
turned to landscape when it is wider than tall.
"""
from __future__ import annotations

import math

from roughness.core.checks import choice

PAGES_MM = {"a4": (210.0, 297.0), "a3": (297.0, 420.0), "letter": (215.9, 279.4), "tabloid": (279.4, 431.8),
            "braille": (279.4, 292.1)}
MARGIN_MM = 10.0  # our choice: room to hold the sheet and for a slicer's brim


def page_width(page: str, picture_shape: tuple[int, ...], margin_mm: float = MARGIN_MM) -> float:
    """The plate width (mm) that fits a picture (h, w, ...) on ``page`` (a PAGES_MM name) within the margins."""
    short, long = PAGES_MM[choice("page", page.lower() if isinstance(page, str) else page, PAGES_MM)]
    h, w = picture_shape[:2]
    across, down = (long, short) if w > h else (short, long)
    return min(across - 2 * margin_mm, (down - 2 * margin_mm) * w / h)


def scale_bar_mm(width_mm: float) -> float:
    """A round length (1, 2 or 5 x 10^n mm) of at most a fifth of ``width_mm``, for a scale bar."""
    target = width_mm / 5
    power = 10 ** math.floor(math.log10(target))
    return max(m * power for m in (1, 2, 5) if m * power <= target)

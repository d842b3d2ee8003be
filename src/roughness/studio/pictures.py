"""Pictures the pages show, as data URLs of PNG images (no file, nothing fetched from elsewhere)."""
from __future__ import annotations

import base64
import io

import numpy as np
from PIL import Image

from roughness.surface.heightmap import Heightmap


def png_url(image: Image.Image) -> str:
    """``image`` as a ``data:image/png`` URL."""
    buffer = io.BytesIO()
    image.save(buffer, format="PNG")
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def heightmap_url(hm: Heightmap, side_px: int = 320) -> str:
    """The heightmap in grey (black: lowest, white: highest), at most ``side_px`` pixels a side."""
    h = np.asarray(hm.heights, dtype=float)
    span = float(h.max() - h.min())
    grey = np.zeros(h.shape, np.uint8) if span == 0 else np.rint((h - h.min()) / span * 255).astype(np.uint8)
    image = Image.fromarray(grey)
    image.thumbnail((side_px, side_px))
    return png_url(image)

"""A tactile plate's relief from its region labels: each region's texture laid periodically (lowest point at 0)
and, optionally, smooth raised outlines along region boundaries (mm). Used by the plate and by its key strip."""
from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from roughness.surface.heightmap import Heightmap


def outline(labels: np.ndarray, pixel_mm: float, width_mm: float, height_mm: float) -> np.ndarray:
    """Smooth raised lines (mm) along region boundaries: height * cos^2(pi d / width) within width / 2 of them."""
    edge = np.zeros(labels.shape, dtype=bool)
    edge[:, 1:] |= labels[:, 1:] != labels[:, :-1]
    edge[1:, :] |= labels[1:, :] != labels[:-1, :]
    d = ndimage.distance_transform_edt(~edge) * pixel_mm
    return np.where(d < width_mm / 2, height_mm * np.cos(math.pi * d / width_mm) ** 2, 0.0)


def compose(labels: np.ndarray, textures: list[Heightmap | None], pixel_mm: float, outline_mm: float | None = None,
            outline_height_mm: float | None = None) -> Heightmap:
    """The plate's relief: texture i (periodic, lowest point at 0) in region i (None: flat), outlines on top."""
    ny, nx = labels.shape
    x = (np.arange(nx) + 0.5) * pixel_mm
    y = (np.arange(ny) + 0.5) * pixel_mm
    relief = np.zeros(labels.shape)
    for i, texture in enumerate(textures):
        inside = labels == i
        if texture is not None and inside.any():
            h = texture.sample(x[None, :], y[:, None], periodic=True)
            relief[inside] = (h - texture.heights.min())[inside]
    if outline_mm:
        height = outline_height_mm if outline_height_mm is not None else float(np.median(
            [np.ptp(t.heights) for t in textures if t is not None] or [0.0]))
        relief = np.maximum(relief, outline(labels, pixel_mm, outline_mm, height))
    return Heightmap(relief, pixel_mm)

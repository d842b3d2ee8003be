"""Shapes to hide in a plate: the paper's four (Fig. 25: circle, square, triangle, cross) or a picture's dark pixels,
as a boolean mask on the plate's pixel grid (rows = y), and how wide a shape is for a fingertip."""
from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from roughness.core.checks import choice, in_range
from roughness.core.errors import InputError

from .edges import smooth_labels

SHAPES = ("circle", "square", "triangle", "cross")
SPAN = 0.5  # a built-in shape spans this fraction of the plate's side
CROSS_BAR = 1 / 3  # a cross's bars are this fraction of its span wide
DARK = 128  # a picture's pixels darker than this (luminance 0..255) are the shape


def builtin_mask(name: str, shape: tuple[int, int], span: float = SPAN) -> np.ndarray:
    """Built-in shape ``name`` centred on a plate of ``shape`` pixels, ``span`` of its shorter side across."""
    name = choice("shape", name, SHAPES)
    span = in_range("span", span, 0.0, 1.0)
    ny, nx = shape
    y, x = np.mgrid[:ny, :nx] + 0.5
    side = span * min(nx, ny)
    u, v = (x - nx / 2) / (side / 2), (y - ny / 2) / (side / 2)  # -1..1 over the shape's box, v down
    if name == "circle":
        return u**2 + v**2 <= 1
    if name == "square":
        return (np.abs(u) <= 1) & (np.abs(v) <= 1)
    if name == "cross":
        bar = CROSS_BAR
        box = (np.abs(u) <= 1) & (np.abs(v) <= 1)
        return box & ((np.abs(u) <= bar) | (np.abs(v) <= bar))
    # an equilateral triangle, apex up, its box's width across and centred in height
    height = math.sqrt(3)
    top = -height / 2
    return (v >= top) & (v <= -top) & (np.abs(u) <= (v - top) / height)


def picture_mask(rgb: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """A picture's dark pixels (luminance below ``DARK``) on a plate of ``shape`` pixels, edges smoothed
    (``edges.smooth_labels``)."""
    luminance = np.asarray(rgb, dtype=float)[..., :3] @ [0.299, 0.587, 0.114]
    return smooth_labels((luminance < DARK).astype(np.int8), shape) == 1


def check_mask(mask: np.ndarray) -> np.ndarray:
    """``mask`` as booleans; InputError if it covers all of the plate or none of it (nothing to compare)."""
    mask = np.asarray(mask, dtype=bool)
    if mask.ndim != 2:
        raise InputError(f"the shape mask must be 2-D, got shape {mask.shape}", parameter="mask")
    covered = int(mask.sum())
    if covered in (0, mask.size):
        raise InputError(f"the shape covers {'none' if covered == 0 else 'all'} of the plate: a hidden shape needs "
                         "both an inside and an outside (a picture's shape is its pixels darker than mid-grey)",
                         parameter="mask")
    return mask


def inscribed_width_mm(mask: np.ndarray, pixel_mm: float) -> float:
    """Diameter (mm) of the largest disk inside the shape; the plate's edge counts as the shape's edge."""
    return 2 * float(ndimage.distance_transform_edt(np.pad(mask, 1)).max()) * pixel_mm

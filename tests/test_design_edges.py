"""Edges follow the shapes: the bundled 60 x 40 px drawing on a 48 mm plate without 0.8 mm staircases."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy import ndimage

from roughness.design.colours import cluster_colours
from roughness.design.edges import smooth_labels, smooth_mask
from roughness.design.tactile_image import plate_labels, plate_shape, read_image

SHAPES = Path(__file__).resolve().parents[1] / "examples" / "design" / "shapes.png"


def circle_departure(inside: np.ndarray, pixel_mm: float) -> tuple[float, float]:
    """RMS and largest distance (mm) of a region's edge pixels from the circle fitted to them (least squares)."""
    edge = inside & ~ndimage.binary_erosion(inside)
    rows, cols = np.nonzero(edge)
    x, y = (cols + 0.5) * pixel_mm, (rows + 0.5) * pixel_mm
    a, b, c = np.linalg.lstsq(np.column_stack([x, y, np.ones_like(x)]), x ** 2 + y ** 2, rcond=None)[0]
    d = np.hypot(x - a / 2, y - b / 2) - np.sqrt(c + a ** 2 / 4 + b ** 2 / 4)
    return float(np.sqrt(np.mean(d ** 2))), float(np.abs(d).max())


def test_the_disc_edge_follows_a_circle_not_the_pixels():
    found = cluster_colours(read_image(SHAPES))
    disc = [tuple(c) for c in found.colours.tolist()].index((220, 120, 30))
    shape = plate_shape(found.labels.shape, 48.0, 0.1)
    rms_near, worst_near = circle_departure(plate_labels(found.labels, 48.0, 0.1) == disc, 0.1)
    rms, worst = circle_departure(smooth_labels(found.labels, shape) == disc, 0.1)
    assert worst_near > 0.4 and rms_near > 0.15  # pixel by pixel: steps of up to half a 0.8 mm pixel
    assert worst < 0.2 and rms < 0.08  # smoothed: what remains is the drawing's own 60 x 40 px circle


def test_straight_edges_stay_put_and_thin_lines_survive():
    labels = np.zeros((24, 60), dtype=int)
    labels[:, 20:40], labels[:, 40:] = 1, 2
    smooth = smooth_labels(labels, (240, 600))
    assert (smooth == plate_labels(labels, 60.0, 0.1)).all()  # a blurred step is 1/2 on the step
    line = np.zeros((40, 40), dtype=bool)
    line[20, 5:35] = True  # one pixel wide
    np.fill_diagonal(line[:, :], True)  # and a diagonal one
    plate = smooth_mask(line, (400, 400))
    pieces, n = ndimage.label(plate, structure=np.ones((3, 3)))
    assert n == 1 and plate[205, 100] and plate[100, 100]
    # across the straight line: blur 0.7 px of a 1 px box exceeds 0.3 within 0.62 px of its centre (12 plate px);
    # reading the blur bilinearly between picture pixels widens that by up to a plate pixel or two each side
    assert 11 <= np.count_nonzero(plate[180:230, 300]) <= 16

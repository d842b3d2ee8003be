"""Overlapping windows of a map too large for one spectral solve, and the footprint positions each one answers.

Each window is solved alone (mirrored across its edges, as a whole map is) and answers the positions whose
sampled strain lies at least a guard band inside its edges: the texture's strain is a local response, and
the relative error of V that a window's edge causes fell, in studies/map_windows.py, from 1.6e-2 at the edge
to at most 3e-4 (printed bumps: 2e-6) ``GUARD_TISSUES`` tissue thicknesses (7.5 mm) inside it and beyond,
far below V's Monte Carlo error (a few percent). An edge of the map itself is
no window edge: the one-solve map is mirrored there too. Windows are planned per axis (all of one size, so
a worker builds the layer's transfer functions once) and combined; every position is answered by exactly
one window. Units: pixels and mm.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError

GUARD_TISSUES = 3.0  # tissue thicknesses between a window's edge and the nearest strain its positions sample


@dataclass(frozen=True)
class Span:
    """One window along one axis: pixels ``start`` to ``start + size`` of the map (beyond the map's ends only for
    a periodic map: they wrap), and the positions ``first`` to ``stop`` (indices of the axis's centres) it
    answers."""

    start: int
    size: int
    first: int
    stop: int


@dataclass(frozen=True)
class Window:
    """A window of the map: its rows and columns, and the positions it answers (rows of y, columns of x)."""

    rows: Span
    cols: Span

    @classmethod
    def whole(cls, shape: tuple[int, int], count_x: int, count_y: int) -> Window:
        """The whole map as one window, answering all ``count_y`` x ``count_x`` positions."""
        return cls(Span(0, shape[0], 0, count_y), Span(0, shape[1], 0, count_x))

    def heights(self, heights: np.ndarray) -> np.ndarray:
        """The window's heights (mm) out of the map's (wrapping around a periodic map)."""
        ny, nx = heights.shape
        r, c = self.rows, self.cols
        if 0 <= r.start and r.start + r.size <= ny and 0 <= c.start and c.start + c.size <= nx:
            return heights[r.start:r.start + r.size, c.start:c.start + c.size]
        return heights[np.ix_(np.arange(r.start, r.start + r.size) % ny, np.arange(c.start, c.start + c.size) % nx)]

    @property
    def positions(self) -> int:
        return (self.rows.stop - self.rows.first) * (self.cols.stop - self.cols.first)


def split_axis(n: int, size: int, centres_mm: np.ndarray, pixel_mm: float, margin_mm: float,
               periodic: bool) -> list[Span]:
    """Windows of ``size`` pixels along an axis of ``n`` pixels that answer every centre once: a centre is
    answered by a window whose edges inside the map lie at least ``margin_mm`` away (InputError if a window
    of ``size`` pixels cannot answer any centre)."""
    if size >= n and not periodic:
        return [Span(0, n, 0, len(centres_mm))]
    spans: list[Span] = []
    first = 0
    while first < len(centres_mm):
        if first == 0 and not periodic:
            start = 0
        else:  # the window's guard band ends at the first centre it answers (the last window: at the map's end)
            start = math.floor((centres_mm[first] - margin_mm) / pixel_mm)
            start = start if periodic else min(start, n - size)
        at_end = not periodic and start + size >= n
        low = start * pixel_mm + (0 if not periodic and start == 0 else margin_mm)
        high = (start + size) * pixel_mm - (0 if at_end else margin_mm)
        stop = first
        while stop < len(centres_mm) and low - 1e-9 <= centres_mm[stop] <= high + 1e-9:
            stop += 1
        if stop == first:
            raise InputError(f"a window of {size} pixels ({size * pixel_mm:g} mm) answers no footprint position "
                             f"beyond its guard bands of {margin_mm:g} mm: use a coarser pixel", parameter="pixel_mm")
        spans.append(Span(start, size, first, stop))
        first = stop
    return spans


def window_sizes(shape: tuple[int, int], max_pixels: int, periodic_guard: int | None = None) -> tuple[int, int]:
    """(rows, columns) of the windows of a map of ``shape``: at most ``max_pixels`` pixels, as square as the
    map allows (a narrow map's windows span its whole width; a periodic map's, its width and a guard band of
    ``periodic_guard`` pixels on each side)."""
    ny, nx = (n + 2 * periodic_guard for n in shape) if periodic_guard is not None else shape
    side = math.isqrt(max_pixels)
    if ny <= side:
        return ny, min(nx, max_pixels // ny)
    if nx <= side:
        return min(ny, max_pixels // nx), nx
    return side, side


def plan_windows(shape: tuple[int, int], pixel_mm: float, xs: np.ndarray, ys: np.ndarray, margin_mm: float,
                 max_pixels: int, periodic: bool) -> list[Window]:
    """The windows of a map of ``shape`` pixels answering the footprint positions (``ys`` x ``xs``, mm), each of
    at most ``max_pixels`` pixels, row by row."""
    rows, cols = window_sizes(shape, max_pixels, math.ceil(margin_mm / pixel_mm) + 1 if periodic else None)
    along_y = split_axis(shape[0], rows, ys, pixel_mm, margin_mm, periodic)
    along_x = split_axis(shape[1], cols, xs, pixel_mm, margin_mm, periodic)
    return [Window(r, c) for r in along_y for c in along_x]

"""The square map every texture is made on: default side and pixel size (mm), and its checks."""
from __future__ import annotations

import os

from roughness.core.checks import integer, positive
from roughness.core.errors import InputError
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, MAX_LENGTH_MM, check_size
from roughness.surface.heightmap import pixel_size

SIZE_MM = 12.0  # side of a texture map (mm): the footprint plus a margin
PIXEL_MM = 0.05  # pixel size (mm)
WORK_ARRAYS = 6  # float64 maps a generator holds at once (spectrum, coordinates, heights, ...)


def map_side(size_mm: object, pixel_mm: object) -> int:
    """Pixels along each side of a map of side ``size_mm`` (mm); InputError unless both are valid (a positive
    size, a ``pixel_size``), the map has at most MAX_HEIGHTMAP_PIXELS and making it fits in this machine's memory."""
    side = positive("size_mm", size_mm) / pixel_size(pixel_mm)  # a float (inf for absurd sizes)
    blamed = "size_mm" if size_mm > MAX_LENGTH_MM else "pixel_mm"  # the one outside what a texture needs
    check_size(f"pixels of a map of size_mm={size_mm:g} at pixel_mm={pixel_mm:g}", side * side, MAX_HEIGHTMAP_PIXELS,
               blamed)
    n = round(side)
    if n < 1:
        raise InputError(f"size_mm={size_mm:g} is smaller than one pixel (pixel_mm={pixel_mm:g})", parameter="size_mm")
    need, have = n * n * 8 * WORK_ARRAYS, _memory_bytes()
    if need > have:
        raise InputError(f"a {size_mm:g} mm map of {pixel_mm:g} mm pixels is {n} x {n} pixels: {_size(n * n * 8)} "
                         f"per map, about {_size(need)} to make it, more than this machine's {_size(have)} of "
                         "memory; use a smaller size_mm or larger pixel_mm", parameter="size_mm")
    return n


def check_seed(seed: object) -> int:
    """``seed`` as an int, or InputError unless it is a non-negative integer."""
    return integer("seed", seed, minimum=0)


def _memory_bytes() -> int:
    return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")


def _size(n_bytes: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n_bytes < 1024 or unit == "TiB":
            return f"{n_bytes:.3g} {unit}"
        n_bytes /= 1024
    raise AssertionError("unreachable")

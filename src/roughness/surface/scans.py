"""Measured scans (.x3p, .sur, .plu, .datx, .gwy, .sdf, ...) read through SurfaceTopography.

SurfaceTopography (MIT, the optional extra ``roughness[scans]``) reads the instrument formats with
the units and pixel sizes they state; here they become millimetres, per axis, with the image
convention of this package (row i is y index i; SurfaceTopography indexes [x, y]). Only formats
that state their length units and were read cleanly are routed here (``FORMATS``); the reader is
chosen by suffix, not by sniffing. The size a file declares is checked against
MAX_HEIGHTMAP_PIXELS before its heights are read.

None of these readers executes anything from a file (checked in SurfaceTopography 1.27): they
parse binary headers, XML (x3p, with the standard library's parser), HDF5 (datx, through h5py) and
NetCDF 3 (scipy), with no pickle and no eval. .npy, .npz, .h5 and .tif are read by
roughness.surface.io; text, .mat and .xlsx (no units) and .nms (its sample reads 160 m wide) are
not routed here.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, check_size

EXTRA = 'pip install "roughness[scans]"'
# suffix -> SurfaceTopography format id; each states its length units and was read cleanly
# (see docs/how-to/real-surfaces.md)
FORMATS = {
    ".x3p": "x3p", ".sur": "sur", ".plu": "plu", ".datx": "datx", ".gwy": "gwy", ".sdf": "sdf", ".nc": "nc",
    ".al3d": "al3d", ".opd": "opd", ".frt": "frt", ".mnt": "mnt", ".tmd": "tmd", ".mi": "mi",
    ".nid": "ezd", ".bcrf": "bcr",
}
SUFFIXES = tuple(FORMATS)
MM_PER = {"m": 1e3, "mm": 1.0, "µm": 1e-3, "um": 1e-3, "nm": 1e-6, "Å": 1e-7, "pm": 1e-9, "km": 1e6}


@dataclass(frozen=True)
class Scan:
    """Heights (ny, nx) in mm of one channel of a scan file, pixel sizes per axis in mm, and what the file said."""

    heights: np.ndarray
    pixel_x_mm: float
    pixel_y_mm: float
    kind: str  # the reader's name, e.g. "Digital Surf SUR"
    unit: str  # the length unit the file states, e.g. "µm"
    channel: str


def read_scan(path: Path) -> Scan:
    """The default channel of the scan at ``path`` in mm; InputError for anything it cannot be."""
    fmt = FORMATS[path.suffix.lower()]
    try:
        import SurfaceTopography
    except ImportError:
        raise InputError(f"{path}: {path.suffix} scans are read by SurfaceTopography, which is not installed; "
                         f"{EXTRA}") from None
    kind = _format_name(fmt, path.suffix)
    try:
        reader = SurfaceTopography.open_topography(str(path), format=fmt)
        channel = reader.default_channel
        grid = tuple(int(n) for n in channel.nb_grid_pts)  # (nx, ny)
    except InputError:
        raise
    except Exception as err:  # a foreign parser of untrusted bytes: any failure is "cannot read"
        raise InputError(f"cannot read {path} as {kind}: {_reason(err)}") from None
    if len(grid) != 2:
        raise InputError(f"{path}: its channel {channel.name!r} is a line scan ({grid[0]:,} points), not a "
                         "height map")
    check_size(f"{path}: pixels its channel {channel.name!r} declares ({grid[0]:,} x {grid[1]:,})",
               math.prod(grid), MAX_HEIGHTMAP_PIXELS)
    if not getattr(channel, "is_uniform", True):
        raise InputError(f"{path}: its channel {channel.name!r} is not on a uniform grid; resample it in the "
                         "instrument's software")
    try:
        topography = reader.topography(channel.index)
        unit = topography.unit
        sizes = topography.physical_sizes
        heights = np.ma.filled(np.ma.asarray(topography.heights(), dtype=float), np.nan)
    except Exception as err:
        raise InputError(f"cannot read {path} as {kind}: {_reason(err)}") from None
    finally:
        close = getattr(reader, "close", None)
        if callable(close):
            close()
    scale = _mm_per(path, unit)
    if sizes is None or len(sizes) != 2 or not all(np.isfinite(s) and s > 0 for s in sizes):
        raise InputError(f"{path}: its channel {channel.name!r} states no physical size (got {sizes!r})")
    nx, ny = heights.shape  # SurfaceTopography: [x, y]
    return Scan(heights.T * scale, float(sizes[0]) * scale / nx, float(sizes[1]) * scale / ny, kind, unit,
                str(channel.name))


def _format_name(fmt: str, suffix: str) -> str:
    """The reader's name for messages (e.g. "Digital Surf SUR"), or the suffix."""
    from SurfaceTopography.IO import lookup_reader_by_format

    reader = lookup_reader_by_format.get(fmt)  # a dict: format id -> reader class
    return str(reader.name()) if reader is not None else suffix


def _mm_per(path: Path, unit: object) -> float:
    """Millimetres per unit of ``unit``, or InputError if the file states none or no length."""
    if unit is None:
        raise InputError(f"{path}: the file states no length unit for its heights; convert it to a format that "
                         "does, or export heights in mm to .npy and pass --pixel-mm")
    if isinstance(unit, (tuple, list)):
        units = set(unit)
        if len(units) != 1:
            raise InputError(f"{path}: its axes have different units {tuple(unit)}; expected one length unit")
        unit = units.pop()
    text = str(unit).replace("\u03bc", "\u00b5")  # GREEK SMALL LETTER MU -> MICRO SIGN
    if text not in MM_PER:
        raise InputError(f"{path}: its heights are in {unit!r}, not a length unit ({', '.join(MM_PER)})")
    return MM_PER[text]


def _reason(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    return f"{type(err).__name__}: {text[0]}" if text else type(err).__name__

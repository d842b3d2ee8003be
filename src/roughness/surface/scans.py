"""Measured scans (.x3p, .sur, .plu, .datx, .gwy, .sdf, ...) read through SurfaceTopography.

SurfaceTopography (MIT, the optional extra ``roughness[scans]``) reads the instrument formats with
the units and pixel sizes they state; here they become millimetres, per axis, with the image
convention of this package (row i is y index i; SurfaceTopography indexes [x, y]). Only formats
that state their length units and were read cleanly are routed here (``FORMATS``); the reader is
chosen by suffix, not by sniffing. The size a file declares is checked against
MAX_HEIGHTMAP_PIXELS before its heights are read, and the MD5 checksum an .x3p states for its
point data against the data; a file with no height channel (lengths on every axis) is refused.

None of these readers executes anything from a file (checked in SurfaceTopography 1.27): they
parse binary headers, XML (x3p, with the standard library's parser), HDF5 (datx, through h5py) and
NetCDF 3 (scipy), with no pickle and no eval. .npy, .npz, .h5 and .tif are read by
roughness.surface.io; text, .mat and .xlsx (no units) and .nms (its sample reads 160 m wide) are
not routed here.
"""
from __future__ import annotations

import hashlib
import math
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.parsers import expat

import numpy as np

from roughness.core.errors import InputError
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, Limit, check_size

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
        if not reader.channels:
            raise InputError(f"{path} holds no height map: none of its channels has heights and lateral axes in "
                             "units of length (a channel in volts, amperes or degrees is no height map); export "
                             "the height channel from the instrument's software")
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
    if fmt == "x3p":
        check_x3p_checksum(path)
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


def check_x3p_checksum(path: Path) -> None:
    """InputError unless the MD5 that an .x3p's main.xml states for its point data (MD5ChecksumPointData, ISO
    25178-72) is the data's; a file that states none passes. The data are hashed as they unpack (no copy)."""
    try:
        with zipfile.ZipFile(path) as archive:
            fields = _x3p_fields(path, archive.read("main.xml"), ("PointDataLink", "MD5ChecksumPointData"))
            link, stated = fields["PointDataLink"].strip(), fields["MD5ChecksumPointData"].strip().upper()
            if not link or not stated:
                return
            check_size(f"{path}: bytes of its point data {link}", archive.getinfo(link).file_size,
                       Limit(8 * MAX_HEIGHTMAP_PIXELS, "8 x MAX_HEIGHTMAP_PIXELS"))
            md5 = hashlib.md5()
            with archive.open(link) as data:
                for block in iter(lambda: data.read(1 << 20), b""):
                    md5.update(block)
    except (KeyError, OSError, EOFError, zipfile.BadZipFile) as err:
        raise InputError(f"cannot read {path} as X3P: {_reason(err)}") from None
    if md5.hexdigest().upper() != stated:
        raise InputError(f"{path}: its point data ({link}) do not match the MD5 checksum its main.xml states "
                         f"({stated}; the data's is {md5.hexdigest().upper()}): the file is damaged or was changed "
                         "after it was written; export it again from the instrument's software")


def _x3p_fields(path: Path, text: bytes, names: tuple[str, ...]) -> dict[str, str]:
    """The text of the elements ``names`` (local names) in an .x3p's main.xml ("" if absent), read with expat; an
    XML entity declaration is refused (an .x3p has none, and entities can expand without bound)."""
    found = dict.fromkeys(names, "")
    open_names: list[str] = []
    parser = expat.ParserCreate()

    def refuse(*_: object) -> None:
        raise InputError(f"{path}: its main.xml declares XML entities, which an .x3p never has: refused")

    def text_of(data: str) -> None:
        if open_names and open_names[-1] in found:
            found[open_names[-1]] += data

    parser.StartElementHandler = lambda name, _: open_names.append(name.rpartition(":")[2])
    parser.EndElementHandler = lambda _: open_names.pop()
    parser.CharacterDataHandler = text_of
    parser.EntityDeclHandler = refuse
    parser.UnparsedEntityDeclHandler = refuse
    try:
        parser.Parse(text, True)
    except expat.ExpatError as err:
        raise InputError(f"cannot read {path}: its main.xml is not XML ({expat.ErrorString(err.code)})") from None
    return found


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

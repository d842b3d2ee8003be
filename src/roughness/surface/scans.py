"""Measured scans read through SurfaceTopography: named formats by suffix, any other file by its own detection.

SurfaceTopography (MIT, the optional extra ``roughness[scans]``) reads the instrument formats with
the units and pixel sizes they state; here they become millimetres, per axis, with the image
convention of this package (row i is y index i; SurfaceTopography indexes [x, y]). One code path
reads every scan (``read_scan``): a suffix in ``FORMATS`` names the reader, any other suffix that
roughness.surface.io does not read itself goes to SurfaceTopography's own format detection
(which tries its readers in turn, each rejecting what its magic bytes rule out). Whatever the
reader, the file must state a length unit and hold a 2-D height map on a uniform grid: a line
scan, a file without units (text matrices without a unit header, Igor waves without one) and a
channel that is no height map are refused with that reason. The size a file declares is checked
against MAX_HEIGHTMAP_PIXELS before its heights are read, and the MD5 checksum an .x3p states for
its point data against the data.

A TIFF may carry instrument data beside a picture of it (Park Systems AFM TIFFs: an 8-bit colour
thumbnail in the image, the heights and their units in private tags 50432-50435);
``instrument_tiff`` finds the reader for such a file, so that its data are read, not its thumbnail.

None of these readers executes anything from a file (checked in SurfaceTopography 1.27: no pickle,
no eval): they parse binary headers, XML (x3p, zon, with the standard library's parser), HDF5 (datx,
through h5py), NetCDF 3 (scipy), MATLAB files (scipy's loadmat) and text. .npy, .npz, .h5 and .tif
are read by roughness.surface.io; .nms is refused (its sample reads 160 m wide: its sizes are not
trusted).
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
# suffix -> SurfaceTopography format id, for the formats a suffix names unambiguously (docs/how-to/real-surfaces.md);
# any other suffix goes to SurfaceTopography's detection (text, .mat, .dat, .csv, .xlsx, ...: several readers each)
FORMATS = {
    ".x3p": "x3p", ".sur": "sur", ".plu": "plu", ".apx": "plu", ".datx": "datx", ".gwy": "gwy", ".sdf": "sdf",
    ".nc": "nc", ".al3d": "al3d", ".opd": "opd", ".opdx": "opdx", ".frt": "frt", ".mnt": "mnt", ".tmd": "tmd",
    ".mi": "mi", ".nid": "ezd", ".ezd": "ezd", ".bcr": "bcr", ".bcrf": "bcr", ".di": "di", ".spm": "di",
    ".ibw": "ibw", ".zon": "zon", ".vk3": "vk", ".vk4": "vk", ".vk6": "vk", ".vk7": "vk", ".zmg": "zmg",
    ".mdt": "mdt", ".os3d": "os3d", ".lext": "lext", ".oir": "oir", ".poir": "poir", ".plux": "plux", ".jpk": "jpk",
    ".qep": "qep", ".stp": "wsxm", ".top": "wsxm", ".cur": "wsxm", ".tom": "wsxm",
}
SUFFIXES = tuple(FORMATS)
# formats refused whatever the suffix: sizes not trusted (the .nms sample reads 160 m wide), or read by io itself
REFUSED = {"nms": "its reader states sizes that are not trusted (SurfaceTopography's sample .nms reads 160 m wide)",
           "npy": "an .npy array (no units): name it .npy and pass pixel_mm",
           "npz": "an .npz archive: name it .npz", "h5": "an HDF5 file: name it .h5"}
NO_MAGIC = ("nms", "hgt")  # readers that accept any file of a plausible size: trusted only under their own suffix
TIFF_MIME = "image/tiff"
OWN_FORMATS = (".npy", ".npz", ".png", ".tif", ".h5")  # read by roughness.surface.io (for messages)
TEXT_BYTES_PER_VALUE = 16  # a number as text ("-1.234567e-05 "): the bytes a file may have per pixel it can hold
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


def read_scan(path: Path, fmt: str | None = None) -> Scan:
    """The default channel of the scan at ``path`` in mm; InputError for anything it cannot be.

    ``fmt``: SurfaceTopography's format id (default: the one ``FORMATS`` names for the suffix, else detected)."""
    fmt = fmt or FORMATS.get(path.suffix.lower())
    SurfaceTopography = _library(path)
    if fmt is None:  # detection may parse the whole file as text before any size is declared
        check_size(f"{path}: bytes of a file of unnamed format", path.stat().st_size,
                   Limit(TEXT_BYTES_PER_VALUE * MAX_HEIGHTMAP_PIXELS, f"{TEXT_BYTES_PER_VALUE} x MAX_HEIGHTMAP_PIXELS"))
    kind = _format_name(fmt, path.suffix) if fmt else "a scan"
    try:
        reader = SurfaceTopography.open_topography(str(path), format=fmt)
    except Exception as err:  # a foreign parser of untrusted bytes: any failure is "cannot read"
        raise _not_read(path, kind, err) from None
    try:
        detected, fmt = fmt is None, str(reader.format())
        kind = _format_name(fmt, path.suffix)
        if detected and fmt in NO_MAGIC and path.suffix.lower().lstrip(".") not in reader.file_extensions():
            raise InputError(f"{path}: {_unsupported(path)}, and none of the scan formats SurfaceTopography detects "
                             f"(only its {kind} reader, which has no magic bytes to check, took it)")
        if fmt in REFUSED:
            raise InputError(f"{path} is {kind}: {REFUSED[fmt]}")
        channel, grid = _height_channel(path, reader)
        check_size(f"{path}: pixels its channel {channel.name!r} declares ({grid[0]:,} x {grid[1]:,})",
                   math.prod(grid), MAX_HEIGHTMAP_PIXELS)
        if fmt == "x3p":
            check_x3p_checksum(path)
        topography = reader.topography(channel.index)
        unit = topography.unit
        sizes = topography.physical_sizes
        heights = np.ma.filled(np.ma.asarray(topography.heights(), dtype=float), np.nan)
    except InputError:
        raise
    except Exception as err:
        raise InputError(f"cannot read {path} as {kind}: {_reason(err)}") from None
    finally:
        close = getattr(reader, "close", None)
        if callable(close):
            close()
    scale = _mm_per(path, unit, kind)
    if sizes is None or len(sizes) != 2 or not all(np.isfinite(s) and s > 0 for s in sizes):
        raise InputError(f"{path}: its channel {channel.name!r} states no physical size (got {sizes!r})")
    nx, ny = heights.shape  # SurfaceTopography: [x, y]
    return Scan(heights.T * scale, float(sizes[0]) * scale / nx, float(sizes[1]) * scale / ny, kind, str(unit),
                str(channel.name))


def instrument_tiff(path: Path) -> str | None:
    """SurfaceTopography's format id if the TIFF at ``path`` carries instrument data that one of its TIFF-based
    readers (Park Systems, Olympus LEXT, ...) reads, else None (a picture: its pixels are the heights' grey levels).

    Without SurfaceTopography, a Park Systems TIFF (its private tag 50432) is refused: its image is a thumbnail."""
    try:
        from SurfaceTopography.IO import readers
    except ImportError:
        if _park_tag(path):
            raise InputError(f"{path} is a Park Systems AFM TIFF: its image is a colour thumbnail, its heights are in "
                             f"private tags that SurfaceTopography reads, which is not installed; {EXTRA}") from None
        return None
    for reader_class in readers:
        if TIFF_MIME not in (reader_class.mime_types() or ()):
            continue
        try:
            reader_class(str(path)).close()
        except Exception:  # not this vendor's TIFF (each reader checks its own tags)
            continue
        return str(reader_class.format())
    return None


def _park_tag(path: Path) -> bool:
    """Whether the TIFF at ``path`` has the Park Systems magic tag (50432) on its first page."""
    import tifffile

    try:
        with tifffile.TiffFile(path) as tif:
            return bool(tif.pages) and 50432 in tif.pages[0].tags
    except Exception:  # not a TIFF tifffile reads: io says so when it reads the image
        return False


def _library(path: Path):
    """The SurfaceTopography module, or InputError naming the extra that installs it."""
    try:
        import SurfaceTopography
    except ImportError:
        if path.suffix.lower() in FORMATS:
            raise InputError(f"{path}: {path.suffix} scans are read by SurfaceTopography, which is not installed; "
                             f"{EXTRA}") from None
        raise InputError(f"{path}: {_unsupported(path)}; other formats are read by SurfaceTopography, which is not "
                         f"installed; {EXTRA}") from None
    return SurfaceTopography


def _not_read(path: Path, kind: str, err: BaseException) -> InputError:
    """The error for a file that no reader (``kind`` "a scan": detection) or the named one could open."""
    if kind == "a scan" and type(err).__name__ == "CannotDetectFileFormat":
        return InputError(f"{path}: {_unsupported(path)}, and none of the scan formats SurfaceTopography detects")
    return InputError(f"cannot read {path} as {kind}: {_reason(err)}")


def _unsupported(path: Path) -> str:
    return (f"unsupported heightmap format {path.suffix.lower() or '(no suffix)'!r}: none of this tool's own "
            f"({', '.join(OWN_FORMATS)})")


def _height_channel(path: Path, reader) -> tuple[object, tuple[int, ...]]:
    """The default channel of an open reader and its grid (nx, ny); InputError if it is no 2-D uniform height map."""
    if not reader.channels:
        raise InputError(f"{path} holds no height map: none of its channels has heights and lateral axes in "
                         "units of length (a channel in volts, amperes or degrees is no height map); export "
                         "the height channel from the instrument's software")
    channel = reader.default_channel
    grid = tuple(int(n) for n in channel.nb_grid_pts)  # (nx, ny)
    if len(grid) != 2:
        raise InputError(f"{path}: its channel {channel.name!r} is a line scan ({grid[0]:,} points), not a height map: "
                         "a fingertip feels an area; scan an area of at least the 10 mm footprint")
    if not getattr(channel, "is_uniform", True):
        raise InputError(f"{path}: its channel {channel.name!r} is not on a uniform grid; resample it in the "
                         "instrument's software")
    return channel, grid


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


def _mm_per(path: Path, unit: object, kind: str) -> float:
    """Millimetres per unit of ``unit``, or InputError if the file states none or no length."""
    if unit is None:
        raise InputError(f"{path} ({kind}) states no length unit for its heights and pixels: its numbers could be "
                         "metres or nanometres; export it with units (e.g. .x3p or .gwy), or save heights in mm to "
                         ".npy and pass --pixel-mm")
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

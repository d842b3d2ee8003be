"""Reading and writing heightmap files (.npy, .npz, .png, .tif/.tiff, .h5/.hdf5).

Integer images map grey value v to height v / full_scale * height_mm (full_scale 255 for 8-bit,
65535 for 16-bit); .npy, .npz, .h5 and float TIFF files hold heights in mm. Image row i is y index i.
Measured scans (.x3p, .sur, .plu, .datx, .gwy, .sdf, ...: ``scans.FORMATS``), any file of another suffix
(through SurfaceTopography's format detection) and TIFFs that carry instrument data (a Park Systems AFM TIFF)
are read through SurfaceTopography (the extra ``roughness[scans]``) with the units and per-axis pixel sizes they
state.

Files this tool writes carry their units where the format allows, and the loader reads them back:
the pixel size (and for PNG the full-scale height and the base height) in a PNG text chunk, a TIFF
ImageDescription, an .npz array or an HDF5 attribute. Only .npy cannot: pass ``pixel_mm``.
A stated unit that disagrees with an explicit argument is an error, never silently overridden; the
one exception is the standard TIFF resolution tags (XResolution, YResolution, ResolutionUnit), read
as the pixel size when the file states nothing else, which picture software fills with 72 or 96 per
inch by habit: a given ``pixel_mm`` replaces them, with a note.
Pixels that are not square (a scan with 10 x 12 um pixels, or different TIFF X and Y resolutions)
are refused unless ``resample_square`` asks for bilinear resampling to the finer of the two sizes; sizes
within SQUARE_RTOL (0.1%: instrument round-off) are one square pixel, their mean, with a note.
Missing points (NaN) are refused by ``load_heightmap`` and ``read_heightmap``; ``read_heights`` keeps
them, for the loading pipeline's clean-up (roughness.surface.loading, which every command uses).
Every failure the user can cause is reported as an InputError naming the file and the problem.
The size a file declares is checked against MAX_HEIGHTMAP_PIXELS before its values are read, so a
small compressed file that would expand to gigabytes is refused without allocating them.
"""
from __future__ import annotations

import json
import math
import struct
import warnings
import zipfile
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from PIL import Image, PngImagePlugin

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.core.files import atomic_write
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, SQUARE_RTOL, Limit, check_size

from . import scans
from .heightmap import Heightmap
from .pixels import Resampling, square
from .stl import DEFAULT_BASE_MM, plate, stl_bytes

OWN_SUFFIXES = (".npy", ".npz", ".png", ".tif", ".tiff", ".h5", ".hdf5")
SUFFIXES = OWN_SUFFIXES + scans.SUFFIXES
SAVE_SUFFIXES = (".npy", ".npz", ".png", ".tif", ".tiff", ".h5", ".hdf5", ".stl")
DEFAULT_DATASET = "heightmap"
FULL_SCALE = {1: 255, 2: 65535}  # unsigned integer samples: bytes per sample -> white
PNG_16BIT = ("I;16", "I;16B", "I;16L")
PNG_ERRORS = (OSError, SyntaxError, ValueError, Image.DecompressionBombError)
UNITS_KEY = "roughness"  # PNG text chunk / TIFF description holding {"pixel_mm": ..., ...}
SAME_UNIT_RTOL = 1e-6  # a stated and a given unit this close are the same (float32 round trips)
MM_PER_RESOLUTION_UNIT = {2: 25.4, 3: 10.0, 4: 1.0, 5: 1e-3}  # TIFF ResolutionUnit: inch, cm, (tifffile) mm, um


@dataclass(frozen=True)
class _Raw:
    """File contents before units: values in mm if ``full_scale`` is None, else grey levels.

    ``pixel_mm``, ``height_mm`` and ``base_mm`` are what the file states (None if nothing);
    ``pixel_y_mm`` the pixel size along y where the file states one per axis (else ``pixel_mm`` is both);
    ``pixel_from`` where the stated pixel size comes from, if not the tool's own metadata.
    """

    values: np.ndarray
    kind: str  # e.g. "16-bit PNG", for messages
    full_scale: float | None = None
    pixel_mm: object = None
    height_mm: object = None
    base_mm: object = None
    pixel_y_mm: object = None
    pixel_from: str | None = None  # "scan" (instrument units) or "TIFF resolution tags"
    unit: str | None = None  # the length unit a scan states for its heights


@dataclass(frozen=True)
class Reading:
    """How a file was read: its format, units and pixel size, and what reading did to its values (a record:
    ``heightmap`` is the map itself only where ``read_heightmap`` made one; the loading pipeline's record,
    whose heights go on to clean-up, has None)."""

    path: str
    kind: str
    unit: str | None  # the file's length unit (scans), None where heights are mm or grey levels
    pixel_file_mm: tuple[float, float] | None  # (x, y) as the file states it, None if it states none
    pixel_from: str  # "file", "TIFF resolution tags" or "given" (pixel_mm)
    pixel_mm: float  # the square pixel of the heights, after any resampling
    resampling: Resampling | None = None
    own_units: bool = False  # heights already in mm: a height_mm given for other inputs was not applied
    notes: tuple[str, ...] = ()
    heightmap: Heightmap | None = field(default=None, repr=False, compare=False)

    def as_dict(self) -> dict:
        """The record for JSON output."""
        return {"file": self.path, "format": self.kind, "unit": self.unit,
                "pixel_file_mm": None if self.pixel_file_mm is None else list(self.pixel_file_mm),
                "pixel_from": self.pixel_from, "pixel_mm": self.pixel_mm,
                "resampled": None if self.resampling is None else self.resampling.as_dict(),
                "own_units": self.own_units, "notes": list(self.notes)}


def load_heightmap(path: str | Path, pixel_mm: float | None = None, height_mm: float | None = None,
                   dataset: str | None = None) -> Heightmap:
    """Heightmap (mm) from a file.

    ``pixel_mm`` (mm) is needed unless the file states it; ``height_mm`` is the height of
    full-scale white in integer images (mm), needed unless the file states it; a value that
    disagrees with the file's is an InputError. ``dataset`` names the HDF5 dataset (default
    "heightmap"). Non-square pixels are an InputError here: ``read_heightmap`` resamples them
    on request and says so.
    """
    reading = read_heightmap(path, pixel_mm, height_mm, dataset)
    if reading.notes:  # the pixel size taken from, or given over, TIFF resolution tags: said, not silent
        warnings.warn("; ".join(reading.notes), stacklevel=2)
    return reading.heightmap


def read_heightmap(path: str | Path, pixel_mm: float | None = None, height_mm: float | None = None,
                   dataset: str | None = None, resample_square: bool = False) -> Reading:
    """``load_heightmap``, with the record of how the file was read (for the reports and the JSON).

    ``resample_square``: resample non-square pixels bilinearly to square ones of the finer size
    (recorded in ``resampling`` and ``notes``) instead of refusing them. Missing points (NaN) are an
    InputError here; ``read_heights`` keeps them for clean-up.
    """
    heights, reading = read_heights(path, pixel_mm, height_mm, dataset, resample_square)
    return replace(reading, heightmap=_heightmap(reading.path, heights, reading.pixel_mm))


def read_heights(path: str | Path, pixel_mm: float | None = None, height_mm: float | None = None,
                 dataset: str | None = None, resample_square: bool = False,
                 height_for_others: bool = False) -> tuple[np.ndarray, Reading]:
    """Heights (ny, nx) in mm on square pixels of ``reading.pixel_mm``, NaN where the file has no value (as
    scanners mark missing points; a resampled pixel next to one is missing too), and how they were read.

    Units as in ``load_heightmap``; ``height_for_others``: ``height_mm`` was given for other inputs of the same
    command too, so a file whose heights are already mm keeps them (``own_units``, noted) instead of refusing it.
    Everything but the holes is checked as a Heightmap is (shape, size, Inf, MAX_HEIGHT_MM).
    """
    path = _existing_file(Path(path))
    suffix = path.suffix.lower()
    if dataset is not None and suffix not in (".h5", ".hdf5"):
        raise InputError(f"{path}: a dataset name applies only to .h5/.hdf5 files", parameter="dataset")
    pixel_mm = None if pixel_mm is None else positive("pixel_mm", pixel_mm)
    height_mm = None if height_mm is None else positive("height_mm", height_mm)
    if suffix == ".npy":
        raw = _read_npy(path)
    elif suffix == ".npz":
        raw = _read_npz(path)
    elif suffix == ".png":
        raw = _read_png(path)
    elif suffix in (".tif", ".tiff"):
        instrument = scans.instrument_tiff(path)
        raw = _read_scan(path, instrument) if instrument else _read_tiff(path)
    elif suffix in (".h5", ".hdf5"):
        raw = _read_h5(path, dataset or DEFAULT_DATASET)
    else:  # a named scan format, or any other file: SurfaceTopography's own detection
        raw = _read_scan(path)
    own = height_for_others and raw.full_scale is None and height_mm is not None
    heights, reading = _apply_units(path, raw, pixel_mm, None if own else height_mm, resample_square)
    if own:
        reading = replace(reading, own_units=True, notes=(*reading.notes, f"{path}: heights as the file states them "
                                                          "(height_mm applies to inputs of grey levels)"))
    holes = np.isnan(heights)
    _heightmap(str(path), np.where(holes, 0.0, heights), reading.pixel_mm)  # every check but the holes'
    if holes.all():
        raise InputError(f"{path}: every point is missing (NaN); nothing to fill from")
    return heights, reading


def _heightmap(path: str, heights: np.ndarray, pixel_mm: float) -> Heightmap:
    """A Heightmap, or InputError naming the file and the defect."""
    try:
        return Heightmap(heights, pixel_mm)
    except InputError as err:
        raise InputError(f"{path}: {err}", parameter=err.parameter) from None


def heightmap_files(folder: str | Path) -> list[Path]:
    """The heightmap files (by suffix) directly inside a folder, sorted by name; InputError if none."""
    folder = Path(folder)
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in SUFFIXES)
    if not files:
        raise InputError(f"{folder} holds no heightmap files ({', '.join(SUFFIXES)})")
    return files


def save_heightmap(hm: Heightmap, path: str | Path, height_mm: float | None = None,
                   base_mm: float | None = None, overwrite: bool = True) -> None:
    """Write ``hm`` atomically, with its pixel size wherever the format can hold it.

    .npy: heights in mm (no room for the pixel size); .npz and .h5: heights in mm and
    ``pixel_mm``; float32 .tif/.tiff: heights in mm, the pixel size in the ImageDescription
    (and as resolution tags for other software); 16-bit .png: (H - min) / height_mm * 65535,
    ``height_mm`` defaulting to the height range, with pixel size, full-scale height and the
    minimum in a text chunk, so that the file loads back without flags; .stl: a watertight
    printable plate in mm, the texture standing on ``base_mm`` of solid (default 2 mm; see
    ``stl.plate``), written but not read back. Unless ``overwrite``, an existing file is never
    replaced, not even by a concurrent writer (OutputExists).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SAVE_SUFFIXES:
        raise InputError(f"cannot save {path}: unsupported format {suffix or '(no suffix)'!r}; "
                         f"supported: {', '.join(SAVE_SUFFIXES)}", parameter="out")
    if height_mm is not None and suffix != ".png":
        raise InputError(f"cannot save {path}: height_mm applies only to PNG output", parameter="height_mm")
    if base_mm is not None and suffix != ".stl":
        raise InputError(f"cannot save {path}: base_mm applies only to STL output", parameter="base_mm")
    if not path.parent.is_dir():
        raise InputError(f"cannot write {path}: its folder does not exist", parameter="out")
    units = {"pixel_mm": hm.pixel_mm}
    if suffix == ".npy":
        atomic_write(path, lambda tmp: np.save(tmp, hm.heights), overwrite)
    elif suffix == ".npz":
        atomic_write(path, lambda tmp: np.savez_compressed(tmp, heightmap=hm.heights, pixel_mm=hm.pixel_mm), overwrite)
    elif suffix == ".png":
        counts, full = _png_counts(hm.heights, height_mm)
        info = PngImagePlugin.PngInfo()
        info.add_text(UNITS_KEY, json.dumps(units | {"height_mm": full, "base_mm": float(hm.heights.min())}))
        atomic_write(path, lambda tmp: Image.fromarray(counts).save(tmp, format="PNG", pnginfo=info), overwrite)
    elif suffix == ".stl":
        data = stl_bytes(plate(hm, DEFAULT_BASE_MM if base_mm is None else base_mm))
        atomic_write(path, lambda tmp: Path(tmp).write_bytes(data), overwrite)
    elif suffix in (".tif", ".tiff"):
        import tifffile

        per_cm = 10.0 / hm.pixel_mm
        atomic_write(path, lambda tmp: tifffile.imwrite(
            tmp, hm.heights.astype(np.float32), description=json.dumps({UNITS_KEY: units}),
            resolution=(per_cm, per_cm), resolutionunit="CENTIMETER", metadata=None), overwrite)
    else:
        atomic_write(path, lambda tmp: _write_h5(tmp, hm), overwrite)


def _write_h5(path: str, hm: Heightmap) -> None:
    import h5py

    with h5py.File(path, "w") as f:
        f.create_dataset(DEFAULT_DATASET, data=hm.heights).attrs["pixel_mm"] = hm.pixel_mm


def _existing_file(path: Path) -> Path:
    """``path`` if it is a regular file (or a link to one); a FIFO, socket or device is refused unopened (reading
    one could block)."""
    if path.is_dir():
        raise InputError(f"{path} is a directory, not a heightmap file")
    if not path.exists():
        raise InputError(f"heightmap file not found: {path}")
    if not path.is_file():
        raise InputError(f"{path} is not a regular file (a FIFO, socket or device): give a heightmap file")
    return path


def _unreadable(path: Path, kind: str, err: BaseException) -> InputError:
    return InputError(f"cannot read {path} as {kind}: {str(err) or type(err).__name__}")


def _apply_units(path: Path, raw: _Raw, pixel_mm: float | None, height_mm: float | None,
                 resample_square: bool = False) -> tuple[np.ndarray, Reading]:
    """``raw``'s heights in mm on square pixels (NaN kept) and the record; InputError names any missing,
    misplaced or contradicting unit."""
    notes: list[str] = []
    pixel_x, pixel_y, pixel_from = _pixels(path, raw, pixel_mm, notes)
    if raw.full_scale is None and height_mm is not None:
        carried = f"carry their unit ({raw.unit}) and are converted to mm" if raw.unit else "are already in mm"
        raise InputError(f"{path}: heights in {raw.kind} files {carried}; drop height_mm", parameter="height_mm")
    if raw.full_scale is not None:
        height_mm = _unit(path, "height_mm", raw.height_mm, height_mm)
    missing = []
    if pixel_x is None:
        missing.append("pixel_mm (pixel size in mm)")
    if raw.full_scale is not None and height_mm is None:
        missing.append("height_mm (height of full-scale white in mm)")
    if missing:
        raise InputError(f"{path}: {raw.kind} heightmaps need {' and '.join(missing)}; the file does not state it",
                         parameter=missing[0].split()[0])
    values = np.asarray(raw.values, dtype=float)
    if raw.full_scale is not None:
        values = values / raw.full_scale * height_mm
        if raw.base_mm is not None:
            values = values + _stated(path, "base_mm", raw.base_mm, positive_only=False)
    resampling = None
    if not math.isclose(pixel_x, pixel_y, rel_tol=SAME_UNIT_RTOL) and math.isclose(pixel_x, pixel_y,
                                                                                 rel_tol=SQUARE_RTOL):
        mean = (pixel_x + pixel_y) / 2
        notes.append(f"{path}: its pixels, {pixel_x:.6g} mm (x) by {pixel_y:.6g} mm (y), differ by "
                     f"{100 * abs(pixel_x - pixel_y) / max(pixel_x, pixel_y):.2g}%, less than {100 * SQUARE_RTOL:g}% "
                     f"(SQUARE_RTOL): read as square pixels of {mean:.6g} mm, their mean")
        pixel_x = pixel_y = mean
    if not math.isclose(pixel_x, pixel_y, rel_tol=SAME_UNIT_RTOL):
        if not resample_square:
            source = "as the file states them" if pixel_from == "file" else f"from its {pixel_from}"
            raise InputError(f"{path}: its pixels are not square: {pixel_x:.6g} mm (x) by {pixel_y:.6g} mm (y), "
                             f"{source}; the engines need square pixels: pass resample_square to resample it "
                             f"(bilinear) to square pixels of {min(pixel_x, pixel_y):.6g} mm",
                             parameter="resample_square")
        values, resampling = square(values, pixel_x, pixel_y)
        notes.append(f"{path}: {resampling.describe()}")
    stated = None if raw.pixel_mm is None else (float(raw.pixel_mm), float(raw.pixel_y_mm or raw.pixel_mm))
    return values, Reading(str(path), raw.kind, raw.unit, stated, pixel_from, min(pixel_x, pixel_y), resampling,
                           notes=tuple(notes))


def _pixels(path: Path, raw: _Raw, given: float | None, notes: list[str]) -> tuple[float | None, float | None, str]:
    """Pixel size (x, y) in mm and where it comes from: the file, its TIFF resolution tags, or ``given``.

    A given size must agree with what the file states, except TIFF resolution tags, which it replaces (noted)."""
    if raw.pixel_mm is None:
        return given, given, "given"
    if raw.pixel_from == "TIFF resolution tags":
        x, y = float(raw.pixel_mm), float(raw.pixel_y_mm)  # nan if a tag is unusable
        if given is None:
            x, y = _stated(path, "pixel_mm", x), _stated(path, "pixel_mm", y)
            notes.append(f"{path}: pixel size {x:.6g} mm (x) by {y:.6g} mm (y) from its TIFF resolution tags")
            return x, y, "TIFF resolution tags"
        if not (math.isclose(given, x, rel_tol=SAME_UNIT_RTOL) and math.isclose(given, y, rel_tol=SAME_UNIT_RTOL)):
            notes.append(f"{path}: its TIFF resolution tags say {x:.6g} mm (x) by {y:.6g} mm (y) pixels; "
                         f"pixel_mm = {given:g} mm was given and is used")
        return given, given, "given"
    if raw.pixel_y_mm is None:
        x = _unit(path, "pixel_mm", raw.pixel_mm, given)
        return x, x, "file"
    x, y = _stated(path, "pixel_mm", raw.pixel_mm), _stated(path, "pixel_mm", raw.pixel_y_mm)
    if given is not None and not (math.isclose(given, x, rel_tol=SAME_UNIT_RTOL)
                                  and math.isclose(given, y, rel_tol=SAME_UNIT_RTOL)):
        raise InputError(f"{path} states its pixel size with its unit ({raw.unit or 'mm'}): {x:.6g} mm (x) by "
                         f"{y:.6g} mm (y), but pixel_mm = {given:g} mm was given; drop the argument (the file's "
                         "units are used) or fix the file", parameter="pixel_mm")
    return x, y, "file"


def _unit(path: Path, name: str, stated: object, given: float | None) -> float | None:
    """The unit to use: the given one, the stated one, or InputError if both are there and differ."""
    if stated is None:
        return given
    stated = _stated(path, name, stated)
    if given is not None and not math.isclose(given, stated, rel_tol=SAME_UNIT_RTOL):
        raise InputError(f"{path} states {name} = {stated:g} mm, but {name} = {given:g} mm was given; "
                         "drop the argument or fix the file", parameter=name)
    return stated


def _stated(path: Path, name: str, value: object, positive_only: bool = True) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not math.isfinite(number) or (positive_only and number <= 0):
        raise InputError(f"{path}: the {name} it states is not a {'positive ' if positive_only else ''}"
                         f"finite number: {value!r}")
    return number


def _read_npy(path: Path) -> _Raw:
    try:
        with open(path, "rb") as f:
            if f.read(6) == np.lib.format.MAGIC_PREFIX:  # else not .npy: np.load names the problem
                f.seek(0)
                shape, dtype = _npy_header(f)
                _check_declared(path, shape, dtype)
                needed = f.tell() + math.prod(shape) * dtype.itemsize
                if path.stat().st_size < needed:
                    raise InputError(f"cannot read {path} as NPY: it declares {_shape_text(shape)} values of "
                                     f"{dtype} ({needed:,} bytes with its header) but holds "
                                     f"{path.stat().st_size:,} bytes (truncated?)")
        values = np.load(path, allow_pickle=False)
    except InputError:
        raise
    except (OSError, ValueError, EOFError) as err:
        raise _unreadable(path, "NPY", err) from None
    if not isinstance(values, np.ndarray):
        values.close()
        raise InputError(f"cannot read {path} as NPY: it is an .npz archive (rename it to .npz)")
    return _Raw(_float_mm(path, values), ".npy")


def _read_npz(path: Path) -> _Raw:
    try:
        with zipfile.ZipFile(path) as archive:  # each member's declared size, before any is decompressed
            for member in archive.namelist():
                if member.endswith(".npy"):
                    with archive.open(member) as f:
                        shape, dtype = _npy_header(f)
                        _check_declared(path, shape, dtype, f"array {member[:-4]!r}",
                                        real=member == f"{DEFAULT_DATASET}.npy")
        with np.load(path, allow_pickle=False) as archive:
            arrays = {name: archive[name] for name in archive.files}
    except InputError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as err:
        raise _unreadable(path, "NPZ", err) from None
    if DEFAULT_DATASET not in arrays:
        raise InputError(f"{path} has no array {DEFAULT_DATASET!r}; arrays in the file: {', '.join(arrays) or 'none'}")
    stated = arrays.get("pixel_mm")
    return _Raw(_float_mm(path, arrays[DEFAULT_DATASET]), ".npz", None, None if stated is None else _scalar(stated))


def _npy_header(f) -> tuple[tuple[int, ...], np.dtype]:
    """Shape and dtype an open .npy stream declares (ValueError if its header is not one); reads nothing more."""
    version = np.lib.format.read_magic(f)
    if version == (1, 0):
        shape, _, dtype = np.lib.format.read_array_header_1_0(f)
    elif version == (2, 0):
        shape, _, dtype = np.lib.format.read_array_header_2_0(f)
    else:
        raise ValueError(f"unsupported .npy format version {version[0]}.{version[1]} (expected 1.0 or 2.0)")
    return tuple(shape), dtype


def _check_declared(path: Path, shape: tuple[int, ...], dtype: np.dtype, what: str = "heightmap",
                    real: bool = True) -> None:
    """InputError unless the array a file declares has at most MAX_HEIGHTMAP_PIXELS pixels (colour
    samples of one pixel count once) and, if ``real``, real numbers; checked before the values are read."""
    shape = tuple(int(n) for n in shape)
    colour = len(shape) == 3 and shape[-1] in (3, 4)
    check_size(f"{path}: pixels its {what} declares ({_shape_text(shape)})", math.prod(shape[:2] if colour else shape),
               MAX_HEIGHTMAP_PIXELS)
    if real and dtype.kind not in "iuf":
        raise InputError(f"{path}: its {what} holds {dtype} values, not real numbers")


def _shape_text(shape: tuple[int, ...]) -> str:
    return " x ".join(f"{n:,}" for n in shape) or "1"


def _float_mm(path: Path, values: np.ndarray) -> np.ndarray:
    """Heights of a file that holds millimetres: an empty array and integers (their unit is a guess) are refused."""
    if values.size == 0:
        raise InputError(f"{path} holds no heights: an empty array ({_shape_text(values.shape)} values of "
                         f"{values.dtype})")
    if values.dtype.kind in "iu":
        raise InputError(f"{path} holds integers ({values.dtype}, {values.min()} to {values.max()}); "
                         f"{path.suffix} heights are millimetres as floating-point numbers: convert them to mm "
                         "(e.g. micrometres / 1000) and save as float, or save grey levels as a 16-bit PNG "
                         "with its full-scale height")
    return values


def _read_png(path: Path) -> _Raw:
    try:
        with open_image(path, MAX_HEIGHTMAP_PIXELS, formats=["PNG"]) as im:
            im.load()
            mode, values, text = im.mode, np.asarray(im), dict(getattr(im, "text", {}))
    except InputError:
        raise
    except PNG_ERRORS as err:
        raise _unreadable(path, "PNG", err) from None
    units = _units(path, text.get(UNITS_KEY))
    stated = {k: units.get(k) for k in ("pixel_mm", "height_mm", "base_mm")}
    if mode in ("L", "LA"):
        return _Raw(values if mode == "L" else values[..., 0], "8-bit PNG", 255, **stated)
    if mode in PNG_16BIT or (mode == "I" and values.min() >= 0 and values.max() <= 65535):
        return _Raw(values, "16-bit PNG", 65535, **stated)
    if mode in ("RGB", "RGBA"):
        return _Raw(_grey(path, values), "8-bit PNG", 255, **stated)
    if mode in ("P", "PA"):
        raise InputError(f"{path} is a palette (indexed-colour) PNG; save it as 8- or 16-bit greyscale")
    raise InputError(f"{path} has PNG image mode {mode!r}; expected 8- or 16-bit greyscale or RGB")


def _read_tiff(path: Path) -> _Raw:
    import tifffile  # loaded only for TIFF files (as h5py for HDF5): predict on a PNG stays quick to start

    try:
        with tifffile.TiffFile(path) as tif:
            if tif.series:
                _check_declared(path, tif.series[0].shape, tif.series[0].dtype, "image")
            values = tif.asarray() if tif.pages else None
            description = tif.pages[0].description if tif.pages else ""
            resolution = _resolution_mm(tif.pages[0]) if tif.pages else None
    except InputError:
        raise
    except (OSError, ValueError, struct.error) as err:
        raise _unreadable(path, "TIFF", err) from None
    if values is None:
        raise InputError(f"cannot read {path} as TIFF: it holds no image")
    colour = values.ndim == 3 and values.shape[-1] in (3, 4)
    stated = _units(path, _json_object(description).get(UNITS_KEY)).get("pixel_mm")
    tags = {"pixel_mm": stated}
    if stated is None and resolution is not None:
        tags = {"pixel_mm": resolution[0], "pixel_y_mm": resolution[1], "pixel_from": "TIFF resolution tags"}
    if values.dtype.kind == "f" and not colour:
        return _Raw(values, "float TIFF", None, **tags)
    if values.dtype.kind != "u" or values.dtype.itemsize not in FULL_SCALE:
        raise InputError(f"{path} has TIFF samples of type {values.dtype}, shape {values.shape}; expected "
                         "8- or 16-bit unsigned greyscale (or RGB), or float greyscale heights in mm")
    bits = 8 * values.dtype.itemsize
    return _Raw(_grey(path, values) if colour else values, f"{bits}-bit TIFF", FULL_SCALE[values.dtype.itemsize],
                **tags)


def _read_scan(path: Path, fmt: str | None = None) -> _Raw:
    scan = scans.read_scan(path, fmt)
    return _Raw(scan.heights, scan.kind, None, scan.pixel_x_mm, None, None, scan.pixel_y_mm, "scan", scan.unit)


def _resolution_mm(page) -> tuple[float, float] | None:
    """Pixel size (x, y) in mm from a TIFF page's XResolution, YResolution and ResolutionUnit (pixels per unit),
    or None if it has none or no physical unit (ResolutionUnit NONE). A missing unit is an inch (TIFF 6.0)."""
    tags = page.tags
    if "XResolution" not in tags or "YResolution" not in tags:
        return None
    unit = int(tags["ResolutionUnit"].value) if "ResolutionUnit" in tags else 2
    if unit not in MM_PER_RESOLUTION_UNIT:
        return None
    sizes = []
    for name in ("XResolution", "YResolution"):
        value = tags[name].value
        try:
            per_unit = value[0] / value[1] if isinstance(value, tuple) else float(value)
        except (TypeError, ValueError, ZeroDivisionError, IndexError):
            per_unit = math.nan
        sizes.append(MM_PER_RESOLUTION_UNIT[unit] / per_unit if math.isfinite(per_unit) and per_unit > 0 else math.nan)
    return sizes[0], sizes[1]


def _read_h5(path: Path, name: str) -> _Raw:
    import h5py

    try:
        with h5py.File(path, "r") as f:
            node = f.get(name)
            if not isinstance(node, h5py.Dataset):
                raise InputError(f"{path} has no dataset {name!r}; datasets in the file: "
                                 f"{', '.join(_dataset_names(f)) or 'none'}")
            _check_declared(path, node.shape, node.dtype, f"dataset {name!r}")
            stated = node.attrs.get("pixel_mm", f.attrs.get("pixel_mm"))
            return _Raw(_float_mm(path, np.asarray(node[()])), "HDF5", None, None if stated is None else _scalar(stated))
    except InputError:
        raise
    except (OSError, ValueError, KeyError) as err:
        raise _unreadable(path, "HDF5", err) from None


def open_image(path: Path, limit: Limit, parameter: str | None = None, formats: list[str] | None = None):
    """A PIL image opened lazily (pixels not decoded), or InputError if it declares more than ``limit`` pixels.

    PIL's own decompression-bomb warning and error are replaced by this check and its message."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            image = Image.open(path, formats=formats)
    except Image.DecompressionBombError:  # PIL refuses above twice its MAX_IMAGE_PIXELS: more than ours
        raise InputError(f"{path} declares an image of more than {2 * Image.MAX_IMAGE_PIXELS:,} pixels: above the "
                         f"limit of {limit:,} ({limit.name})", parameter=parameter) from None
    width, height = image.size
    try:
        check_size(f"{path}: pixels it declares ({width:,} x {height:,})", width * height, limit, parameter)
    except InputError:
        image.close()
        raise
    return image


def _dataset_names(f) -> list[str]:
    """Paths of the datasets in an open h5py file."""
    import h5py

    names: list[str] = []
    f.visititems(lambda name, node: names.append(name) if isinstance(node, h5py.Dataset) else None)
    return names


def _scalar(value: object) -> object:
    """A one-element attribute as a Python scalar; anything else unchanged (rejected later)."""
    array = np.asarray(value)
    return array.item() if array.size == 1 else value


def _grey(path: Path, rgb: np.ndarray) -> np.ndarray:
    """Grey levels of an (ny, nx, 3|4) image whose R = G = B; a colour image is an InputError."""
    colour = rgb[..., :3]
    if np.array_equal(colour[..., 0], colour[..., 1]) and np.array_equal(colour[..., 0], colour[..., 2]):
        return colour[..., 0]
    raise InputError(f"{path} is a colour image (its red, green and blue differ), not a greyscale heightmap; "
                     "heights are read from grey levels: convert it to greyscale if its brightness really "
                     "encodes height")


def _units(path: Path, text: object) -> dict:
    """The units a file states in its ``roughness`` metadata (a JSON object), or {}."""
    if text is None:
        return {}
    units = _json_object(text) if isinstance(text, str) else text
    if not isinstance(units, dict):
        raise InputError(f"{path}: its {UNITS_KEY!r} metadata is not a JSON object: {text!r}")
    return units


def _json_object(text: str) -> dict:
    try:
        value = json.loads(text)
    except (TypeError, ValueError):
        return {}
    return value if isinstance(value, dict) else {}


def _png_counts(heights: np.ndarray, height_mm: float | None) -> tuple[np.ndarray, float]:
    """16-bit grey levels of (heights - min) over the full-scale height (default: the range, mm), and that height."""
    low = float(heights.min())
    span = float(heights.max()) - low
    scale = span if height_mm is None else positive("height_mm", height_mm)
    if span > scale:
        raise InputError(f"height_mm={height_mm} is below the map's height range {span:.6g} mm; the PNG would clip",
                         parameter="height_mm")
    if scale == 0:
        return np.zeros(heights.shape, dtype=np.uint16), 1.0
    return np.clip(np.rint((heights - low) / scale * 65535), 0, 65535).astype(np.uint16), scale




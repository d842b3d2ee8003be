"""Reading and writing heightmap files (.npy, .png, .tif/.tiff, .h5/.hdf5).

Integer images map grey value v to height v / full_scale * height_mm (full_scale 255 for 8-bit,
65535 for 16-bit); .npy, .h5 and float TIFF files hold heights in mm. Image row i is y index i.
Every failure the user can cause is reported as an InputError naming the file and the problem.
"""
from __future__ import annotations

import struct
import warnings
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import tifffile
from PIL import Image

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.core.files import atomic_write

from .heightmap import Heightmap

SUFFIXES = (".npy", ".png", ".tif", ".tiff", ".h5", ".hdf5")
SAVE_SUFFIXES = (".npy", ".png", ".tif", ".tiff")
DEFAULT_DATASET = "heightmap"
LUMINANCE = np.array([0.299, 0.587, 0.114])  # ITU-R BT.601 weights of R, G, B
FULL_SCALE = {1: 255, 2: 65535}  # unsigned integer samples: bytes per sample -> white
PNG_16BIT = ("I;16", "I;16B", "I;16L")
PNG_ERRORS = (OSError, SyntaxError, ValueError, Image.DecompressionBombError)


@dataclass(frozen=True)
class _Raw:
    """File contents before units: values in mm if ``full_scale`` is None, else grey levels."""

    values: np.ndarray
    kind: str  # e.g. "16-bit PNG", for messages
    full_scale: float | None = None
    pixel_mm: object = None  # as stated in the file, validated with the other units


def load_heightmap(path: str | Path, pixel_mm: float | None = None, height_mm: float | None = None,
                   dataset: str | None = None) -> Heightmap:
    """Heightmap (mm) from a file; ``pixel_mm`` overrides a pixel size stated in an HDF5 file.

    ``height_mm`` is the height of full-scale white in integer images; ``dataset`` names the
    HDF5 dataset (default "heightmap").
    """
    path = _existing_file(Path(path))
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise InputError(f"{path}: unsupported heightmap format {suffix or '(no suffix)'!r}; "
                         f"supported: {', '.join(SUFFIXES)}")
    if dataset is not None and suffix not in (".h5", ".hdf5"):
        raise InputError(f"{path}: a dataset name applies only to .h5/.hdf5 files")
    pixel_mm = None if pixel_mm is None else positive("--pixel-mm", pixel_mm)
    height_mm = None if height_mm is None else positive("--height-mm", height_mm)
    if suffix == ".npy":
        raw = _read_npy(path)
    elif suffix == ".png":
        raw = _read_png(path)
    elif suffix in (".tif", ".tiff"):
        raw = _read_tiff(path)
    else:
        raw = _read_h5(path, dataset or DEFAULT_DATASET)
    return _to_heightmap(path, raw, pixel_mm, height_mm)


def heightmap_files(folder: str | Path) -> list[Path]:
    """The heightmap files (by suffix) directly inside a folder, sorted by name; InputError if none."""
    folder = Path(folder)
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in SUFFIXES)
    if not files:
        raise InputError(f"{folder} holds no heightmap files ({', '.join(SUFFIXES)})")
    return files


def save_heightmap(hm: Heightmap, path: str | Path, height_mm: float | None = None) -> None:
    """Write ``hm`` atomically: .npy (mm), 16-bit .png or float32 .tif/.tiff (mm).

    PNG stores (H - min) / height_mm * 65535, ``height_mm`` defaulting to the height range
    (a flat map is all zeros); the pixel size and the minimum height are not stored.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SAVE_SUFFIXES:
        raise InputError(f"cannot save {path}: unsupported format {suffix or '(no suffix)'!r}; "
                         f"supported: {', '.join(SAVE_SUFFIXES)}")
    if height_mm is not None and suffix != ".png":
        raise InputError(f"cannot save {path}: height_mm applies only to PNG output")
    if not path.parent.is_dir():
        raise InputError(f"cannot write {path}: its folder does not exist")
    if suffix == ".npy":
        atomic_write(path, lambda tmp: np.save(tmp, hm.heights))
    elif suffix == ".png":
        counts = _png_counts(hm.heights, height_mm)
        atomic_write(path, lambda tmp: Image.fromarray(counts).save(tmp, format="PNG"))
    else:
        atomic_write(path, lambda tmp: tifffile.imwrite(tmp, hm.heights.astype(np.float32)))


def _existing_file(path: Path) -> Path:
    if path.is_dir():
        raise InputError(f"{path} is a directory, not a heightmap file")
    if not path.exists():
        raise InputError(f"heightmap file not found: {path}")
    return path


def _unreadable(path: Path, kind: str, err: BaseException) -> InputError:
    return InputError(f"cannot read {path} as {kind}: {str(err) or type(err).__name__}")


def _to_heightmap(path: Path, raw: _Raw, pixel_mm: float | None, height_mm: float | None) -> Heightmap:
    """Apply units to ``raw``; InputError names any missing or misplaced flag."""
    if pixel_mm is None and raw.pixel_mm is not None:
        pixel_mm = positive(f"the pixel_mm attribute of {path}", raw.pixel_mm)
    missing = []
    if pixel_mm is None:
        missing.append("--pixel-mm (pixel size in mm)")
    if raw.full_scale is not None and height_mm is None:
        missing.append("--height-mm (height of full-scale white in mm)")
    if missing:
        raise InputError(f"{path}: {raw.kind} heightmaps need {' and '.join(missing)}")
    if raw.full_scale is None and height_mm is not None:
        raise InputError(f"{path}: heights in {raw.kind} files are already in mm; drop --height-mm")
    values = raw.values
    if raw.full_scale is not None:
        values = values / raw.full_scale * height_mm
    try:
        return Heightmap(values, pixel_mm)
    except InputError as err:
        raise InputError(f"{path}: {err}") from None


def _read_npy(path: Path) -> _Raw:
    try:
        values = np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError) as err:
        raise _unreadable(path, "NPY", err) from None
    if not isinstance(values, np.ndarray):
        values.close()
        raise InputError(f"cannot read {path} as NPY: it is an .npz archive")
    return _Raw(values, ".npy")


def _read_png(path: Path) -> _Raw:
    try:
        with Image.open(path, formats=["PNG"]) as im:
            im.load()
            mode, values = im.mode, np.asarray(im)
    except PNG_ERRORS as err:
        raise _unreadable(path, "PNG", err) from None
    if mode in ("L", "LA"):
        return _Raw(values if mode == "L" else values[..., 0], "8-bit PNG", 255)
    if mode in PNG_16BIT or (mode == "I" and values.min() >= 0 and values.max() <= 65535):
        return _Raw(values, "16-bit PNG", 65535)
    if mode in ("RGB", "RGBA"):
        return _Raw(_grey(path, values), "8-bit PNG", 255)
    if mode in ("P", "PA"):
        raise InputError(f"{path} is a palette (indexed-colour) PNG; save it as 8- or 16-bit greyscale")
    raise InputError(f"{path} has PNG image mode {mode!r}; expected 8- or 16-bit greyscale or RGB")


def _read_tiff(path: Path) -> _Raw:
    try:
        with tifffile.TiffFile(path) as tif:
            values = tif.asarray() if tif.pages else None
    except (OSError, ValueError, struct.error) as err:
        raise _unreadable(path, "TIFF", err) from None
    if values is None:
        raise InputError(f"cannot read {path} as TIFF: it holds no image")
    colour = values.ndim == 3 and values.shape[-1] in (3, 4)
    if values.dtype.kind == "f" and not colour:
        return _Raw(values, "float TIFF")
    if values.dtype.kind != "u" or values.dtype.itemsize not in FULL_SCALE:
        raise InputError(f"{path} has TIFF samples of type {values.dtype}, shape {values.shape}; expected "
                         "8- or 16-bit unsigned greyscale (or RGB), or float greyscale heights in mm")
    bits = 8 * values.dtype.itemsize
    return _Raw(_grey(path, values) if colour else values, f"{bits}-bit TIFF", FULL_SCALE[values.dtype.itemsize])


def _read_h5(path: Path, name: str) -> _Raw:
    try:
        with h5py.File(path, "r") as f:
            node = f.get(name)
            if not isinstance(node, h5py.Dataset):
                raise InputError(f"{path} has no dataset {name!r}; datasets in the file: "
                                 f"{', '.join(_dataset_names(f)) or 'none'}")
            stated = node.attrs.get("pixel_mm", f.attrs.get("pixel_mm"))
            return _Raw(np.asarray(node[()]), "HDF5", None, None if stated is None else _scalar(stated))
    except InputError:
        raise
    except (OSError, ValueError, KeyError) as err:
        raise _unreadable(path, "HDF5", err) from None


def _dataset_names(f: h5py.File) -> list[str]:
    names: list[str] = []
    f.visititems(lambda name, node: names.append(name) if isinstance(node, h5py.Dataset) else None)
    return names


def _scalar(value: object) -> object:
    """A one-element attribute as a Python scalar; anything else unchanged (rejected later)."""
    array = np.asarray(value)
    return array.item() if array.size == 1 else value


def _grey(path: Path, rgb: np.ndarray) -> np.ndarray:
    """Grey levels of an (ny, nx, 3|4) colour image: the common value if R = G = B, else BT.601 luminance."""
    colour = rgb[..., :3]
    if np.array_equal(colour[..., 0], colour[..., 1]) and np.array_equal(colour[..., 0], colour[..., 2]):
        return colour[..., 0]
    warnings.warn(f"{path} is a colour image; using its luminance as the grey level", stacklevel=4)
    return colour @ LUMINANCE


def _png_counts(heights: np.ndarray, height_mm: float | None) -> np.ndarray:
    """16-bit grey levels of (heights - min) over ``height_mm`` (default: the height range, mm)."""
    low = float(heights.min())
    span = float(heights.max()) - low
    scale = span if height_mm is None else positive("height_mm", height_mm)
    if span > scale:
        raise InputError(f"height_mm={height_mm} is below the map's height range {span:.6g} mm; the PNG would clip")
    if scale == 0:
        return np.zeros(heights.shape, dtype=np.uint16)
    return np.clip(np.rint((heights - low) / scale * 65535), 0, 65535).astype(np.uint16)



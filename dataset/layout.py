"""A dataset on disk, as the writer and the readers both find it: the HDF5 file and its parts folder.

The HDF5 file's layout is described in ``schema``. Beside it, the folder ``<file>.parts/`` holds the
finished samples not yet packed into the file: one ``<id>.npz`` each, its index entry (JSON of the
``Entry`` fields, array ``entry``) and its maps (``MAPS`` and ``grid_axis_mm``). Names starting with
"." are temporary files of a writer.
"""
from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import h5py
import numpy as np

from roughness.core.errors import InputError
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, check_size

from .schema import (
    ADDED_FIELDS,
    ENTRY_FIELDS,
    TEXT_FIELDS,
    TUPLE_FIELDS,
    Entry,
    Header,
    as_tuples,
    entry_from_attrs,
    read_header,
)

MAPS = ("heightmap", "fluctuation")


def parts_folder(path: str | os.PathLike) -> Path:
    """The sidecar folder of finished, not yet packed samples of dataset ``path``."""
    path = Path(path)
    return path.with_name(path.name + ".parts")


def open_h5(path: Path) -> h5py.File:
    """The dataset file opened for reading; InputError if it is missing, not a file or not HDF5."""
    if not path.exists():
        raise InputError(f"no dataset file {path}")
    if not path.is_file():
        raise InputError(f"{path} is not a file")
    try:
        return h5py.File(path, "r")
    except OSError as err:
        raise InputError(f"{path} is not an HDF5 file or is damaged ({err})") from None


def read_index(h5: h5py.File, path: Path, context: str = "is") -> tuple[Header, dict[str, Entry]]:
    """Header and index entries (sorted by id) of an open file; InputError if it is not a dataset."""
    header = read_header(h5.attrs, f"{path} {context}")
    try:
        if header.schema_version == 1:
            journal = path.with_name(path.name + "-journal")
            if journal.exists() and journal.stat().st_size:
                raise InputError(f"{path} was left by an interrupted writer of an older roughness (page journal "
                                 f"{journal.name}); finish it with that version")
            return header, {n: entry_from_attrs(n, g.attrs) for n, g in sorted(h5["samples"].items())
                            if not n.startswith(".tmp-")}
        index = h5["index"]
        # Columns added after version 2 first shipped (ADDED_FIELDS) may be absent: their defaults.
        names = [n for n in ENTRY_FIELDS if n in index or n not in ADDED_FIELDS]
        columns = [index[n].asstr()[()] if n in TEXT_FIELDS else index[n][()] for n in names]
    except KeyError as err:
        raise InputError(f"{path} {context} is not a roughness dataset: {err}") from None
    except OSError as err:  # HDF5's "can't read data" of a damaged chunk or header
        raise InputError(f"{path}: its index cannot be read ({err}): the file is damaged") from None
    columns = [[tuple(h.tolist()) for h in c] if n in TUPLE_FIELDS else c.tolist()
               for n, c in zip(names, columns)]
    return header, {row[0]: Entry(**dict(zip(names, row))) for row in zip(*columns)}


def read_part(file: Path) -> tuple[Entry, dict[str, np.ndarray]]:
    """Index entry and maps of one part file; FileNotFoundError if it is gone (packed meanwhile), InputError naming
    it if it is damaged."""
    try:
        with np.load(file, allow_pickle=False) as npz:
            data = {name: npz[name] for name in npz.files}
        values = json.loads(str(data.pop("entry")))
        return Entry(**as_tuples(values)), data
    except FileNotFoundError:
        raise
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile) as err:
        raise InputError(f"{file}: a finished sample's part file that cannot be read ({type(err).__name__}: {err}): "
                         "it is damaged; delete it to simulate the sample again") from None


def part_ids(folder: Path) -> list[str]:
    """Ids of the samples in parts folder ``folder`` (none if it does not exist), sorted."""
    try:
        names = os.listdir(folder)
    except FileNotFoundError:
        return []
    return sorted(n[:-4] for n in names if n.endswith(".npz") and not n.startswith("."))


def sample_maps(h5: h5py.File, sid: str) -> dict[str, np.ndarray]:
    """The maps of packed sample ``sid`` (``group_maps``); InputError naming the file and the sample if HDF5 cannot
    read them (a damaged chunk or header)."""
    try:
        return group_maps(h5["samples"][sid])
    except OSError as err:
        raise InputError(f"{h5.filename}: sample {sid} cannot be read ({err}): the file is damaged; `roughness "
                         "dataset verify` lists every damaged sample") from None


def group_maps(group: h5py.Group) -> dict[str, np.ndarray]:
    """The maps of a packed sample's group (those it has), with ``grid_axis_mm`` if it has a fluctuation map."""
    maps = {}
    for name in MAPS:
        try:
            data = group[name]
        except KeyError:
            continue
        check_size(f"{group.file.filename}: values of {group.name}/{name} ({data.shape})", data.size,
                   MAX_HEIGHTMAP_PIXELS)  # declared: checked before a compressed map is expanded
        maps[name] = data[()]
    if "fluctuation" in maps:
        maps["grid_axis_mm"] = data.attrs["grid_axis_mm"]
    return maps

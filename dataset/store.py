"""HDF5 store of FEM training samples: one file per dataset, one writer, crash safe, readable throughout.

The file layout is described in ``schema``. The HDF5 file is never changed in place (HDF5 updates
its metadata in place, so a writer killed mid-flush can leave a file that no longer opens):

- ``DatasetWriter`` writes each finished sample atomically as its own file ``<id>.npz`` in the
  sidecar folder ``<file>.parts/`` (``atomic_write``: a temporary file renamed into place);
- its ``close`` packs them: a copy of the HDF5 file plus the new samples and a rewritten index,
  renamed over the file (``atomic_write``), after which the parts are deleted.

Readers take the parts, then open the HDF5 file, so a pack in between loses nothing; a sample both
packed and still a part (writer killed before deleting the parts) counts once.

Guarantee: whenever the writer stops (SIGKILL, SIGINT or an exception, at any point), the dataset
(file plus parts) holds every sample whose ``write_*`` call returned, each complete, and nothing
else; the next writer packs what is left. Temporary files are ignored by readers and removed by the
next writer. One writer per file: it holds an ``flock`` on the parts folder. POSIX only.
"""
from __future__ import annotations

import fcntl
import json
import math
import os
import re
import shutil
from collections import Counter
from collections.abc import Iterator
from dataclasses import asdict, dataclass, fields
from datetime import datetime, timezone
from pathlib import Path

import h5py
import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.core.files import atomic_write
from roughness.core.hashing import canonical_json
from roughness.core.provenance import Provenance
from roughness.core.limits import MAX_HEIGHTMAP_PIXELS, check_size
from roughness.surface.heightmap import Heightmap

from .schema import (
    ADDED_FIELDS,
    ENTRY_FIELDS,
    OPTIONAL_FLOATS,
    RESULT_ARRAYS,
    RESULT_ATTRS,
    SCHEMA,
    SCHEMA_VERSION,
    STATUSES,
    TEXT_FIELDS,
    TUPLE_FIELDS,
    DatasetConfig,
    Entry,
    Header,
    as_tuples,
    entry_from_attrs,
    header_problems,
    ladder_columns,
    read_header,
    result_fields,
    sample_id,
)

__all__ = ["SCHEMA", "Dataset", "DatasetWriter", "Sample", "info", "open_dataset", "parts_folder", "result_fields",
           "sample_id", "verify"]
MAPS = ("heightmap", "fluctuation")
_COLUMN_TYPES = {"float": "f8", "int": "i8", "bool": "?"}


def parts_folder(path: str | os.PathLike) -> Path:
    """The sidecar folder of finished, not yet packed samples of dataset ``path``."""
    path = Path(path)
    return path.with_name(path.name + ".parts")


# ---------------------------------------------------------------------------------------------
# Writer


class DatasetWriter:
    """Single writer of a dataset file (created with its first sample, else added to); a context manager.

    ``config`` says how the samples are made (``DatasetConfig``, or its dict form); adding to a file
    requires the same configuration. ``version`` is the package version (stored).
    """

    def __init__(self, path: str | os.PathLike, config: DatasetConfig | dict, version: str,
                 provenance: Provenance | None = None) -> None:
        self.path = Path(path)
        self._provenance = provenance  # stored as the root attribute ``provenance`` (JSON) by the last writer
        self.config = config if isinstance(config, DatasetConfig) else DatasetConfig.parse(config)
        self._version = version
        self._parts = parts_folder(self.path)
        self._lock = _claim(self._parts, self.path)
        try:
            entries, self._old_layout = {}, False
            if self.path.exists():
                with _open_h5(self.path) as h5:
                    header, entries = _read_index(h5, self.path, "exists and")
                if header.config != self.config:
                    raise InputError(f"{self.path} was made with another configuration "
                                     f"({header.config.differences(self.config)}); use a new file for this one")
                self._old_layout = header.schema_version < SCHEMA_VERSION  # converted on close
            _remove_temporaries(self.path)  # of this dataset's writers: checked to be one above
            self._ids = set(entries) | set(_part_ids(self._parts))
        except BaseException:
            self._release()
            raise

    @property
    def ids(self) -> frozenset[str]:
        """Ids of the samples in the dataset, failed ones included."""
        return frozenset(self._ids)

    def write_result(self, recipe: dict, heightmap: np.ndarray, pixel_mm: float, result_fields: dict,
                     fluctuation: np.ndarray) -> bool:
        """Store a simulated sample (heights in mm); False, writing nothing, if its id is present.

        ``result_fields`` holds the keys of RESULT_ATTRS and RESULT_ARRAYS (see ``result_fields()``).
        """
        values = _result_values(result_fields)
        maps = {"heightmap": _map("heightmap", heightmap), "fluctuation": _map("fluctuation", fluctuation),
                "grid_axis_mm": np.asarray(result_fields["grid_axis_mm"], dtype=float)}
        return self._write(recipe, pixel_mm, "ok", values, maps)

    def write_labelled(self, recipe: dict, heightmap: np.ndarray | None, pixel_mm: float, values: dict) -> bool:
        """Store a sample with a result computed before (``labels.Label.values``: Entry fields, its time and
        version of writing kept); no fluctuation map. False, writing nothing, if its id is present."""
        status = values["status"]
        maps = {} if heightmap is None else {"heightmap": _map("heightmap", heightmap, finite=status == "ok")}
        rest = {k: v for k, v in values.items() if k != "status"}
        return self._write(recipe, pixel_mm, status, {**rest, "restored": True}, maps)

    def write_failure(self, recipe: dict, heightmap: np.ndarray | None, pixel_mm: float, error: str) -> bool:
        """Record a sample whose simulation failed and why; False, writing nothing, if its id is present."""
        if not isinstance(error, str) or not error.strip():
            raise ValueError("a failure needs its reason as a non-empty string")
        maps = {} if heightmap is None else {"heightmap": _map("heightmap", heightmap, finite=False)}
        return self._write(recipe, pixel_mm, "failed", {"error": error}, maps)

    def close(self) -> None:
        """Pack the finished samples into the file (and a version-1 file into version 2); release it (idempotent)."""
        if self._lock < 0:
            return
        try:
            if _part_ids(self._parts) or self._old_layout:
                self._pack()
        finally:
            self._release()

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _write(self, recipe: dict, pixel_mm: float, status: str, values: dict, maps: dict) -> bool:
        if not isinstance(recipe, dict) or not isinstance(recipe.get("family"), str):
            raise ValueError(f"a recipe is a dict with a 'family' string, got {recipe!r}")
        values = {"written": _now(), "roughness_version": self._version, **values}
        entry = Entry(id=sample_id(recipe), recipe=canonical_json(recipe), family=recipe["family"], status=status,
                      **as_tuples({**values, "pixel_mm": positive("pixel_mm", pixel_mm)}))
        if self._lock < 0:
            raise ValueError(f"the writer of {self.path} is closed")
        if entry.id in self._ids:
            return False
        if not self.path.exists():
            self._pack()  # the file exists (an empty dataset) once the first sample is on its way
        arrays = {"entry": np.array(json.dumps(asdict(entry))), **maps}
        atomic_write(self._parts / f"{entry.id}.npz", lambda tmp: np.savez_compressed(tmp, **arrays))
        self._ids.add(entry.id)
        return True

    def _pack(self) -> None:
        """Write the file anew with every part in it (atomically), then delete the parts."""
        ids = _part_ids(self._parts)

        def write(tmp: str) -> None:
            base = self.path.exists()
            if base:
                shutil.copyfile(self.path, tmp)
            with h5py.File(tmp, "r+" if base else "w") as h5:
                if base:
                    header, entries = _read_index(h5, self.path, "exists and")
                else:
                    header, entries = Header(self.config, self._version, _now()), {}
                samples = h5.require_group("samples")
                for name in [n for n in samples if n not in entries]:
                    del samples[name]  # unfinished samples of a version-1 writer
                for sid in ids:
                    if sid not in entries:
                        entries[sid], maps = _read_part(self._parts / f"{sid}.npz")
                        _put_maps(samples.create_group(sid), maps)
                h5.attrs.update(Header(header.config, header.roughness_version, header.created).attrs())
                if self._provenance is not None:
                    h5.attrs["provenance"] = json.dumps(self._provenance.as_dict())
                _write_index(h5, entries)

        atomic_write(self.path, write)
        for sid in ids:
            (self._parts / f"{sid}.npz").unlink()

    def _release(self) -> None:
        if self._lock < 0:
            return
        try:
            self._parts.rmdir()
        except OSError:
            pass  # parts left to pack: the next writer does it
        os.close(self._lock)  # drops the writer lock
        self._lock = -1


def _claim(folder: Path, path: Path) -> int:
    """Create and exclusively lock the parts folder; InputError if another writer holds it."""
    for _ in range(10):  # retried only when another writer removed the folder between our open and lock
        try:
            folder.mkdir(exist_ok=True)
            fd = os.open(folder, os.O_RDONLY)
        except OSError as err:
            raise InputError(f"cannot write {path}: {err.strerror} ({folder})") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise InputError(f"{path} is open in another DatasetWriter") from None
        if _same_file(fd, folder):
            return fd
        os.close(fd)
    raise InputError(f"cannot lock {folder}: other writers keep replacing it")


def _same_file(fd: int, path: Path) -> bool:
    try:
        named = os.stat(path)
    except FileNotFoundError:
        return False
    held = os.fstat(fd)
    return (named.st_dev, named.st_ino) == (held.st_dev, held.st_ino)


def _remove_temporaries(path: Path) -> None:
    """Remove the temporary files (from ``atomic_write``) that a killed writer left behind."""
    folder = parts_folder(path)
    for name in os.listdir(folder):
        if name.startswith("."):
            (folder / name).unlink()
    packing = re.compile(rf"\.{re.escape(path.stem)}\.[a-z0-9_]{{8}}{re.escape(path.suffix)}")
    for name in os.listdir(path.parent):
        if packing.fullmatch(name):
            (path.parent / name).unlink()


def _map(name: str, values: np.ndarray, finite: bool = True) -> np.ndarray:
    array = np.asarray(values, dtype=np.float32)
    if array.ndim != 2 or array.size == 0:
        raise ValueError(f"{name} must be a non-empty 2-D array, got shape {array.shape}")
    if finite and not np.all(np.isfinite(array)):
        raise ValueError(f"{name} has non-finite values")
    return array


def _result_values(fields: dict) -> dict:
    """Entry values from ``result_fields``; ValueError if keys are missing or unknown, or a float is not finite."""
    expected = {*RESULT_ATTRS, *RESULT_ARRAYS}
    if set(fields) != expected:
        raise ValueError(f"result_fields needs exactly {sorted(expected)}; missing "
                         f"{sorted(expected - set(fields))}, unknown {sorted(set(fields) - expected)}")
    values: dict = {}
    for key, (name, kind) in RESULT_ATTRS.items():
        value = fields[key]
        values[name] = math.nan if value is None and key in OPTIONAL_FLOATS else kind(value)
        if kind is float and key not in OPTIONAL_FLOATS and not math.isfinite(values[name]):
            raise ValueError(f"{key} is {values[name]} in a successful result")
    values["contact_history"] = tuple(int(c) for c in fields["contact_history"])
    values["ladder_h_mm"], values["ladder_V"] = ladder_columns(fields["ladder"])
    return values


def _put_maps(group: h5py.Group, maps: dict) -> None:
    for name in MAPS:
        if name in maps:
            group.create_dataset(name, data=maps[name], chunks=maps[name].shape, compression="gzip", shuffle=True)
    if "fluctuation" in maps:
        group["fluctuation"].attrs["grid_axis_mm"] = maps["grid_axis_mm"]


def _write_index(h5: h5py.File, entries: dict[str, Entry]) -> None:
    if "index" in h5:
        del h5["index"]
    group = h5.create_group("index")
    rows = [entries[sid] for sid in sorted(entries)]
    for f in fields(Entry):
        values = [getattr(e, f.name) for e in rows]
        if f.name in TEXT_FIELDS:
            group.create_dataset(f.name, data=np.array(values, dtype=object), dtype=h5py.string_dtype())
        elif f.name in TUPLE_FIELDS:
            kind = np.int64 if TUPLE_FIELDS[f.name] is int else np.float64
            column = np.empty(len(rows), dtype=object)
            column[:] = [np.asarray(v, dtype=kind) for v in values]
            group.create_dataset(f.name, data=column, dtype=h5py.vlen_dtype(kind))
        else:
            group.create_dataset(f.name, data=np.array(values, dtype=_COLUMN_TYPES[f.type]))


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


# ---------------------------------------------------------------------------------------------
# Reading


def _open_h5(path: Path) -> h5py.File:
    if not path.exists():
        raise InputError(f"no dataset file {path}")
    if not path.is_file():
        raise InputError(f"{path} is not a file")
    try:
        return h5py.File(path, "r")
    except OSError as err:
        raise InputError(f"{path} is not an HDF5 file or is damaged ({err})") from None


def _read_index(h5: h5py.File, path: Path, context: str = "is") -> tuple[Header, dict[str, Entry]]:
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
    columns = [[tuple(h.tolist()) for h in c] if n in TUPLE_FIELDS else c.tolist()
               for n, c in zip(names, columns)]
    return header, {row[0]: Entry(**dict(zip(names, row))) for row in zip(*columns)}


def _read_part(file: Path) -> tuple[Entry, dict[str, np.ndarray]]:
    """Index entry and maps of one part file."""
    with np.load(file) as npz:
        data = {name: npz[name] for name in npz.files}
    values = json.loads(str(data.pop("entry")))
    return Entry(**as_tuples(values)), data


def _part_ids(folder: Path) -> list[str]:
    try:
        names = os.listdir(folder)
    except FileNotFoundError:
        return []
    return sorted(n[:-4] for n in names if n.endswith(".npz") and not n.startswith("."))


def _group_maps(group: h5py.Group) -> dict[str, np.ndarray]:
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


@dataclass(frozen=True)
class Sample:
    """One stored sample: ``values`` holds its scalar values (V, ..., or error)."""

    id: str
    recipe: dict
    status: str
    values: dict
    heightmap: Heightmap | None
    fluctuation: np.ndarray | None
    grid_axis_mm: np.ndarray | None  # coordinates (mm) of the fluctuation map's rows and columns


class Dataset:
    """Read access to a dataset: the samples it held when opened, sorted by id.

    Opening reads the index (and the entries of unpacked parts), never every sample group.
    """

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self._parts = parts_folder(self.path)
        unpacked = {}
        for sid in _part_ids(self._parts):  # before the file: a pack in between moves them into it
            try:
                unpacked[sid] = _read_part(self._parts / f"{sid}.npz")[0]
            except FileNotFoundError:
                pass  # packed meanwhile: the file opened below holds it
        self._h5 = _open_h5(self.path)
        try:
            self.header, packed = _read_index(self._h5, self.path)
        except BaseException:
            self._h5.close()
            raise
        self._packed = set(packed)
        self._entries = dict(sorted({**unpacked, **packed}.items()))
        self._recipes: list[dict] | None = None

    @property
    def config(self) -> DatasetConfig:
        """How every sample was made (simulation configuration and recipe)."""
        return self.header.config

    @property
    def ids(self) -> list[str]:
        return list(self._entries)

    @property
    def recipes(self) -> list[dict]:
        """Recipes in the order of ``ids``."""
        if self._recipes is None:
            self._recipes = [json.loads(e.recipe) for e in self._entries.values()]
        return list(self._recipes)

    def __len__(self) -> int:
        return len(self._entries)

    def table(self) -> dict[str, np.ndarray]:
        """Columns id, family, status, pixel_mm and the RESULT_ATTRS names (failed: nan, False or -1)."""
        entries = list(self._entries.values())
        columns = {name: np.array([getattr(e, name) for e in entries], dtype=kind)
                   for name, kind in [("id", str), ("family", str), ("status", str), ("pixel_mm", float),
                                      *RESULT_ATTRS.values()]}
        return columns

    def heightmap(self, sid: str) -> Heightmap:
        """The texture of sample ``sid`` (heights in mm)."""
        return Heightmap(self._maps(sid, "heightmap")["heightmap"].astype(float), self._entry(sid).pixel_mm)

    def fluctuation(self, sid: str) -> np.ndarray:
        """Strain fluctuation map at receptor depth of ok sample ``sid`` (float32, on grid_axis_mm).

        KeyError for a failed sample and for one restored from a labels file (which has none)."""
        return self._maps(sid, "fluctuation")["fluctuation"]

    def entries(self) -> dict[str, Entry]:
        """The index entries, by id (sorted)."""
        return dict(self._entries)

    def iter_samples(self, status: str | None = "ok") -> Iterator[Sample]:
        """Samples with ``status`` ("ok", "failed", or None for all), maps included, in id order."""
        for sid, entry in self._entries.items():
            if status is None or entry.status == status:
                maps = self._maps(sid)
                heights = maps.get("heightmap")
                yield Sample(sid, json.loads(entry.recipe), entry.status, entry.values(),
                             None if heights is None else Heightmap(heights.astype(float), entry.pixel_mm),
                             maps.get("fluctuation"), maps.get("grid_axis_mm"))

    def failures(self) -> list[tuple[str, dict, str]]:
        """(id, recipe, error) of every failed sample."""
        return [(e.id, json.loads(e.recipe), e.error) for e in self._entries.values() if e.status == "failed"]

    def close(self) -> None:
        self._h5.close()

    def __enter__(self) -> Dataset:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _entry(self, sid: str) -> Entry:
        try:
            return self._entries[sid]
        except KeyError:
            raise KeyError(f"no sample {sid!r} in {self.path}") from None

    def _maps(self, sid: str, needed: str | None = None) -> dict[str, np.ndarray]:
        entry = self._entry(sid)
        maps = None
        if sid not in self._packed:
            try:
                maps = _read_part(self._parts / f"{sid}.npz")[1]
            except FileNotFoundError:  # packed since we opened: the file now holds it
                self._h5.close()
                self._h5 = _open_h5(self.path)
                self._packed.add(sid)
        if maps is None:
            maps = _group_maps(self._h5["samples"][sid])
        if needed is not None and needed not in maps:
            restored = " restored from a labels file" if entry.restored else ""
            raise KeyError(f"sample {sid} ({entry.status}{restored}) has no {needed}")
        return maps


def open_dataset(path: str | os.PathLike) -> Dataset:
    """Open a dataset file for reading; InputError if it is missing, not HDF5 or not a dataset."""
    return Dataset(path)


# ---------------------------------------------------------------------------------------------
# Summary and checks


def info(path: str | os.PathLike) -> dict:
    """Counts by status and family, value ranges of ok samples, failure reasons and file attributes."""
    with open_dataset(path) as ds:
        table = ds.table()
        ok = table["status"] == "ok"
        families: dict[str, Counter] = {}
        for family, status in zip(table["family"], table["status"]):
            families.setdefault(str(family), Counter())[str(status)] += 1
        return {
            "path": str(ds.path),
            "samples": len(ds),
            **{status: int(np.sum(table["status"] == status)) for status in STATUSES},
            "converged": int(np.sum(table["converged"][ok])),
            "restored": sum(e.restored for e in ds.entries().values()),
            "families": {f: {s: counts[s] for s in STATUSES} for f, counts in sorted(families.items())},
            "V": _span(table["V"][ok]),
            "contact_fraction": _span(table["contact_fraction"][ok]),
            "failure_reasons": dict(Counter(error for _, _, error in ds.failures()).most_common()),
            "roughness_version": ds.header.roughness_version,
            "created": ds.header.created,
            "schema_version": ds.header.schema_version,
        }


def _span(values: np.ndarray) -> list[float] | None:
    return [float(values.min()), float(values.max())] if values.size else None


def verify(path: str | os.PathLike) -> list[str]:
    """Problems found in a dataset (empty: all good); InputError if the file is missing or not HDF5."""
    path = Path(path)
    with _open_h5(path) as h5:
        problems = header_problems(h5.attrs)
        if problems:
            return problems
        try:
            _, entries = _read_index(h5, path)
        except InputError as err:
            return [str(err)]
        samples = h5.get("samples", {})
        problems += [f"samples/{n}: not in the index (an unfinished sample)" for n in samples if n not in entries]
        for sid, entry in entries.items():
            maps = _group_maps(samples[sid]) if sid in samples else {}
            problems += [f"samples/{sid}: {p}" for p in _entry_problems(entry, maps)]
    folder = parts_folder(path)
    for sid in _part_ids(folder):
        try:
            entry, maps = _read_part(folder / f"{sid}.npz")
        except (OSError, ValueError, KeyError, TypeError) as err:
            problems.append(f"{folder.name}/{sid}.npz: unreadable ({err})")
            continue
        problems += [f"{folder.name}/{sid}.npz: {p}" for p in _entry_problems(entry, maps)]
        if entry.id != sid:
            problems.append(f"{folder.name}/{sid}.npz: holds sample {entry.id}")
    return problems


def _entry_problems(entry: Entry, maps: dict[str, np.ndarray]) -> list[str]:
    try:
        recipe = json.loads(entry.recipe)
        expected = sample_id(recipe)
    except (TypeError, ValueError):
        return ["recipe is not a JSON object"]
    problems = [] if expected == entry.id else [f"id does not match its recipe (expected {expected})"]
    if recipe.get("family") != entry.family:
        problems.append(f"family {entry.family!r} is not the recipe's {recipe.get('family')!r}")
    if entry.status == "ok":
        for name in ["pixel_mm"] + [n for k, (n, kind) in RESULT_ATTRS.items()
                                    if kind is float and k not in OPTIONAL_FLOATS]:
            if not math.isfinite(getattr(entry, name)):
                problems.append(f"{name} is {getattr(entry, name)}")
        for name in [m for m in MAPS if not (entry.restored and m == "fluctuation")]:
            if name not in maps or maps[name].ndim != 2:
                problems.append(f"{name} is missing or not 2-D")
            elif not np.all(np.isfinite(maps[name])):
                problems.append(f"{name} has non-finite values")
    elif entry.status == "failed":
        if not entry.error:
            problems.append("failed sample without an error message")
    else:
        problems.append(f"status {entry.status!r} is neither 'ok' nor 'failed'")
    return problems

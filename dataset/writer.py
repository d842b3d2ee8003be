"""The one writer of a dataset file: crash safe, and the file stays readable throughout.

The HDF5 file is never changed in place (HDF5 updates its metadata in place, so a writer killed
mid-flush can leave a file that no longer opens):

- ``DatasetWriter`` writes each finished sample atomically as its own file ``<id>.npz`` in the
  parts folder (``layout``; ``atomic_write``: a temporary file renamed into place);
- its ``close`` packs them: a copy of the HDF5 file plus the new samples and a rewritten index,
  renamed over the file (``atomic_write``), after which the parts are deleted.

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
from dataclasses import asdict, fields
from datetime import datetime, timezone
from pathlib import Path

import h5py
import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.core.files import atomic_write
from roughness.core.hashing import canonical_json
from roughness.core.provenance import Provenance

from .layout import MAPS, open_h5, part_ids, parts_folder, read_index, read_part
from .schema import (
    OPTIONAL_FLOATS,
    RESULT_ARRAYS,
    RESULT_ATTRS,
    SCHEMA_VERSION,
    TEXT_FIELDS,
    TUPLE_FIELDS,
    DatasetConfig,
    Entry,
    Header,
    as_tuples,
    ladder_columns,
    sample_id,
)

__all__ = ["DatasetWriter"]
_COLUMN_TYPES = {"float": "f8", "int": "i8", "bool": "?"}


class DatasetWriter:
    """Single writer of a dataset file (created with its first sample, else added to); a context manager.

    ``config`` says how the samples are made (``DatasetConfig``, or its dict form); adding to a file
    requires the same configuration. ``version`` is the package version (stored). Each sample is
    given by its texture record (a dict with a "family" string: family, parameters, seeds, ...; its
    id is ``sample_id`` of it).
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
                with open_h5(self.path) as h5:
                    header, entries = read_index(h5, self.path, "exists and")
                if header.config != self.config:
                    raise InputError(f"{self.path} was made with another configuration "
                                     f"({header.config.differences(self.config)}); use a new file for this one")
                self._old_layout = header.schema_version < SCHEMA_VERSION  # converted on close
            _remove_temporaries(self.path)  # of this dataset's writers: checked to be one above
            self._ids = set(entries) | set(part_ids(self._parts))
        except BaseException:
            self._release()
            raise

    @property
    def ids(self) -> frozenset[str]:
        """Ids of the samples in the dataset, failed ones included."""
        return frozenset(self._ids)

    def write_result(self, texture_record: dict, heightmap: np.ndarray, pixel_mm: float, result_fields: dict,
                     fluctuation: np.ndarray) -> bool:
        """Store a simulated sample (heights in mm); False, writing nothing, if its id is present.

        ``result_fields`` holds the keys of RESULT_ATTRS and RESULT_ARRAYS (see ``result_fields()``).
        """
        values = _result_values(result_fields)
        maps = {"heightmap": _map("heightmap", heightmap), "fluctuation": _map("fluctuation", fluctuation),
                "grid_axis_mm": np.asarray(result_fields["grid_axis_mm"], dtype=float)}
        return self._write(texture_record, pixel_mm, "ok", values, maps)

    def write_labelled(self, texture_record: dict, heightmap: np.ndarray | None, pixel_mm: float,
                       values: dict) -> bool:
        """Store a sample with a result computed before (``labels.Label.values``: Entry fields, its time and
        version of writing kept); no fluctuation map. False, writing nothing, if its id is present."""
        status = values["status"]
        maps = {} if heightmap is None else {"heightmap": _map("heightmap", heightmap, finite=status == "ok")}
        rest = {k: v for k, v in values.items() if k != "status"}
        return self._write(texture_record, pixel_mm, status, {**rest, "restored": True}, maps)

    def write_failure(self, texture_record: dict, heightmap: np.ndarray | None, pixel_mm: float, error: str) -> bool:
        """Record a sample whose simulation failed and why; False, writing nothing, if its id is present."""
        if not isinstance(error, str) or not error.strip():
            raise ValueError("a failure needs its reason as a non-empty string")
        maps = {} if heightmap is None else {"heightmap": _map("heightmap", heightmap, finite=False)}
        return self._write(texture_record, pixel_mm, "failed", {"error": error}, maps)

    def close(self) -> None:
        """Pack the finished samples into the file (and a version-1 file into version 2); release it (idempotent)."""
        if self._lock < 0:
            return
        try:
            if part_ids(self._parts) or self._old_layout:
                self._pack()
        finally:
            self._release()

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _write(self, texture_record: dict, pixel_mm: float, status: str, values: dict, maps: dict) -> bool:
        if not isinstance(texture_record, dict) or not isinstance(texture_record.get("family"), str):
            raise ValueError(f"a texture record is a dict with a 'family' string, got {texture_record!r}")
        values = {"written": _now(), "roughness_version": self._version, **values}
        entry = Entry(id=sample_id(texture_record), recipe=canonical_json(texture_record),
                      family=texture_record["family"], status=status,
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
        ids = part_ids(self._parts)

        def write(tmp: str) -> None:
            base = self.path.exists()
            if base:
                shutil.copyfile(self.path, tmp)
            with h5py.File(tmp, "r+" if base else "w") as h5:
                if base:
                    header, entries = read_index(h5, self.path, "exists and")
                else:
                    header, entries = Header(self.config, self._version, _now()), {}
                samples = h5.require_group("samples")
                for name in [n for n in samples if n not in entries]:
                    del samples[name]  # unfinished samples of a version-1 writer
                for sid in ids:
                    if sid not in entries:
                        entries[sid], maps = read_part(self._parts / f"{sid}.npz")
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

"""HDF5 store of FEM training samples: one file per dataset, appended by one writer, crash safe.

Schema ("roughness.dataset", version 1)
---------------------------------------
``/``                 attrs ``schema``, ``schema_version``, ``config`` (JSON of the simulation configuration,
                      ``SimConfig.as_dict()``), ``roughness_version`` (package that created the file),
                      ``created`` (ISO 8601, UTC)
``/samples/<id>``     one group per sample; ``<id> = sample_id(recipe)``, 16 hex digits
  ``heightmap``       float32 (ny, nx) heights in mm, one gzip chunk; shapes may differ between
                      samples; absent for a failed sample whose texture could not be made
  ``fluctuation``     float32 strain fluctuation map at receptor depth (ok samples only), one gzip
                      chunk; attr ``grid_axis_mm``: coordinates (mm) of its rows and columns
  attrs, always       ``recipe`` (canonical JSON: family, params, seed, perturbation, ...),
                      ``status`` ("ok" | "failed"), ``pixel_mm``, ``written`` (ISO 8601, UTC),
                      ``roughness_version`` (package that wrote the sample)
  attrs, ok           ``V``, ``V_stderr``, ``contact_fraction``, ``indentation_mm`` (mm), ``converged``,
                      ``iterations``, ``unresolved_nodes``, ``cycled``, ``seconds`` (s),
                      ``contact_history`` (contact node count per round)
  attrs, failed       ``error`` (why the simulation failed)

Crash safety
------------
HDF5 updates its metadata in place: a plain flush-per-sample h5py writer killed at most of the
write calls of one flush left a file in which earlier, complete samples were unreachable, or one
that no longer opened (fault injection while developing this module). So HDF5 never writes the
file directly here: h5py runs on ``_PagedView``, an in-memory page buffer over the file (h5py's
file-object driver). Each sample is built as ``samples/.tmp-<id>``, renamed to ``samples/<id>``
and committed: the changed pages go to the redo journal ``<file>-journal`` as one SHA-256-sealed
record (fsync), are copied into the file (fsync), and the journal is emptied. A torn record is
ignored; a complete one is replayed by the next writer and overlaid in memory by readers.

Guarantee: whenever the writer stops (SIGKILL, SIGINT or an exception, at any point), the dataset
holds every sample whose ``write_*`` call returned, possibly the one being committed, each
complete, and nothing else; after an exception the writer rolls back to its last commit. The
fsync order also covers power loss where the file system honours fsync (not tested).
Readers of this module hold a shared ``flock`` on the file while they read and a commit holds an
exclusive one while it copies, so reading beside a running writer is safe. HDF5 flocks the files
it opens, so a plain ``h5py.File`` is kept apart from commits too (a commit waits for it, warning
after LOCK_PATIENCE_S); it sees a consistent file except after a writer died while copying,
until the next ``DatasetWriter`` opens the file. Move or copy a file with its leftover journal.
The default HDF5 format (libver "earliest") is used on purpose: "latest" marks the file
open-for-write in its superblock, a mark that would outlive a crash. POSIX only (``fcntl``).
"""
from __future__ import annotations

import fcntl
import hashlib
import json
import math
import os
import stat
import struct
import time
import warnings
from collections import Counter
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import BinaryIO, Callable, Iterator, NamedTuple

import h5py
import numpy as np

from roughness.core.errors import InputError
from roughness.core.hashing import canonical_json, digest
from roughness.simulate.heightmap import Heightmap

SCHEMA = "roughness.dataset"
SCHEMA_VERSION = 1
ROOT_ATTRS = ("schema", "schema_version", "config", "roughness_version", "created")
TMP = ".tmp-"
STATUSES = ("ok", "failed")
# write_result's result_fields key (a simulate.model.Result attribute) -> (sample attribute, type).
RESULT_ATTRS = {
    "roughness": ("V", float),
    "roughness_stderr": ("V_stderr", float),
    "contact_fraction": ("contact_fraction", float),
    "indentation_mm": ("indentation_mm", float),
    "converged": ("converged", bool),
    "iterations": ("iterations", int),
    "unresolved_nodes": ("unresolved_nodes", int),
    "cycled": ("cycled", bool),
    "seconds": ("seconds", float),
}
RESULT_ARRAYS = ("contact_history", "grid_axis_mm")
MISSING = {float: math.nan, bool: False, int: -1}  # table() values of failed samples

LOCK_PATIENCE_S = 2.0  # wait this long (s) for a file lock before warning that we are blocked
PAGE = 4096
_MAGIC = b"RGHJRNL1"
_HEADER = struct.Struct("<8sQQQ")  # magic, kept length of the old file, new length, page count
_INDEX = struct.Struct("<Q")
_ENTRY = _INDEX.size + PAGE
_DIGEST = hashlib.sha256().digest_size


# ---------------------------------------------------------------------------------------------
# Sample ids


def sample_id(recipe: dict) -> str:
    """16 hex digits of the SHA-1 of the recipe's canonical JSON: independent of key order."""
    if not isinstance(recipe, dict):
        raise TypeError(f"a recipe is a dict, got {type(recipe).__name__}")
    return digest(recipe)


def result_fields(result: object) -> dict:
    """The ``result_fields`` of ``DatasetWriter.write_result`` from a ``simulate.model.Result``."""
    return {key: getattr(result, key) for key in (*RESULT_ATTRS, *RESULT_ARRAYS)}


# ---------------------------------------------------------------------------------------------
# Page buffer and redo journal


class _Record(NamedTuple):
    """One commit: cut the file to ``base`` bytes, write ``pages`` (index -> PAGE bytes), set ``size``."""

    base: int
    size: int
    pages: dict[int, bytes]

    def encode(self) -> bytes:
        parts = [_HEADER.pack(_MAGIC, self.base, self.size, len(self.pages))]
        for index in sorted(self.pages):
            parts += [_INDEX.pack(index), self.pages[index]]
        body = b"".join(parts)
        return body + hashlib.sha256(body).digest()


def _records(journal: bytes) -> list[_Record]:
    """The intact records at the start of ``journal``; a torn tail (a commit cut short) is ignored."""
    records, at, data = [], 0, memoryview(journal)
    while at + _HEADER.size <= len(journal):
        magic, base, size, count = _HEADER.unpack_from(journal, at)
        end = at + _HEADER.size + count * _ENTRY
        if (magic != _MAGIC or end + _DIGEST > len(journal)
                or hashlib.sha256(data[at:end]).digest() != journal[end:end + _DIGEST]):
            break
        entries = range(at + _HEADER.size, end, _ENTRY)
        pages = {_INDEX.unpack_from(journal, e)[0]: journal[e + _INDEX.size:e + _ENTRY] for e in entries}
        records.append(_Record(base, size, pages))
        at = end + _DIGEST
    return records


def _apply(fd: int, record: _Record) -> None:
    """Write one record into the file (idempotent, so a replay after a crash is safe)."""
    os.ftruncate(fd, record.base)
    for index, page in record.pages.items():
        os.pwrite(fd, page, index * PAGE)
    os.ftruncate(fd, record.size)


class _PagedView:
    """File object for h5py's fileobj driver over ``fd`` that keeps every write in memory pages.

    Bytes below ``base`` come from ``fd`` unless a page holds them; bytes up to ``size`` that
    neither holds read as zeros, like a sparse file.
    """

    def __init__(self, fd: int) -> None:
        self._fd = fd
        self.size = self.base = self._committed = os.fstat(fd).st_size
        self.pages: dict[int, bytearray] = {}
        self._pos = 0

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        origin = {os.SEEK_SET: 0, os.SEEK_CUR: self._pos, os.SEEK_END: self.size}[whence]
        self._pos = origin + offset
        return self._pos

    def tell(self) -> int:
        return self._pos

    def flush(self) -> None:
        """Nothing to do: pages reach the file only through a commit."""

    def read(self, n: int = -1) -> bytes:
        start = self._pos
        end = max(start, self.size if n < 0 else start + n)
        out = bytearray(end - start)
        pos = start
        while pos < end:
            index, offset = divmod(pos, PAGE)
            stop = min(end, (index + 1) * PAGE)
            page = self.pages.get(index)
            if page is not None:
                out[pos - start:stop - start] = page[offset:offset + stop - pos]
            else:  # one pread for the run of pages that are not buffered
                while stop < end and stop // PAGE not in self.pages:
                    stop = min(end, stop + PAGE)
                if pos < self.base:
                    data = os.pread(self._fd, min(stop, self.base) - pos, pos)
                    out[pos - start:pos - start + len(data)] = data
            pos = stop
        self._pos = end
        return bytes(out)

    def write(self, data: bytes) -> int:
        view = memoryview(data).cast("B")
        done = 0
        while done < len(view):
            index, offset = divmod(self._pos + done, PAGE)
            n = min(PAGE - offset, len(view) - done)
            if index not in self.pages:
                self.pages[index] = bytearray(PAGE) if n == PAGE else self._file_page(index)
            self.pages[index][offset:offset + n] = view[done:done + n]
            done += n
        self._pos += done
        self.size = max(self.size, self._pos)
        return done

    def truncate(self, size: int | None = None) -> int:
        size = self._pos if size is None else size
        if size < self.size:
            self.base = min(self.base, size)
            last, offset = divmod(size, PAGE)
            for index in [i for i in self.pages if i > last]:
                del self.pages[index]
            if last in self.pages:
                self.pages[last][offset:] = bytes(PAGE - offset)
        self.size = size
        return size

    def _file_page(self, index: int) -> bytearray:
        page = bytearray(PAGE)
        start = index * PAGE
        if start < self.base:
            data = os.pread(self._fd, min(PAGE, self.base - start), start)
            page[:len(data)] = data
        return page

    def replay(self, record: _Record) -> None:
        """Apply a journal record in memory (readers never write the file)."""
        self.truncate(record.base)
        for index, page in record.pages.items():
            self.seek(index * PAGE)
            self.write(page)
        self.truncate(record.size)

    def pending(self) -> _Record | None:
        """Everything written since the last commit, or None."""
        if not self.pages and self.base == self.size == self._committed:
            return None
        return _Record(self.base, self.size, {i: bytes(p) for i, p in self.pages.items()})

    def settle(self) -> None:
        """The pending record is now in the file."""
        self.pages.clear()
        self.base = self._committed = self.size


@contextmanager
def _locked(fd: int, shared: bool, path: Path) -> Iterator[None]:
    """Hold a shared (readers) or exclusive (commits) flock on the dataset file ``fd``.

    HDF5 flocks files it opens for their whole life, so a plain ``h5py.File`` of ``path`` makes
    us wait; a warning says so after LOCK_PATIENCE_S.
    """
    mode = fcntl.LOCK_SH if shared else fcntl.LOCK_EX
    deadline = time.monotonic() + LOCK_PATIENCE_S
    while True:
        try:
            fcntl.flock(fd, mode | fcntl.LOCK_NB)
            break
        except BlockingIOError:
            if time.monotonic() > deadline:
                warnings.warn(f"waiting for {path}: another program (an open h5py.File?) holds it", stacklevel=3)
                fcntl.flock(fd, mode)
                break
            time.sleep(0.01)
    try:
        yield
    finally:
        fcntl.flock(fd, fcntl.LOCK_UN)


def journal_path(path: str | os.PathLike) -> Path:
    """The redo journal that goes with dataset ``path``."""
    path = Path(path)
    return path.with_name(path.name + "-journal")


def _journal_bytes(path: Path) -> bytes:
    try:
        return journal_path(path).read_bytes()
    except FileNotFoundError:
        return b""


def _claim_journal(path: Path) -> BinaryIO:
    """Open and exclusively lock the journal of dataset ``path``; InputError if a writer holds it."""
    journal = journal_path(path)
    while True:
        try:
            handle = open(journal, "a+b")
        except OSError as err:
            raise InputError(f"cannot write {journal}: {err.strerror}") from None
        try:
            fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.close()
            raise InputError(f"{path} is open in another DatasetWriter") from None
        if _same_file(handle.fileno(), journal):
            return handle
        handle.close()  # the previous writer removed it between our open and our lock: retry


def _same_file(fd: int, path: Path) -> bool:
    try:
        named = os.stat(path)
    except FileNotFoundError:
        return False
    held = os.fstat(fd)
    return (named.st_dev, named.st_ino) == (held.st_dev, held.st_ino)


def _h5open(view: _PagedView, mode: str, path: Path) -> h5py.File:
    try:
        return h5py.File(view, mode)
    except OSError as err:
        raise InputError(f"{path} is not an HDF5 file or is damaged ({err})") from None


# ---------------------------------------------------------------------------------------------
# Writer


class DatasetWriter:
    """Single writer of a dataset file (created if missing, else appended to); a context manager.

    ``config`` is the simulation configuration (a JSON-ready dict, e.g. ``SimConfig.as_dict()``);
    appending requires the same configuration. ``version`` is the package version (stored).
    """

    def __init__(self, path: str | os.PathLike, config: dict, version: str) -> None:
        self.path = Path(path)
        self._config = json.loads(canonical_json(config))
        self._version = version
        self._h5: h5py.File | None = None
        self._fd = -1
        self._journal = _claim_journal(self.path)
        try:
            self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as err:
            self._release()
            raise InputError(f"cannot write {self.path}: {err.strerror}") from None
        try:
            self._open()
        except BaseException:
            self._release()
            raise

    @property
    def ids(self) -> frozenset[str]:
        """Ids of the samples in the file, failed ones included."""
        return self._ids

    def write_result(self, recipe: dict, heightmap: np.ndarray, pixel_mm: float, result_fields: dict,
                     fluctuation: np.ndarray) -> bool:
        """Store a simulated sample (heights in mm); False, writing nothing, if its id is present.

        ``result_fields`` holds the keys of RESULT_ATTRS and RESULT_ARRAYS (see ``result_fields()``).
        """
        values = _result_values(result_fields)
        heights, strain = _map("heightmap", heightmap), _map("fluctuation", fluctuation)
        axis = np.asarray(result_fields["grid_axis_mm"], dtype=float)

        def fill(group: h5py.Group) -> None:
            _put_map(group, "heightmap", heights)
            _put_map(group, "fluctuation", strain).attrs["grid_axis_mm"] = axis
            group.attrs.update(values)

        return self._write(recipe, pixel_mm, "ok", fill)

    def write_failure(self, recipe: dict, heightmap: np.ndarray | None, pixel_mm: float, error: str) -> bool:
        """Record a sample whose simulation failed and why; False, writing nothing, if its id is present."""
        if not isinstance(error, str) or not error.strip():
            raise ValueError("a failure needs its reason as a non-empty string")
        heights = None if heightmap is None else _map("heightmap", heightmap, finite=False)

        def fill(group: h5py.Group) -> None:
            if heights is not None:
                _put_map(group, "heightmap", heights)
            group.attrs["error"] = error

        return self._write(recipe, pixel_mm, "failed", fill)

    def close(self) -> None:
        """Commit and release the file (idempotent)."""
        try:
            if self._h5 is not None:
                h5, self._h5 = self._h5, None
                h5.close()
                self._persist()
        finally:
            self._release()

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _write(self, recipe: dict, pixel_mm: float, status: str, fill: Callable[[h5py.Group], None]) -> bool:
        text = _recipe_json(recipe)
        pixel = _positive("pixel_mm", pixel_mm)
        sid = sample_id(recipe)
        if self._h5 is None:
            raise ValueError(f"the writer of {self.path} is closed")
        if sid in self._ids:
            return False
        samples = self._h5["samples"]
        try:
            group = samples.create_group(TMP + sid)
            group.attrs.update(recipe=text, status=status, pixel_mm=pixel, written=_now(),
                               roughness_version=self._version)
            fill(group)
            samples.move(TMP + sid, sid)
            self._h5.flush()
            self._persist()
        except BaseException:
            self._reopen()
            raise
        self._ids = self._ids | {sid}
        return True

    def _open(self) -> None:
        """Replay the journal, open HDF5 on a fresh view, drop unfinished samples and commit."""
        with _locked(self._fd, False, self.path):
            for record in _records(_journal_bytes(self.path)):
                _apply(self._fd, record)
            os.fsync(self._fd)
            self._journal.truncate(0)
        view = _PagedView(self._fd)
        h5 = _h5open(view, "r+" if view.size else "w", self.path)
        try:
            self._prepare(h5, new=not view.size)
            h5.flush()
        except BaseException:
            with suppress(Exception):
                h5.close()
            raise
        self._view, self._h5 = view, h5
        self._ids = frozenset(h5["samples"])
        self._persist()

    def _prepare(self, h5: h5py.File, new: bool) -> None:
        if new:
            h5.attrs.update(schema=SCHEMA, schema_version=SCHEMA_VERSION, config=canonical_json(self._config),
                            roughness_version=self._version, created=_now())
            h5.create_group("samples")
            return
        problems = _root_problems(h5)
        if problems:
            raise InputError(f"{self.path} exists and is not a roughness dataset: {'; '.join(problems)}")
        stored = json.loads(h5.attrs["config"])
        if stored != self._config:
            raise InputError(f"{self.path} was simulated with another configuration "
                             f"({_differences(stored, self._config)}); use a new file for this one")
        samples = h5["samples"]
        for name in [n for n in samples if n.startswith(TMP)]:
            del samples[name]

    def _reopen(self) -> None:
        """Drop everything since the last commit and reopen the file as committed."""
        h5, self._h5 = self._h5, None
        with suppress(Exception):
            h5.close()  # its last writes land in the discarded view
        self._open()

    def _persist(self) -> None:
        """Commit the view's pending pages: journal record (fsync), copy into the file (fsync)."""
        record = self._view.pending()
        if record is None:
            return
        with _locked(self._fd, False, self.path):
            self._journal.write(record.encode())
            self._journal.flush()
            os.fsync(self._journal.fileno())
            _apply(self._fd, record)
            os.fsync(self._fd)
            self._journal.truncate(0)
        self._view.settle()

    def _release(self) -> None:
        if self._journal.closed:
            return
        if os.fstat(self._journal.fileno()).st_size == 0:
            os.unlink(journal_path(self.path))
        self._journal.close()  # drops the writer lock
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


def _differences(stored: dict, given: dict) -> str:
    keys = sorted(set(stored) | set(given), key=str)
    return "; ".join(f"{k}: file {stored.get(k, '<none>')!r}, given {given.get(k, '<none>')!r}"
                     for k in keys if k not in stored or k not in given or stored[k] != given[k])


def _recipe_json(recipe: dict) -> str:
    if not isinstance(recipe, dict) or not isinstance(recipe.get("family"), str):
        raise ValueError(f"a recipe is a dict with a 'family' string, got {recipe!r}")
    return canonical_json(recipe)


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be positive and finite, got {value}")
    return value


def _map(name: str, values: np.ndarray, finite: bool = True) -> np.ndarray:
    array = np.asarray(values, dtype=np.float32)
    if array.ndim != 2 or array.size == 0:
        raise ValueError(f"{name} must be a non-empty 2-D array, got shape {array.shape}")
    if finite and not np.all(np.isfinite(array)):
        raise ValueError(f"{name} has non-finite values")
    return array


def _put_map(group: h5py.Group, name: str, values: np.ndarray) -> h5py.Dataset:
    return group.create_dataset(name, data=values, chunks=values.shape, compression="gzip", shuffle=True)


def _result_values(fields: dict) -> dict:
    """Sample attributes from ``result_fields``; ValueError if keys are missing or unknown."""
    expected = {*RESULT_ATTRS, *RESULT_ARRAYS}
    if set(fields) != expected:
        raise ValueError(f"result_fields needs exactly {sorted(expected)}; missing "
                         f"{sorted(expected - set(fields))}, unknown {sorted(set(fields) - expected)}")
    values: dict = {}
    for key, (name, kind) in RESULT_ATTRS.items():
        values[name] = kind(fields[key])
        if kind is float and not math.isfinite(values[name]):
            raise ValueError(f"{key} is {values[name]} in a successful result")
    values["contact_history"] = np.asarray(fields["contact_history"], dtype=np.int64)
    return values


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


# ---------------------------------------------------------------------------------------------
# Reading


class _Reader:
    """Shared-locked, journal-aware read access to a dataset file, reopened when the file changed."""

    def __init__(self, path: Path) -> None:
        self.path = path
        try:
            self._fd = os.open(path, os.O_RDONLY)
        except FileNotFoundError:
            raise InputError(f"no dataset file {path}") from None
        except OSError as err:
            raise InputError(f"cannot read {path}: {err.strerror}") from None
        self._h5: h5py.File | None = None
        self._stamp: tuple | None = None
        if not stat.S_ISREG(os.fstat(self._fd).st_mode):
            self.close()
            raise InputError(f"{path} is not a file")

    @contextmanager
    def file(self) -> Iterator[h5py.File]:
        """The HDF5 file as last committed, locked against commits while in use."""
        with _locked(self._fd, True, self.path):
            if self._stamp != self._current_stamp():
                self._close_h5()
                view = _PagedView(self._fd)
                for record in _records(_journal_bytes(self.path)):
                    view.replay(record)
                self._h5 = _h5open(view, "r", self.path)
                self._stamp = self._current_stamp()
            yield self._h5

    def _current_stamp(self) -> tuple:
        held = os.fstat(self._fd)
        try:
            journal = os.stat(journal_path(self.path))
            journal_stamp = (journal.st_ino, journal.st_size, journal.st_mtime_ns)
        except FileNotFoundError:
            journal_stamp = None
        return held.st_size, held.st_mtime_ns, journal_stamp

    def _close_h5(self) -> None:
        if self._h5 is not None:
            self._h5.close()
            self._h5 = None

    def close(self) -> None:
        self._close_h5()
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


@dataclass(frozen=True)
class Sample:
    """One stored sample: ``values`` holds its scalar attributes (V, ..., or error)."""

    id: str
    recipe: dict
    status: str
    values: dict
    heightmap: Heightmap | None
    fluctuation: np.ndarray | None
    grid_axis_mm: np.ndarray | None  # coordinates (mm) of the fluctuation map's rows and columns


class Dataset:
    """Read access to a dataset file: the samples committed when it was opened, sorted by id."""

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self._reader = _Reader(self.path)
        try:
            with self._reader.file() as h5:
                problems = _root_problems(h5)
                if problems:
                    raise InputError(f"{self.path} is not a roughness dataset: {'; '.join(problems)}")
                self.attrs = {name: _plain(h5.attrs[name]) for name in ROOT_ATTRS}
                self.attrs["config"] = json.loads(self.attrs["config"])
                self._entries = {name: _entry(self.path, name, group) for name, group in h5["samples"].items()
                                 if not name.startswith(TMP)}
        except BaseException:
            self._reader.close()
            raise

    @property
    def config(self) -> dict:
        """The simulation configuration of every sample."""
        return self.attrs["config"]

    @property
    def ids(self) -> list[str]:
        return list(self._entries)

    @property
    def recipes(self) -> list[dict]:
        """Recipes in the order of ``ids``."""
        return [entry["recipe"] for entry in self._entries.values()]

    def __len__(self) -> int:
        return len(self._entries)

    def table(self) -> dict[str, np.ndarray]:
        """Columns id, family, status, pixel_mm and the RESULT_ATTRS names (failed: nan, False or -1)."""
        entries = list(self._entries.values())
        columns = {
            "id": np.array([e["id"] for e in entries], dtype=str),
            "family": np.array([e["recipe"]["family"] for e in entries], dtype=str),
            "status": np.array([e["status"] for e in entries], dtype=str),
            "pixel_mm": np.array([e["pixel_mm"] for e in entries], dtype=float),
        }
        for name, kind in RESULT_ATTRS.values():
            columns[name] = np.array([e.get(name, MISSING[kind]) for e in entries], dtype=kind)
        return columns

    def heightmap(self, sid: str) -> Heightmap:
        """The texture of sample ``sid`` (heights in mm)."""
        entry = self._entry(sid)
        return Heightmap(self._array(sid, "heightmap").astype(float), entry["pixel_mm"])

    def fluctuation(self, sid: str) -> np.ndarray:
        """Strain fluctuation map at receptor depth of ok sample ``sid`` (float32, on grid_axis_mm)."""
        self._entry(sid)
        return self._array(sid, "fluctuation")

    def iter_samples(self, status: str | None = "ok") -> Iterator[Sample]:
        """Samples with ``status`` ("ok", "failed", or None for all), maps included, in id order."""
        for sid, entry in self._entries.items():
            if status is None or entry["status"] == status:
                with self._reader.file() as h5:
                    group = h5["samples"][sid]
                    heights = group["heightmap"][()].astype(float) if "heightmap" in group else None
                    strain = group.get("fluctuation")
                    strain, axis = (None, None) if strain is None else (strain[()], strain.attrs["grid_axis_mm"])
                values = {k: v for k, v in entry.items() if k not in ("id", "recipe", "status")}
                yield Sample(sid, entry["recipe"], entry["status"], values,
                             None if heights is None else Heightmap(heights, entry["pixel_mm"]), strain, axis)

    def failures(self) -> list[tuple[str, dict, str]]:
        """(id, recipe, error) of every failed sample."""
        return [(e["id"], e["recipe"], e["error"]) for e in self._entries.values() if e["status"] == "failed"]

    def close(self) -> None:
        self._reader.close()

    def __enter__(self) -> Dataset:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _entry(self, sid: str) -> dict:
        try:
            return self._entries[sid]
        except KeyError:
            raise KeyError(f"no sample {sid!r} in {self.path}") from None

    def _array(self, sid: str, name: str) -> np.ndarray:
        with self._reader.file() as h5:
            group = h5["samples"][sid]
            if name not in group:
                raise KeyError(f"sample {sid} ({self._entries[sid]['status']}) has no {name}")
            return group[name][()]


def open_dataset(path: str | os.PathLike) -> Dataset:
    """Open a dataset file for reading; InputError if it is missing, not HDF5 or not a dataset."""
    return Dataset(path)


def _plain(value: object) -> object:
    """An HDF5 attribute as a Python value (numpy scalars and arrays become numbers and lists)."""
    return value.tolist() if isinstance(value, (np.generic, np.ndarray)) else value


def _entry(path: Path, name: str, group: h5py.Group) -> dict:
    entry = {"id": name, **{key: _plain(value) for key, value in group.attrs.items()}}
    try:
        entry["recipe"] = json.loads(entry["recipe"])
    except (KeyError, TypeError, ValueError):
        raise InputError(f"{path}: sample {name} has no readable recipe; run verify") from None
    return entry


def _root_problems(h5: h5py.File) -> list[str]:
    problems = [f"root attribute {name!r} is missing" for name in ROOT_ATTRS if name not in h5.attrs]
    schema, version = h5.attrs.get("schema"), h5.attrs.get("schema_version")
    if schema is not None and schema != SCHEMA:
        problems.append(f"schema is {schema!r}, not {SCHEMA!r}")
    if version is not None and version != SCHEMA_VERSION:
        problems.append(f"schema version {version} is not {SCHEMA_VERSION}")
    with suppress(KeyError):
        try:
            json.loads(h5.attrs["config"])
        except (TypeError, ValueError):
            problems.append("root attribute 'config' is not JSON")
    if not isinstance(h5.get("samples"), h5py.Group):
        problems.append("group 'samples' is missing")
    return problems


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
            "families": {f: {s: counts[s] for s in STATUSES} for f, counts in sorted(families.items())},
            "V": _span(table["V"][ok]),
            "contact_fraction": _span(table["contact_fraction"][ok]),
            "failure_reasons": dict(Counter(error for _, _, error in ds.failures()).most_common()),
            **{name: ds.attrs[name] for name in ("roughness_version", "created", "schema_version")},
        }


def _span(values: np.ndarray) -> list[float] | None:
    return [float(values.min()), float(values.max())] if values.size else None


def verify(path: str | os.PathLike) -> list[str]:
    """Problems found in a dataset file (empty: all good); InputError if it is missing or not HDF5."""
    reader = _Reader(Path(path))
    try:
        with reader.file() as h5:
            problems = _root_problems(h5)
            samples = h5.get("samples")
            if isinstance(samples, h5py.Group):
                for name, group in samples.items():
                    problems += [f"samples/{name}: {p}" for p in _sample_problems(name, group)]
            return problems
    finally:
        reader.close()


def _sample_problems(name: str, group: h5py.Group) -> list[str]:
    if name.startswith(TMP):
        return ["unfinished sample left behind"]
    try:
        recipe = json.loads(group.attrs["recipe"])
        expected = sample_id(recipe)
    except (KeyError, TypeError, ValueError):
        return ["recipe missing or not a JSON object"]
    problems = [] if expected == name else [f"id does not match its recipe (expected {expected})"]
    if not isinstance(recipe.get("family"), str):
        problems.append("recipe has no family")
    status = group.attrs.get("status")
    if status == "ok":
        problems += _ok_problems(group)
    elif status == "failed":
        if not group.attrs.get("error"):
            problems.append("failed sample without an error message")
    else:
        problems.append(f"status {status!r} is neither 'ok' nor 'failed'")
    return problems


def _ok_problems(group: h5py.Group) -> list[str]:
    problems = []
    for name, kind in [("pixel_mm", float), *RESULT_ATTRS.values()]:
        if name not in group.attrs:
            problems.append(f"attribute {name!r} is missing")
        elif kind is float and not np.isfinite(group.attrs[name]):
            problems.append(f"{name} is {group.attrs[name]}")
    for name in ("heightmap", "fluctuation"):
        data = group.get(name)
        if not isinstance(data, h5py.Dataset) or data.ndim != 2:
            problems.append(f"{name} is missing or not 2-D")
        elif not np.all(np.isfinite(data[()])):
            problems.append(f"{name} has non-finite values")
    return problems

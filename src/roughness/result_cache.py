"""Results keyed by what they depend on: a texture's content and an engine's identity, never a file name.

Used by ``roughness compare`` (its output folder's results) and the perception analysis (its FEM cache,
with each result's fluctuation field). A renamed file hits the cache; a changed texture, pixel size,
configuration or model misses it. A line torn by an interruption is dropped and computed again.
"""
from __future__ import annotations

import json
import os
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.core.files import atomic_write
from roughness.core.hashing import array_digest
from roughness.surface.heightmap import Heightmap

RESULTS_FILE = "results.jsonl"
ARRAYS_FOLDER = "arrays"


def content_key(heightmap: Heightmap) -> str:
    """What a result depends on besides the engine: the heights (mm) and the pixel size (mm).

    Heights count at float32 precision (1e-7 relative, far below any engine's resolution), the
    precision datasets store them in: a dataset sample has the key of the texture it was made from.
    """
    return array_digest(np.asarray(heightmap.heights, dtype=np.float32), heightmap.pixel_mm)


class ResultCache:
    """A folder's results.jsonl: {engine, identity, key, ...fields} per line, and arrays beside it.

    ``key`` is the texture's ``content_key``; ``identities`` maps each engine spec to what its results
    depend on (configuration digest, model file digest): entries made under another identity (a
    retrained model, say) are ignored. The file is created with the first result, after ``before_first``
    (if given) has run, e.g. to write the folder's manifest. ``provenance`` (engine spec -> provenance record)
    goes into each new line. Arrays of a result (a fluctuation field) go to ``arrays/<identity>-<key>.npz``,
    written before its line, so a line always has its arrays.
    """

    def __init__(self, folder: Path, identities: dict[str, str], before_first: Callable[[], None] | None = None,
                 provenance: dict[str, dict] | None = None) -> None:
        self.identities, self.provenance = identities, provenance or {}
        self.folder, self.before_first = folder, before_first
        self.path = folder / RESULTS_FILE
        self.entries: dict[tuple[str, str], dict] = {}
        self.notes: list[str] = []  # damaged entries found, each computed again (``arrays``)
        if self.path.exists():
            text = self.path.read_text()
            if text and not text.endswith("\n"):  # a line torn by an interruption: dropped, computed again
                text = text[:text.rfind("\n") + 1]
                with open(self.path, "r+") as f:
                    f.truncate(len(text.encode()))
            for number, line in enumerate(text.splitlines(), 1):
                try:
                    entry = json.loads(line)
                except json.JSONDecodeError:
                    entry = None
                if not (isinstance(entry, dict) and isinstance(entry.get("engine"), str)
                        and isinstance(entry.get("key"), str)):
                    raise InputError(f"{self.path} line {number} is not a result (a JSON object with engine and "
                                     "key): the cache is damaged; remove that line to recompute it")
                if entry.get("identity") == identities.get(entry["engine"]):
                    self.entries[(entry["engine"], entry["key"])] = entry

    def get(self, engine: str, key: str) -> dict | None:
        return self.entries.get((engine, key))

    def arrays(self, engine: str, key: str, required: tuple[str, ...] = ()) -> dict[str, np.ndarray]:
        """The arrays stored with a result (empty if none were). A damaged arrays file (unreadable, or without the
        ``required`` arrays) reads as none, noted in ``notes``: the caller computes the result again and ``put``
        replaces the file."""
        path = self._arrays_path(engine, key)
        if not path.is_file():
            return {}
        try:
            with np.load(path, allow_pickle=False) as data:
                arrays = {name: data[name] for name in data.files}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as err:
            return self._damaged(path, f"{type(err).__name__}: {err}")
        missing = [name for name in required if name not in arrays]
        return self._damaged(path, f"no array {', '.join(missing)}") if missing else arrays

    def _damaged(self, path: Path, why: str) -> dict[str, np.ndarray]:
        self.notes.append(f"{path}: a damaged entry of the result cache {self.folder} ({why}): computed again")
        return {}

    def put(self, engine: str, key: str, arrays: dict[str, np.ndarray] | None = None, **fields) -> None:
        """Store a result: its fields as a line, its ``arrays`` (if any) in an .npz file first."""
        entry = {"engine": engine, "identity": self.identities[engine], "key": key, **fields,
                 **({"provenance": self.provenance[engine]} if engine in self.provenance else {})}
        self.entries[(engine, key)] = entry
        if self.before_first is not None:  # e.g. what these results belong to, before the first of them
            self.before_first()
            self.before_first = None
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if arrays:
            path = self._arrays_path(engine, key)
            path.parent.mkdir(exist_ok=True)
            atomic_write(path, lambda tmp: np.savez_compressed(tmp, **arrays))
        with open(self.path, "a") as f:
            f.write(json.dumps(entry) + "\n")
            f.flush()
            os.fsync(f.fileno())

    def _arrays_path(self, engine: str, key: str) -> Path:
        return self.folder / ARRAYS_FOLDER / f"{self.identities[engine]}-{key}.npz"

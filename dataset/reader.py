"""Reading a dataset (``open_dataset``), also while its writer adds to it.

A reader takes the parts (``layout``), then opens the HDF5 file, so a pack in between loses
nothing; a sample both packed and still a part (writer killed before deleting the parts) counts once.
"""
from __future__ import annotations

import json
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roughness.core.checks import file_path
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from .layout import open_h5, part_ids, parts_folder, read_index, read_part, sample_maps
from .schema import RESULT_ATTRS, DatasetConfig, Entry

__all__ = ["Dataset", "Sample", "open_dataset"]


@dataclass(frozen=True)
class Sample:
    """One stored sample: ``values`` holds its scalar values (V, ..., or error)."""

    id: str
    texture_record: dict  # what made its heightmap (family, params, seed, ...): the id is its sample_id
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
        for sid in part_ids(self._parts):  # before the file: a pack in between moves them into it
            try:
                unpacked[sid] = read_part(self._parts / f"{sid}.npz")[0]
            except FileNotFoundError:
                pass  # packed meanwhile: the file opened below holds it
        self._h5 = open_h5(self.path)
        try:
            self.header, packed = read_index(self._h5, self.path)
        except BaseException:
            self._h5.close()
            raise
        self._packed = set(packed)
        self._entries = dict(sorted({**unpacked, **packed}.items()))
        self._texture_records: list[dict] | None = None

    @property
    def config(self) -> DatasetConfig:
        """How every sample was made (simulation configuration and recipe)."""
        return self.header.config

    @property
    def ids(self) -> list[str]:
        return list(self._entries)

    @property
    def texture_records(self) -> list[dict]:
        """Texture records in the order of ``ids``."""
        if self._texture_records is None:
            self._texture_records = [json.loads(e.recipe) for e in self._entries.values()]
        return list(self._texture_records)

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
        """(id, texture record, error) of every failed sample."""
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
                maps = read_part(self._parts / f"{sid}.npz")[1]
            except FileNotFoundError:  # packed since we opened: the file now holds it
                self._h5.close()
                self._h5 = open_h5(self.path)
                self._packed.add(sid)
        if maps is None:
            maps = sample_maps(self._h5, sid)
        if needed is not None and needed not in maps:
            restored = " restored from a labels file" if entry.restored else ""
            raise KeyError(f"sample {sid} ({entry.status}{restored}) has no {needed}")
        return maps


def open_dataset(path: str | os.PathLike) -> Dataset:
    """Open a dataset file for reading; InputError (parameter ``path``) if it is missing, not HDF5 or not a dataset."""
    try:
        return Dataset(file_path("path", path))
    except InputError as err:
        err.parameter = err.parameter or "path"
        raise

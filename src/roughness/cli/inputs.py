"""Inputs of `roughness predict`: heightmap files, folders of them, and roughness dataset files.

Each input is loaded when it is needed, so a large folder or dataset streams through in
batches. An input that cannot be used (unreadable, too small for the footprint, ...) is
recorded in ``errors`` with its reason and skipped; the others are still predicted.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap
from roughness.surface.io import heightmap_files
from roughness.surface.units import split_input


class InputReader:
    """Heightmaps named by the paths given, in order; folders sorted by file name."""

    def __init__(self, paths: list[str], footprint_mm: float, centre_mm: tuple[float, float] | None, tile: bool,
                 load: Callable[[str, bool], Heightmap]) -> None:
        """``load(text, several)`` loads one heightmap file (``text``: its path, with the units it carries as
        FILE:pixel-mm=..,height-mm=..); ``several``: other inputs come with it. Units given with a folder go
        with each of its files."""
        self._load_file = load
        self.footprint_mm, self.centre_mm, self.tile = footprint_mm, centre_mm, tile
        self.errors: list[tuple[str, InputError]] = []  # (input, its error, whose message names the input)
        self._items: list[tuple[str, Path, str | None]] = []  # (name, file, sample id in a dataset)
        for text in paths:
            path = split_input(text)[0]
            tail = text[len(path):]  # FILE:pixel-mm=..: the units go with every file of a folder
            self._items += [(name + tail if sid is None else name, Path(f"{f}{tail}") if sid is None else f, sid)
                            for name, f, sid in self._expand(Path(path))]
        self.total = len(self._items)

    def _expand(self, path: Path) -> list[tuple[str, Path, str | None]]:
        if path.is_dir():
            return [item for f in heightmap_files(path) for item in self._expand(f)]
        if path.suffix.lower() in (".h5", ".hdf5") and _is_dataset(path):
            from roughness.dataset.reader import open_dataset

            with open_dataset(path) as data:
                ids = [sid for sid, status in zip(data.ids, data.table()["status"]) if status == "ok"]
            return [(f"{path}:{sid}", path, sid) for sid in ids]
        return [(str(path), path, None)]

    def named(self) -> Iterator[tuple[str, Heightmap]]:
        """(name, heightmap) of each usable input, in order."""
        datasets: dict[Path, object] = {}
        try:
            for name, path, sid in self._items:
                try:
                    hm = self._load(name, path, sid, datasets)
                    hm.require_footprint(self.footprint_mm, self.centre_mm, self.tile)
                except InputError as err:
                    named = err if str(path) in str(err) else InputError(f"{name}: {err}", err.parameter)
                    self.errors.append((name, named))
                    continue
                yield name, hm
        finally:
            for data in datasets.values():
                data.close()

    def _load(self, name: str, path: Path, sid: str | None, datasets: dict) -> Heightmap:
        if sid is None:
            return self._load_file(str(path), self.total > 1)
        if path not in datasets:
            from roughness.dataset.reader import open_dataset

            datasets[path] = open_dataset(path)
        return datasets[path].heightmap(sid)


def _is_dataset(path: Path) -> bool:
    import h5py  # only for .h5 inputs: a PNG prediction starts without it

    from roughness.dataset.schema import SCHEMA

    try:
        with h5py.File(path, "r") as h5:
            return h5.attrs.get("schema") == SCHEMA
    except OSError:
        return False  # not HDF5: loading it reports it

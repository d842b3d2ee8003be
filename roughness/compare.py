"""`roughness compare`: every engine on every texture of a set, scored against a reference engine.

Inputs: a dataset file (its stored FEM labels serve as results of ``fem:<its fidelity>`` when its
simulation parameters are the defaults), a folder of heightmaps, or a recipe JSON (its first
``n`` samples). Results go to ``results.jsonl`` in the output folder as they arrive, one line per
(engine, texture); a rerun reads it and computes only what is missing, so an interrupted
comparison resumes and FEM results are never recomputed. Textures run one at a time, every engine
in turn, in one process: the times are single-core times.
"""
from __future__ import annotations

import json
import os
import sys
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from roughness.core.errors import InputError
from roughness.simulate.heightmap import Heightmap

from .engines import FEM_FIDELITIES, Engine, fem_identity

RESULTS_FILE = "results.jsonl"
SETUP_KEY = "(set-up)"  # cache key of an engine's one-time preparation (FEM block, model loading)


@dataclass(frozen=True)
class Texture:
    key: str  # stable identity: sample id, or file name
    family: str
    load: Callable[[], Heightmap]


def dataset_textures(path: Path) -> tuple[list[Texture], dict[str, dict[str, dict]]]:
    """Samples of a dataset file, and its stored FEM results if they are reusable."""
    from roughness.dataset.store import open_dataset
    from roughness.simulate.config import SimConfig

    with open_dataset(path) as data:
        table, recipes, simulation = data.table(), data.recipes, data.config.simulation
    fidelity = simulation.get("fidelity")
    ok = [i for i, status in enumerate(table["status"]) if status == "ok"]

    samples = _DatasetSamples(path)
    textures = [Texture(str(table["id"][i]), recipes[i]["family"], partial(samples.heightmap, str(table["id"][i])))
                for i in ok]
    stored: dict[str, dict[str, dict]] = {}
    if fidelity in FEM_FIDELITIES and fem_identity(simulation) == fem_identity(SimConfig(fidelity=fidelity).as_dict()):
        stored[f"fem:{fidelity}"] = {str(table["id"][i]): {"value": float(table["V"][i]),
                                                          "seconds": float(table["seconds"][i]), "source": "dataset"}
                                     for i in ok}
    return textures, stored


class _DatasetSamples:
    """Heightmaps of one dataset file through one reader, opened on first use and closed with this object
    (opening a dataset reads its whole index: once per texture would cost seconds each on a large file)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._data = None

    def heightmap(self, sid: str) -> Heightmap:
        if self._data is None:
            from roughness.dataset.store import open_dataset

            self._data = open_dataset(self.path)
            weakref.finalize(self, self._data.close)
        return self._data.heightmap(sid)


def folder_textures(path: Path, pixel_mm: float | None, height_mm: float | None) -> list[Texture]:
    from roughness.simulate.io import heightmap_files, load_heightmap

    return [Texture(f.name, "file", lambda f=f: load_heightmap(f, pixel_mm, height_mm)) for f in heightmap_files(path)]


def recipe_textures(path: Path, n: int | None) -> list[Texture]:
    from roughness.dataset.recipe import expand, load_recipe, realise
    from roughness.dataset.store import sample_id

    if n is None:
        raise InputError("a recipe input needs --n, the number of its samples to compare on")
    return [Texture(sample_id(r), r["family"], lambda r=r: realise(r)) for r in expand(load_recipe(path), n)]


def textures_of(source: str, n: int | None = None, pixel_mm: float | None = None,
                height_mm: float | None = None) -> tuple[list[Texture], dict[str, dict[str, dict]]]:
    """The textures an INPUT names, and any stored results that come with it."""
    path = Path(source)
    if path.is_dir():
        return folder_textures(path, pixel_mm, height_mm), {}
    if not path.is_file():
        raise InputError(f"compare input not found: {source}")
    if path.suffix.lower() == ".json":
        return recipe_textures(path, n), {}
    if path.suffix.lower() in (".h5", ".hdf5"):
        textures, stored = dataset_textures(path)
        return textures[:n] if n else textures, stored
    raise InputError(f"{source}: compare takes a dataset (.h5), a folder of heightmaps or a recipe (.json)")


class ResultCache:
    """The output folder's results.jsonl: {engine, identity, key, value, seconds, error, source} per line.

    ``identities`` maps each engine spec to what its results depend on (configuration digest, model
    file digest); entries made under another identity (a retrained model, say) are ignored.
    """

    def __init__(self, folder: Path, identities: dict[str, str]) -> None:
        self.identities = identities
        folder.mkdir(parents=True, exist_ok=True)
        self.path = folder / RESULTS_FILE
        self.entries: dict[tuple[str, str], dict] = {}
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
                    raise InputError(f"{self.path} line {number} is not JSON: remove that line to recompute it") from None
                if entry.get("identity") == identities.get(entry["engine"]):
                    self.entries[(entry["engine"], entry["key"])] = entry

    def get(self, engine: str, key: str) -> dict | None:
        return self.entries.get((engine, key))

    def put(self, engine: str, key: str, **fields) -> None:
        entry = {"engine": engine, "identity": self.identities[engine], "key": key, **fields}
        self.entries[(engine, key)] = entry
        with open(self.path, "a") as f:
            f.write(json.dumps(entry) + "\n")
            f.flush()
            os.fsync(f.fileno())


def run(textures: list[Texture], engines: list[Engine], cache: ResultCache,
        stored: dict[str, dict[str, dict]], quiet: bool = False) -> None:
    """Fill the cache for every (engine, texture), and each engine's one-time set-up seconds (SETUP_KEY)."""
    for spec, results in stored.items():
        if spec not in cache.identities:
            continue
        for key, entry in results.items():
            if cache.get(spec, key) is None:
                cache.put(spec, key, **entry)
    todo = [(t, e) for t in textures for e in engines if cache.get(e.spec, t.key) is None]
    start, done = time.monotonic(), 0
    if not quiet:
        print(f"compare: {len(textures)} textures x {len(engines)} engines; {len(todo)} results to compute, "
              f"{len(textures) * len(engines) - len(todo)} cached", file=sys.stderr, flush=True)
    for texture in textures:
        pending = [e for e in engines if cache.get(e.spec, texture.key) is None]
        if not pending:
            continue
        try:
            heightmap = texture.load()
        except InputError as err:
            for engine in pending:
                cache.put(engine.spec, texture.key, value=None, seconds=None, error=f"input: {err}")
            continue
        for engine in pending:
            try:
                value, seconds = engine.measure(heightmap)
                cache.put(engine.spec, texture.key, value=value, seconds=seconds, error=None, source="computed")
                if engine.setup_seconds and cache.get(engine.spec, SETUP_KEY) is None:
                    cache.put(engine.spec, SETUP_KEY, seconds=engine.setup_seconds)
            except Exception as err:  # a failure is a result of the comparison, recorded with its reason
                cache.put(engine.spec, texture.key, value=None, seconds=None, error=f"{type(err).__name__}: {err}")
            done += 1
            if not quiet:
                rate = done / max(time.monotonic() - start, 1e-9)
                print(f"\r  {done}/{len(todo)} results, {texture.key} {engine.spec:<20s} ETA "
                      f"{(len(todo) - done) / rate / 60:5.1f} min", end="", file=sys.stderr, flush=True)
    if not quiet and todo:
        print(file=sys.stderr)

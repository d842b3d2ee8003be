"""`roughness compare`: every engine on every texture of a set, scored against a reference engine.

Inputs: a dataset file (its stored FEM labels serve as results of ``fem:<its fidelity>``, or of
``fem:converged@TOL`` for a build converged to another tolerance than the default, when its
simulation parameters are the defaults), a folder of heightmaps, or a recipe JSON (its first
``n`` samples). Results go to ``results.jsonl`` in the output folder as they arrive, one line per
(engine, texture), with its uncertainties (``engines.Measurement``: ``stderr_abs`` and ``ensemble_std_abs`` in V
units, ``discretization_rel`` a fraction of V; null where the engine has none), keyed by the texture's content (its heights and pixel size) and the engine's
identity (configuration, model file); a rerun reads it and computes only what is missing, so an
interrupted comparison resumes, FEM results are never recomputed, and a replaced file or another
``--pixel-mm`` is computed afresh. The folder's manifest (``compare.json``: input, number of
textures, reference, engines) is written before its first result, so that the same command finds
the same comparison there after an interruption and resumes it; another is refused. Inputs that
cannot be read are never cached: they are reported.
Textures run one at a time, every engine in turn, in one process: the times are single-core times.
"""
from __future__ import annotations

import json
import math
import sys
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from roughness.core.errors import InputError
from roughness.core.files import atomic_write, check_output_folder
from roughness.core.status_line import StatusLine
from roughness.surface.heightmap import Heightmap

from .engines import FEM_FIDELITIES, Engine, Measurement, fem_identity, fem_spec
from .result_cache import ResultCache, content_key

MANIFEST_FILE = "compare.json"  # what the report in a folder compares: input, reference, engines
SETUP_KEY = "(set-up)"  # cache key of an engine's one-time preparation (FEM block, model loading)
STORED = "dataset"  # ``source`` of results read from a dataset file (its build's times, not measured here)


@dataclass(frozen=True)
class Texture:
    name: str  # shown in the report: sample id or file name
    family: str
    load: Callable[[], Heightmap]


def dataset_textures(path: Path) -> tuple[list[Texture], dict[str, dict[str, dict]]]:
    """Samples of a dataset file, and its stored FEM results (by sample id) if they are reusable."""
    from roughness.dataset.reader import open_dataset
    from roughness.simulate.config import SimConfig

    with open_dataset(path) as data:
        table, records, simulation = data.table(), data.texture_records, data.config.simulation
    fidelity = simulation.get("fidelity")
    ok = [i for i, status in enumerate(table["status"]) if status == "ok"]

    samples = _DatasetSamples(path)
    textures = [Texture(str(table["id"][i]), records[i]["family"], partial(samples.heightmap, str(table["id"][i])))
                for i in ok]
    stored: dict[str, dict[str, dict]] = {}
    if fidelity in FEM_FIDELITIES and fem_identity(simulation) == fem_identity(SimConfig(
            fidelity=fidelity, tolerance=simulation.get("tolerance", SimConfig.tolerance)).as_dict()):
        stored[fem_spec(simulation)] = {str(table["id"][i]): {**_stored_measurement(table, i).fields(),
                                                          "source": STORED} for i in ok}
    return textures, stored


def _stored_measurement(table: dict, i: int) -> Measurement:
    """A dataset's FEM result for sample ``i`` with its uncertainties (missing ones, nan in the file: None)."""
    def known(name: str) -> float | None:
        value = float(table[name][i]) if name in table else math.nan
        return value if math.isfinite(value) else None

    return Measurement(float(table["V"][i]), float(table["seconds"][i]), known("V_stderr"),
                       known("discretization_error"))


class _DatasetSamples:
    """Heightmaps of one dataset file through one reader, opened on first use and closed with this object
    (opening a dataset reads its whole index: once per texture would cost seconds each on a large file)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._data = None

    def heightmap(self, sid: str) -> Heightmap:
        if self._data is None:
            from roughness.dataset.reader import open_dataset

            self._data = open_dataset(self.path)
            weakref.finalize(self, self._data.close)
        return self._data.heightmap(sid)


def folder_textures(path: Path, load: Callable[[Path], Heightmap]) -> list[Texture]:
    """The folder's heightmap files; ``load(path)`` loads one (the CLI: units, clean-up and checks)."""
    from roughness.surface.io import heightmap_files

    return [Texture(f.name, "file", lambda f=f: load(f)) for f in heightmap_files(path)]


def recipe_textures(path: Path, n: int | None) -> list[Texture]:
    from roughness.core.limits import MAX_DATASET_SAMPLES, check_size
    from roughness.dataset.recipe import expand, load_recipe, realise
    from roughness.dataset.schema import sample_id

    if n is None:
        raise InputError("a recipe input needs n=N, the number of its samples to compare on", parameter="n")
    check_size("samples of a recipe to compare on", n, MAX_DATASET_SAMPLES, "n")
    return [Texture(sample_id(r), r["family"], lambda r=r: realise(r)) for r in expand(load_recipe(path), n)]


def textures_of(source: str, n: int | None, load: Callable[[Path], Heightmap]
                ) -> tuple[list[Texture], dict[str, dict[str, dict]]]:
    """The textures an INPUT names, and any stored results that come with it (by texture name); ``load`` loads
    a folder's files (folder_textures)."""
    path = Path(source)
    if path.is_dir():
        return folder_textures(path, load), {}
    if not path.is_file():
        raise InputError(f"compare input not found: {source}", parameter="input")
    if path.suffix.lower() == ".json":
        return recipe_textures(path, n), {}
    if path.suffix.lower() in (".h5", ".hdf5"):
        textures, stored = dataset_textures(path)
        return textures[:n] if n else textures, stored
    raise InputError(f"{source}: compare takes a dataset (.h5), a folder of heightmaps or a recipe (.json)",
                     parameter="input")


def check_report_folder(folder: Path, manifest: dict, overwrite: bool = False) -> None:
    """Refuse (OutputExists) a folder holding anything but a report of the same comparison, unless ``overwrite``.

    The same comparison (input, number of textures, reference and engines) resumes there.
    """
    try:
        written = json.loads((folder / MANIFEST_FILE).read_text())
        same = isinstance(written, dict) and {k: v for k, v in written.items() if k != "provenance"} == manifest
    except (OSError, json.JSONDecodeError):
        same = False
    check_output_folder(folder, overwrite or same, "out")


def write_manifest(folder: Path, manifest: dict, provenance: dict | None = None) -> None:
    """The folder's manifest, with each engine's provenance record (spec -> record) if given."""
    folder.mkdir(parents=True, exist_ok=True)
    text = json.dumps(manifest | ({"provenance": provenance} if provenance else {}), indent=1) + "\n"
    atomic_write(folder / MANIFEST_FILE, lambda tmp: Path(tmp).write_text(text))


@dataclass
class Outcome:
    """What ``run`` found: the content key of every readable texture and the inputs that could not be used."""

    keys: dict[str, str] = field(default_factory=dict)  # texture name -> content key
    input_errors: list[tuple[str, str]] = field(default_factory=list)  # (texture name, message)
    computed: int = 0
    cached: int = 0


class Progress:
    """Progress on stderr (a ``StatusLine``: one updated line on a terminal, plain lines now and then otherwise).

    The ETA is the remaining results of each engine times that engine's mean time so far (set-up excluded).
    """

    def __init__(self, remaining: dict[str, int], quiet: bool) -> None:
        self.remaining, self.quiet = dict(remaining), quiet
        self.total, self.done = sum(remaining.values()), 0
        self.spent: dict[str, list[float]] = {e: [0.0, 0] for e in remaining}
        self.line = StatusLine()

    def eta_minutes(self) -> float | None:
        if any(n and not self.spent[e][1] for e, n in self.remaining.items()):
            return None  # an engine with work left has not finished a texture yet
        return sum(n * self.spent[e][0] / self.spent[e][1] for e, n in self.remaining.items() if n) / 60

    def step(self, engine: str, seconds: float, texture: str) -> None:
        self.done += 1
        self.remaining[engine] -= 1
        self.spent[engine][0] += seconds
        self.spent[engine][1] += 1
        if self.quiet:
            return
        eta = self.eta_minutes()
        text = f"  {self.done}/{self.total} results, {texture} {engine:<20s} ETA " + (
            f"{eta:5.1f} min" if eta is not None else "  ? min")
        self.line.show(text, last=self.done == self.total)

    def close(self) -> None:
        self.line.close()


def _input_error(outcome: Outcome, name: str, err: InputError) -> None:
    message = str(err) if name in str(err) else f"{name}: {err}"
    outcome.input_errors.append((name, message))
    print(f"roughness: error: {message}", file=sys.stderr, flush=True)


def run(textures: list[Texture], engines: list[Engine], cache: ResultCache,
        stored: dict[str, dict[str, dict]], quiet: bool = False) -> Outcome:
    """Fill the cache for every (engine, readable texture), and each engine's set-up seconds (SETUP_KEY).

    A first pass reads every texture for its content key (and takes over stored results); a
    second computes what is missing. Input errors are printed and returned, never cached.
    """
    outcome = Outcome()
    for texture in textures:
        try:
            key = content_key(texture.load())
        except InputError as err:
            _input_error(outcome, texture.name, err)
            continue
        outcome.keys[texture.name] = key
        for spec, results in stored.items():
            if spec in cache.identities and texture.name in results and cache.get(spec, key) is None:
                cache.put(spec, key, texture=texture.name, **results[texture.name])
    pending = {t.name: [e for e in engines if cache.get(e.spec, outcome.keys[t.name]) is None]
               for t in textures if t.name in outcome.keys}
    todo = sum(map(len, pending.values()))
    outcome.cached = len(outcome.keys) * len(engines) - todo
    if not quiet:
        print(f"compare: {len(textures)} textures x {len(engines)} engines; {todo} results to compute, "
              f"{outcome.cached} cached", file=sys.stderr, flush=True)
    progress = Progress({e.spec: sum(e in p for p in pending.values()) for e in engines}, quiet)
    try:
        for texture in textures:
            if not pending.get(texture.name):
                continue
            heightmap, key = texture.load(), outcome.keys[texture.name]
            for engine in pending[texture.name]:
                setup, start = engine.setup_seconds, time.perf_counter()
                try:
                    measured = engine.measure(heightmap)
                except InputError as err:  # the texture does not suit the engine (e.g. smaller than the footprint)
                    _input_error(outcome, texture.name, err)
                    del outcome.keys[texture.name]  # not compared: listed with its reason instead
                    break
                except Exception as err:  # a failure is a result of the comparison, recorded with its reason
                    cache.put(engine.spec, key, texture=texture.name, value=None, seconds=None,
                              error=f"{type(err).__name__}: {err}")
                else:
                    cache.put(engine.spec, key, texture=texture.name, **measured.fields(), error=None,
                              source="computed")
                    if engine.setup_seconds and cache.get(engine.spec, SETUP_KEY) is None:
                        cache.put(engine.spec, SETUP_KEY, seconds=engine.setup_seconds)
                outcome.computed += 1
                progress.step(engine.spec, time.perf_counter() - start - (engine.setup_seconds - setup), texture.name)
    finally:
        progress.close()
    return outcome

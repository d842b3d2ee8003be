"""V of the stimuli with any engine; FEM results (and their fluctuation fields) cached by content.

FEM runs through the engines' ``FemEngine`` and its results go to a ``ResultCache`` folder (as
``roughness compare``'s do), keyed by the heightmap's content (heights and pixel size) and the FEM
configuration's identity, never the file name, so a renamed file hits the cache and a changed texture
or configuration misses it. Each result keeps V, its standard error, and as arrays the lambda3
fluctuation field at receptor depth and its grid axis (mm), so the sampling (d, r) can be changed
later without new FEM runs.
"""
from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.engines import FemEngine
from roughness.result_cache import ResultCache, content_key
from roughness.surface.heightmap import Heightmap

ENGINES = ("surrogate", "auto", "fem:coarse", "fem:default", "fem:fine")
FIELD_ARRAYS = ("fluctuation", "grid_axis_mm")  # stored with each FEM result


@dataclass
class StimulusValue:
    """V of one stimulus and, for FEM, the field it came from."""

    stimulus: str
    roughness: float
    roughness_stderr: float  # Monte Carlo standard error of the pair sampling (NaN for the surrogate)
    engine: str
    fluctuation: np.ndarray | None = None  # lambda3 fluctuation at receptor depth (FEM only)
    grid_axis_mm: np.ndarray | None = None
    config: dict | None = None  # the FEM configuration


def check_engine(engine: str) -> str:
    if engine not in ENGINES:
        raise InputError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}", parameter="engine")
    return engine


def fem_value(stimulus: str, heightmap: Heightmap, cache: ResultCache, engine: FemEngine
              ) -> tuple[StimulusValue, bool]:
    """(FEM V of ``heightmap``, whether it came from the cache); runs and stores it on a miss, and on a damaged
    cache entry (noted in ``cache.notes``)."""
    key = content_key(heightmap)
    entry = cache.get(engine.spec, key)
    arrays = cache.arrays(engine.spec, key, FIELD_ARRAYS) if entry is not None else {}
    config = engine.config.as_dict()
    if arrays:
        return StimulusValue(stimulus, entry["value"], entry["stderr"], engine.spec, arrays["fluctuation"],
                             arrays["grid_axis_mm"], config), True
    result = engine.simulate(heightmap)
    value = StimulusValue(stimulus, float(result.roughness), float(result.roughness_stderr), engine.spec,
                          np.asarray(result.fluctuation, dtype=float), np.asarray(result.grid_axis_mm, dtype=float),
                          config)
    cache.put(engine.spec, key, arrays={"fluctuation": value.fluctuation, "grid_axis_mm": value.grid_axis_mm},
              texture=stimulus, value=value.roughness, stderr=value.roughness_stderr, seconds=result.seconds,
              resolved_config=result.config.as_dict())
    return value, False


def _warn(message: str) -> None:
    warnings.warn(message, stacklevel=3)


def stimulus_values(ids: Sequence[str], heightmaps: Sequence, engine: str, cache: Path | None = None,
                    progress: Callable[[str], None] | None = None, **overrides) -> list[StimulusValue]:
    """V of every stimulus (in order). FEM engines need ``cache`` (a folder, created if missing);
    ``overrides`` (e.g. ``force_n``) go to the FEM configuration."""
    import roughness

    check_engine(engine)
    if not engine.startswith("fem:"):
        if overrides:
            raise InputError(f"configuration overrides need a FEM engine, not {engine}", parameter="engine")
        predictions = roughness.predict(heightmaps, engine=engine)
        return [StimulusValue(s, float(p.roughness), float("nan"), p.engine) for s, p in zip(ids, predictions)]
    if cache is None:
        raise InputError("FEM values need a cache folder", parameter="cache")
    fem = FemEngine.of(engine[4:], overrides)
    results = ResultCache(cache, {fem.spec: fem.identity})
    out = []
    for i, (s, hm) in enumerate(zip(ids, heightmaps), 1):
        value, cached = fem_value(s, hm, results, fem)
        out.append(value)
        for note in results.notes:  # a damaged entry, computed again: said even without progress
            (progress or _warn)(f"note: {note}")
        results.notes.clear()
        if progress:
            progress(f"{engine} {i}/{len(ids)} {s}: V = {value.roughness:.4f}"
                     f"{' (cached)' if cached else ''}")
    return out

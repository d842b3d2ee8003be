"""V of the stimuli with any engine; FEM results (and their fluctuation fields) cached by content.

A FEM result is stored as ``<heights digest>-<configuration digest>.npz`` in the cache folder: the
digest of the heightmap's heights and pixel size (``array_digest``) and of the full simulation
configuration (``SimConfig.as_dict()``, centre and tiling), never the file name, so a renamed file
hits the cache and a changed texture or configuration misses it. Each file holds V, its standard
error, the lambda3 fluctuation field at receptor depth and its grid axis (mm), so the sampling
(d, r) can be changed later without new FEM runs.
"""
from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.core.files import atomic_write
from roughness.core.hashing import array_digest, digest

ENGINES = ("surrogate", "auto", "fem:coarse", "fem:default", "fem:fine")


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


def fem_config(fidelity: str, **overrides) -> dict:
    """The full FEM configuration of ``roughness.fem_roughness(hm, fidelity=..., **overrides)``."""
    import roughness

    return roughness.SimConfig(fidelity=fidelity, **overrides).as_dict()


def cache_path(cache: Path, heightmap, config: dict) -> Path:
    key = array_digest(heightmap.heights, heightmap.pixel_mm)
    return cache / f"{key}-{digest({'simulation': config, 'centre_mm': None, 'tile': False})}.npz"


def fem_value(stimulus: str, heightmap, cache: Path, fidelity: str, **overrides) -> tuple[StimulusValue, bool]:
    """(FEM V of ``heightmap``, whether it came from the cache); runs and stores it on a miss."""
    import roughness

    config = fem_config(fidelity, **overrides)
    path = cache_path(cache, heightmap, config)
    if path.is_file():
        with np.load(path) as data:
            return StimulusValue(stimulus, float(data["roughness"]), float(data["roughness_stderr"]),
                                 f"fem:{fidelity}", data["fluctuation"], data["grid_axis_mm"],
                                 json.loads(str(data["config"]))), True
    result = roughness.fem_roughness(heightmap, fidelity=fidelity, **overrides)
    value = StimulusValue(stimulus, float(result.roughness), float(result.roughness_stderr), f"fem:{fidelity}",
                          np.asarray(result.fluctuation, dtype=float), np.asarray(result.grid_axis_mm, dtype=float),
                          config)
    atomic_write(path, lambda tmp: np.savez_compressed(
        tmp, roughness=value.roughness, roughness_stderr=value.roughness_stderr, fluctuation=value.fluctuation,
        grid_axis_mm=value.grid_axis_mm, config=json.dumps(config, sort_keys=True),
        resolved_config=json.dumps(result.config.as_dict(), sort_keys=True)))
    return value, False


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
    cache.mkdir(parents=True, exist_ok=True)
    out = []
    for i, (s, hm) in enumerate(zip(ids, heightmaps), 1):
        value, cached = fem_value(s, hm, cache, engine[4:], **overrides)
        out.append(value)
        if progress:
            progress(f"{engine} {i}/{len(ids)} {s}: V = {value.roughness:.4f}"
                     f"{' (cached)' if cached else ''}")
    return out

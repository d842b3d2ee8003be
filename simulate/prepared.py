"""This process's simulators, made once and shared by whoever runs an engine: ``roughness.predict``, ``compare``,
the design tools, the perception analysis, ``roughness simulate`` and the dataset workers.

The FEM is one ``Simulator`` for the process (``model.SHARED``): every configuration runs on it, so a mesh, its
assembled block and its base field are made once per process and shared by every configuration on that mesh
(up to ``max_blocks`` meshes, least recently used dropped). The spectral engine is one ``SpectralSimulator`` per
configuration (its flat state and transfer functions depend on the tissue). Both are safe to share between
threads.
"""
from __future__ import annotations

import threading
from dataclasses import fields
from typing import TYPE_CHECKING

from roughness.surface.heightmap import Heightmap

from .config import SimConfig
from .model import SHARED, Simulator
from .result import Result

if TYPE_CHECKING:
    from .spectral.engine import SpectralResult, SpectralSimulator

_SPECTRAL: dict[SimConfig, SpectralSimulator] = {}
_SPECTRAL_LOCK = threading.Lock()


def prepare(config: SimConfig, engine: str = "fem") -> Simulator | SpectralSimulator:
    """The shared simulator of ``engine`` for ``config``, with the FEM's block and base field for it prepared."""
    if engine == "spectral":
        from .spectral.engine import SpectralSimulator

        with _SPECTRAL_LOCK:
            if config not in _SPECTRAL:
                _SPECTRAL[config] = SpectralSimulator(config)
            return _SPECTRAL[config]
    SHARED.block(config.resolved()).base(config.force_n, config.contact)
    return SHARED


def simulate(config: SimConfig, heightmap: Heightmap, centre_mm: tuple[float, float] | None = None,
             tile: bool = False, engine: str = "fem") -> Result | SpectralResult:
    """``engine``'s result for ``heightmap`` under the footprint at ``centre_mm`` (mm) with ``config``."""
    if engine == "spectral":
        return prepare(config, "spectral").run(heightmap, centre_mm, tile)
    return SHARED.run(heightmap, centre_mm, tile, **{f.name: getattr(config, f.name) for f in fields(config)})

"""Roughness engines that `roughness compare` times and scores: FEM fidelities, the surrogate, classical measures.

Spec strings: ``fem:coarse``, ``fem:default``, ``fem:fine``, ``surrogate`` (or ``surrogate:PATH.onnx``),
and the classical measures ``ra``, ``p90``, ``glcm_sum_of_squares``, ``glcm_sum_variance``.
Each engine returns a value and the seconds it took for one texture: FEM reports the solve with
its block prepared (mesh, assembly and base field are paid once per process and reported as
``setup_seconds``); the surrogate and the measures are timed end to end from the heightmap.
"""
from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from roughness.core.errors import InputError
from roughness.simulate.heightmap import Heightmap

from .classical import MEASURES, footprint

FEM_FIDELITIES = ("coarse", "default", "fine")


class Engine(Protocol):
    spec: str
    kind: str  # "fem", "surrogate" or "classical" (a measure, not an estimate of V)
    setup_seconds: float
    identity: str  # what the results depend on (configuration, model file): cached results must match it

    def measure(self, heightmap: Heightmap) -> tuple[float, float]:
        """(value, seconds) for one texture."""


@dataclass
class FemEngine:
    spec: str
    fidelity: str
    kind: str = "fem"
    setup_seconds: float = 0.0
    _simulator: object = field(default=None, repr=False)

    @property
    def identity(self) -> str:
        from roughness.simulate.config import SimConfig

        return fem_identity(SimConfig(fidelity=self.fidelity).as_dict())

    def measure(self, heightmap: Heightmap) -> tuple[float, float]:
        if self._simulator is None:
            from roughness.simulate.config import SimConfig
            from roughness.simulate.model import Simulator

            start = time.perf_counter()
            config = SimConfig(fidelity=self.fidelity)
            self._simulator = Simulator(config)
            self._simulator.block(config.resolved()).base(config.force_n, config.contact)
            self.setup_seconds = time.perf_counter() - start
        result = self._simulator.run(heightmap)
        return result.roughness, result.seconds


@dataclass
class SurrogateEngine:
    spec: str
    model_path: str | None = None
    kind: str = "surrogate"
    setup_seconds: float = 0.0
    _model: object = field(default=None, repr=False)

    @property
    def identity(self) -> str:
        from roughness.core.hashing import file_sha256
        from roughness.surrogate.predictor import DEFAULT_MODEL

        path = Path(self.model_path or DEFAULT_MODEL)
        if not path.is_file():
            raise InputError(f"surrogate model not found: {path}")
        return "model-" + file_sha256(path)[:16]

    @property
    def model(self):
        """The loaded model (one onnxruntime thread), loaded on first use."""
        from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel

        if self._model is None:
            start = time.perf_counter()
            self._model = SurrogateModel(self.model_path or DEFAULT_MODEL, threads=1)
            self.setup_seconds = time.perf_counter() - start
        return self._model

    def measure(self, heightmap: Heightmap) -> tuple[float, float]:
        from roughness.surrogate.predictor import predict

        model = self.model
        start = time.perf_counter()
        [p] = predict(heightmap, engine="surrogate", model=model)
        return p.roughness, time.perf_counter() - start


@dataclass
class ClassicalEngine:
    spec: str
    kind: str = "classical"
    setup_seconds: float = 0.0
    identity: str = "classical-1"  # bump when a measure's definition changes

    def measure(self, heightmap: Heightmap) -> tuple[float, float]:
        start = time.perf_counter()
        value = MEASURES[self.spec](footprint(heightmap))
        return value, time.perf_counter() - start


def fem_identity(simulation: dict) -> str:
    """Identity of FEM results: a digest of the full simulation configuration."""
    return "fem-" + hashlib.sha1(json.dumps(simulation, sort_keys=True).encode()).hexdigest()[:16]


def make_engine(spec: str) -> Engine:
    """Engine for a spec string; InputError lists the valid ones."""
    if spec.startswith("fem:") and spec[4:] in FEM_FIDELITIES:
        return FemEngine(spec, spec[4:])
    if spec == "surrogate" or spec.startswith("surrogate:"):
        return SurrogateEngine(spec, spec.partition(":")[2] or None)
    if spec in MEASURES:
        return ClassicalEngine(spec)
    valid = [f"fem:{f}" for f in FEM_FIDELITIES] + ["surrogate", "surrogate:MODEL.onnx", *MEASURES]
    raise InputError(f"unknown engine {spec!r}; valid: {', '.join(valid)}")

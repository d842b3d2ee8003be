"""The engines: FEM, the spectral engine, the surrogate and classical measures behind one interface.

Used by ``roughness compare``, the design tools and ``roughness.predict`` (``roughness.prediction``).

Spec strings (compare): ``fem:coarse``, ``fem:default``, ``fem:fine``, ``fem:converged`` (or ``fem:converged@TOL``,
refined to the relative tolerance TOL instead of the default 0.03), ``surrogate`` (or
``surrogate:PATH.onnx``), ``spectral``, and the classical measures ``ra``, ``p90``, ``glcm_sum_of_squares``,
``glcm_sum_variance``. Each engine returns a ``Measurement`` for one texture: the value, the seconds it took and
its uncertainties (FEM: Monte Carlo standard error and discretization error; spectral: Monte Carlo standard error;
surrogate ensemble: the members' spread; named ``_abs`` in V units or ``_rel`` as a fraction of V). FEM
reports the solve with its block prepared (mesh, assembly and base field are paid once per process
and reported as ``setup_seconds``); the surrogate and the measures are timed end to end from the
heightmap.
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from roughness.core.errors import InputError
from roughness.core.hashing import digest, file_sha256
from roughness.core.provenance import Provenance, make_provenance
from roughness.surface.heightmap import Heightmap

from .classical import MEASURES, footprint

if TYPE_CHECKING:
    from roughness.simulate.config import SimConfig
    from roughness.simulate.result import Result
    from roughness.simulate.spectral.engine import SpectralResult
    from roughness.surrogate.predictor import SurrogateModel

FEM_FIDELITIES = ("coarse", "default", "fine", "converged")


@dataclass(frozen=True)
class Measurement:
    """One engine's value for one texture, the seconds it took, and how sure the value is. Absolute uncertainties
    are in the value's units (``_abs``), relative ones a fraction of the value (``_rel``); None: the engine has no
    such estimate (classical measures have none)."""

    value: float
    seconds: float
    stderr_abs: float | None = None  # FEM, spectral: Monte Carlo standard error of V (V units)
    discretization_rel: float | None = None  # FEM: estimated relative error of V from the mesh
    ensemble_std_abs: float | None = None  # surrogate ensemble: spread of V over its members (V units)

    def fields(self) -> dict:
        """The fields a result line stores (``results.jsonl``)."""
        return {"value": self.value, "seconds": self.seconds, "stderr_abs": self.stderr_abs,
                "discretization_rel": self.discretization_rel, "ensemble_std_abs": self.ensemble_std_abs}


class Engine(Protocol):
    spec: str
    kind: str  # "fem", "surrogate" or "classical" (a measure, not an estimate of V)
    setup_seconds: float
    identity: str  # what the results depend on (configuration, model file): cached results must match it

    def measure(self, heightmap: Heightmap) -> Measurement:
        """The value for one texture, its seconds and its uncertainties."""


def fem_identity(simulation: dict) -> str:
    """Identity of FEM results: a digest of the full simulation configuration."""
    return "fem-" + digest(simulation)


@dataclass
class SimulatorEngine:
    """An engine that runs the process's shared simulator (``simulate.prepared``) with a configuration
    (``SimConfig``) on one footprint per texture.

    The simulator is prepared for the configuration on first use (its cost is ``setup_seconds``: nothing when
    another engine of the process prepared the same mesh already); threads share it.
    """

    spec: str
    config: SimConfig
    centre_mm: tuple[float, float] | None = None
    tile: bool = False
    kind: str = ""
    setup_seconds: float = 0.0
    _prepared: bool = field(default=False, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    def simulate(self, heightmap: Heightmap) -> Result | SpectralResult:
        """The simulator's result for one heightmap."""
        from roughness.simulate import prepared

        with self._lock:
            if not self._prepared:
                start = time.perf_counter()
                prepared.prepare(self.config, self.kind)
                self.setup_seconds, self._prepared = time.perf_counter() - start, True
        return prepared.simulate(self.config, heightmap, self.centre_mm, self.tile, self.kind)

    def measure(self, heightmap: Heightmap) -> Measurement:
        result = self.simulate(heightmap)
        error = getattr(result, "discretization_error", None)  # the spectral engine has no mesh
        return Measurement(result.roughness, result.seconds, result.roughness_stderr,
                           error if error is not None and math.isfinite(error) else None)


@dataclass
class FemEngine(SimulatorEngine):
    """The FEM with a configuration (``roughness.simulate.config.SimConfig``), prepared on first use.

    Thread-safe: threads share the process's one prepared ``Simulator`` and get the sequential answers bit for bit.
    """

    kind: str = "fem"

    @classmethod
    def of(cls, fidelity: str, simulation: dict | None = None, centre_mm: tuple[float, float] | None = None,
           tile: bool = False) -> FemEngine:
        """FEM at ``fidelity`` with the other parameters of ``simulation`` (default: the defaults)."""
        from roughness.simulate.config import SimConfig

        return cls(f"fem:{fidelity}", SimConfig(**{**(simulation or {}), "fidelity": fidelity}), centre_mm, tile)

    @property
    def fidelity(self) -> str:
        return self.config.fidelity

    @property
    def identity(self) -> str:
        return self.config.identity()


@dataclass
class SpectralEngine(SimulatorEngine):
    """The spectral skin engine (``roughness.simulate.spectral``) with a configuration (``SimConfig``)."""

    kind: str = "spectral"

    @classmethod
    def of(cls, simulation: dict | None = None, centre_mm: tuple[float, float] | None = None,
           tile: bool = False) -> SpectralEngine:
        from roughness.simulate.config import SimConfig

        return cls("spectral", SimConfig(**(simulation or {})), centre_mm, tile)

    @property
    def fidelity(self) -> str:
        return "spectral"

    @property
    def identity(self) -> str:
        from roughness.simulate.spectral.engine import identity

        return identity(self.config)


@dataclass
class SurrogateEngine:
    """The ONNX surrogate (default: the shipped model), loaded on first use."""

    spec: str
    model_path: str | None = None
    threads: int = 1
    kind: str = "surrogate"
    setup_seconds: float = 0.0
    _model: SurrogateModel | None = field(default=None, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    @property
    def path(self) -> Path:
        from roughness.surrogate.predictor import DEFAULT_MODEL

        return Path(self.model_path or DEFAULT_MODEL)

    @property
    def identity(self) -> str:
        self.model  # loads and checks the model file: a broken one is refused before any result is written
        return "model-" + file_sha256(self.path)[:16]

    @property
    def model(self) -> SurrogateModel:
        """The loaded ``SurrogateModel`` (loaded once; its ONNX session may run in several threads)."""
        from roughness.surrogate.predictor import SurrogateModel

        with self._lock:
            if self._model is None:
                start = time.perf_counter()
                self._model = SurrogateModel(self.path, threads=self.threads)
                self.setup_seconds = time.perf_counter() - start
        return self._model

    def measure(self, heightmap: Heightmap) -> Measurement:
        model = self.model
        start = time.perf_counter()
        estimate = model.evaluate(model.patch(heightmap, None, False)[None])
        spread = None if estimate.roughness_std is None else float(estimate.roughness_std[0])
        return Measurement(float(estimate.roughness[0]), time.perf_counter() - start, ensemble_std_abs=spread)


@dataclass
class ClassicalEngine:
    spec: str
    kind: str = "classical"
    setup_seconds: float = 0.0
    identity: str = "classical-1"  # bump when a measure's definition changes

    def measure(self, heightmap: Heightmap) -> Measurement:
        start = time.perf_counter()
        value = MEASURES[self.spec](footprint(heightmap))
        return Measurement(value, time.perf_counter() - start)


def fem_spec(simulation: dict) -> str:
    """The spec string of FEM results with this simulation configuration: ``fem:<fidelity>``, and
    ``fem:converged@TOL`` when converged to another tolerance than the default."""
    from roughness.simulate.config import SimConfig

    fidelity = simulation.get("fidelity", "default")
    tolerance = simulation.get("tolerance", SimConfig.tolerance)
    return f"fem:{fidelity}@{tolerance:g}" if fidelity == "converged" and tolerance != SimConfig.tolerance \
        else f"fem:{fidelity}"


def make_engine(spec: str, parameter: str = "engines") -> Engine:
    """Engine for a spec string; InputError lists the valid ones (naming ``parameter``, the option it came from)."""
    if spec.startswith("fem:") and spec[4:] in FEM_FIDELITIES:
        return FemEngine.of(spec[4:])
    if spec.startswith("fem:converged@"):
        try:
            tolerance = float(spec.partition("@")[2])
        except ValueError:
            raise InputError(f"engine {spec!r}: the tolerance after @ must be a number, e.g. fem:converged@0.01",
                             parameter=parameter) from None
        try:
            engine = FemEngine.of("converged", {"tolerance": tolerance})  # SimConfig checks 0 < tolerance < 1
        except InputError as err:
            raise InputError(f"engine {spec!r}: {err}", parameter=parameter) from None
        return replace(engine, spec=spec)
    if spec == "surrogate" or spec.startswith("surrogate:"):
        return SurrogateEngine(spec, spec.partition(":")[2] or None)
    if spec == "spectral":
        return SpectralEngine.of()
    if spec in MEASURES:
        return ClassicalEngine(spec)
    valid = [f"fem:{f}" for f in FEM_FIDELITIES] + ["fem:converged@TOL", "surrogate", "surrogate:MODEL.onnx", "spectral",
                                                    *MEASURES]
    raise InputError(f"unknown engine {spec!r}; valid: {', '.join(valid)}", parameter=parameter)


def model_provenance(model) -> Provenance:
    """Provenance of the surrogate ``model``'s answers: its configuration is that of its training labels."""
    return make_provenance("surrogate", model.fidelity, FemEngine.of(model.fidelity, model.meta.simulation).identity,
                           model)


def engine_provenance(engine: Engine) -> Provenance:
    """Provenance of an engine's results (``compare``): its kind, fidelity and identity, and its model if any."""
    if isinstance(engine, SurrogateEngine):
        return model_provenance(engine.model)
    kind = engine.spec if engine.kind == "classical" else engine.kind
    return make_provenance(kind, getattr(engine, "fidelity", None), engine.identity)


def spectral_provenance(simulation: dict | None = None) -> Provenance:
    """Provenance of the spectral engine's answers with ``simulation`` (default: the paper's parameters)."""
    return make_provenance("spectral", "spectral", SpectralEngine.of(simulation).identity)

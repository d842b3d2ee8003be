"""The engine layer: FEM, the surrogate, classical measures, and prediction with automatic dispatch.

Used by ``roughness predict``, ``roughness compare`` and the Python API (``roughness.predict``).

Spec strings (compare): ``fem:coarse``, ``fem:default``, ``fem:fine``, ``fem:converged`` (or ``fem:converged@TOL``,
refined to the relative tolerance TOL instead of the default 0.03), ``surrogate`` (or
``surrogate:PATH.onnx``), and the classical measures ``ra``, ``p90``, ``glcm_sum_of_squares``,
``glcm_sum_variance``. Each engine returns a value and the seconds it took for one texture: FEM
reports the solve with its block prepared (mesh, assembly and base field are paid once per process
and reported as ``setup_seconds``); the surrogate and the measures are timed end to end from the
heightmap.

``predict`` engines: ``surrogate`` (milliseconds), ``spectral`` (the skin as an infinite layer:
tens of milliseconds, ``roughness.simulate.spectral``), ``fem`` (the reference; seconds) and ``auto``
(the surrogate; for inputs outside the model's domain and, with an ensemble model, for inputs whose
relative spread roughness_std / (V + 0.001) exceeds ``max_std`` (by default the threshold measured
when the ensemble was exported, see surrogate/ensemble.py), the spectral engine on a flat base where
its contact fraction is at least ``SPECTRAL_MIN_CONTACT``, else the FEM). The FEM runs with the
model's simulation parameters at the fidelity of its training labels unless told otherwise (a given
``fidelity`` also makes ``auto`` skip the spectral rung); each answer is placed on the standard scale
of its own engine and fidelity.
"""
from __future__ import annotations

import itertools
import math
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np

from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.hashing import digest, file_sha256
from roughness.core.provenance import Provenance, make_provenance
from roughness.core.reprs import short_repr, v_text
from roughness.models import MODELS_DIR
from roughness.surface.heightmap import Heightmap, heightmaps_of

from .classical import MEASURES, footprint

if TYPE_CHECKING:
    from roughness.perceptual_scale import Placement

FEM_FIDELITIES = ("coarse", "default", "fine", "converged")
PREDICT_ENGINES = ("surrogate", "spectral", "fem", "auto")
# auto's spectral rung answers where its contact fraction is at least this: against FEM converged to 1% on the
# validation set, p95 error 6.0% there (145 of 160 textures), 17% below (studies/results/spectral_validation.md)
SPECTRAL_MIN_CONTACT = 0.9
CURVATURE_RANGE_PATH = MODELS_DIR / "curvature_range.json"


class Engine(Protocol):
    spec: str
    kind: str  # "fem", "surrogate" or "classical" (a measure, not an estimate of V)
    setup_seconds: float
    identity: str  # what the results depend on (configuration, model file): cached results must match it

    def measure(self, heightmap: Heightmap) -> tuple[float, float]:
        """(value, seconds) for one texture."""


def fem_identity(simulation: dict) -> str:
    """Identity of FEM results: a digest of the full simulation configuration."""
    return "fem-" + digest(simulation)


@dataclass
class SimulatorEngine:
    """An engine that runs a simulator of a configuration (``SimConfig``) on one footprint per texture.

    The simulator is made on first use, once (its cost is ``setup_seconds``); threads share it.
    """

    spec: str
    config: object  # SimConfig
    centre_mm: tuple[float, float] | None = None
    tile: bool = False
    kind: str = ""
    setup_seconds: float = 0.0
    _simulator: object = field(default=None, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    def _make(self) -> object:
        """The prepared simulator (``run(heightmap, centre_mm, tile)``)."""
        raise NotImplementedError

    def simulate(self, heightmap: Heightmap):
        """The simulator's result for one heightmap."""
        with self._lock:
            if self._simulator is None:
                start = time.perf_counter()
                self._simulator = self._make()
                self.setup_seconds = time.perf_counter() - start
        return self._simulator.run(heightmap, self.centre_mm, self.tile)

    def measure(self, heightmap: Heightmap) -> tuple[float, float]:
        result = self.simulate(heightmap)
        return result.roughness, result.seconds


@dataclass
class FemEngine(SimulatorEngine):
    """The FEM with a configuration (``roughness.simulate.config.SimConfig``), prepared on first use.

    Thread-safe: threads share its one prepared ``Simulator`` and get the sequential answers bit for bit.
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
        return self.config.identity("fem")

    def _make(self) -> object:
        from roughness.simulate.model import Simulator

        simulator = Simulator(self.config)
        simulator.block(self.config.resolved()).base(self.config.force_n, self.config.contact)
        return simulator


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
        return self.config.identity("spectral")

    def _make(self) -> object:
        from roughness.simulate.spectral.engine import SpectralSimulator

        return SpectralSimulator(self.config)


@dataclass
class SurrogateEngine:
    """The ONNX surrogate (default: the shipped model), loaded on first use."""

    spec: str
    model_path: str | None = None
    threads: int = 1
    kind: str = "surrogate"
    setup_seconds: float = 0.0
    _model: object = field(default=None, repr=False)
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
    def model(self):
        """The loaded ``SurrogateModel`` (loaded once; its ONNX session may run in several threads)."""
        from roughness.surrogate.predictor import SurrogateModel

        with self._lock:
            if self._model is None:
                start = time.perf_counter()
                self._model = SurrogateModel(self.path, threads=self.threads)
                self.setup_seconds = time.perf_counter() - start
        return self._model

    def measure(self, heightmap: Heightmap) -> tuple[float, float]:
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


@dataclass(frozen=True)
class CurvatureRange:
    """Curved bases on which the flat-trained surrogate may answer, as measured by studies/curvature.py.

    Per base shape (cylinder, sphere): convex radii (mm) from ``min_convex_radius_mm`` and concave
    ones from ``min_concave_radius_mm`` (None: no studied radius qualified); there flat and curved V
    agreed within ``tolerance`` (relative) for every studied texture. Shapes not studied: none.
    """

    limits: dict[str, tuple[float | None, float | None]]
    tolerance: float
    source: str

    @classmethod
    def load(cls, path: str | Path | None = None) -> CurvatureRange:
        """The range in ``path`` (default: the shipped ``models/curvature_range.json``)."""
        import json

        path = Path(path or CURVATURE_RANGE_PATH)
        data = json.loads(path.read_text())
        limits = {base: (entry["min_convex_radius_mm"], entry["min_concave_radius_mm"])
                  for base, entry in data["bases"].items()}
        return cls(limits, data["tolerance"], f"measured by studies/curvature.py, {path.name}")

    def outside(self, radius_mm: float, base: str) -> str:
        """Why the flat-trained surrogate may not answer for this base (empty if it may)."""
        if base not in self.limits:
            return (f"curved base: the flat-trained surrogate's range of curvatures was not measured on a {base} "
                    f"({self.source})")
        side = "convex" if radius_mm > 0 else "concave"
        limit = self.limits[base][0 if radius_mm > 0 else 1]
        if limit is not None and abs(radius_mm) >= limit:
            return ""
        where = f"below {limit:g} mm" if limit is not None else "at every studied radius"
        return (f"curved base: a {side} {base} of radius {abs(radius_mm):g} mm is outside the range where the "
                f"flat-trained surrogate agrees with the curved FEM within {100 * self.tolerance:.0f}% ({side} radii "
                f"{where} differ more; {self.source})")


@dataclass
class Prediction:
    """Roughness V (dimensionless strain variation) of one input and how it was obtained."""

    source: str
    roughness: float
    engine: str  # "surrogate" or "fem"
    fidelity: str  # FEM fidelity of the engine's scale (for the surrogate: of its training labels)
    in_domain: bool
    seconds: float  # wall time spent on this input (batched surrogate time is shared out)
    placement: Placement  # on the standard scale of its engine and fidelity
    domain_notes: list[str] = field(default_factory=list)
    roughness_stderr: float | None = None  # FEM: Monte Carlo standard error of V; surrogate: not estimated yet
    roughness_std: float | None = None  # surrogate ensemble: spread of V over its members; None: not estimated
    discretization_error: float | None = None  # FEM: estimated relative error of V from the mesh
    provenance: Provenance | None = None  # tool version, model, engine, configuration digest
    curvature_error: float | None = None  # a flat engine's V corrected for a curved base: the correction's error (V)

    def __repr__(self) -> str:
        v = v_text(self.roughness, self.roughness_stderr)
        if self.roughness_std is not None:
            v += f" (ensemble spread {self.roughness_std:.2g})"
        if self.curvature_error is not None:
            v += f" (curvature correction ± {self.curvature_error:.2g})"
        engine = self.engine if self.fidelity == self.engine else f"{self.engine} ({self.fidelity})"
        return short_repr(self, repr(self.source), v, engine,
                          "in domain" if self.in_domain else "out of domain",
                          self.placement.describe(), f"{len(self.domain_notes)} note(s)"
                          if self.domain_notes else "")

    def as_dict(self) -> dict:
        return {"input": self.source, "roughness": self.roughness, "roughness_stderr": self.roughness_stderr,
                "roughness_std": self.roughness_std, "discretization_error": self.discretization_error,
                "curvature_error": self.curvature_error,
                "engine": self.engine, "fidelity": self.fidelity, "in_domain": self.in_domain,
                "seconds": self.seconds, **self.placement.as_dict(), "domain_notes": self.domain_notes,
                "provenance": None if self.provenance is None else self.provenance.as_dict()}


def predict(heightmaps: Heightmap | np.ndarray | Iterable[Heightmap | np.ndarray], engine: str = "auto",
            model: object | str | Path | None = None, centre_mm: tuple[float, float] | None = None,
            tile: bool = False, fidelity: str | None = None, tolerance: float | None = None, batch_size: int = 256,
            sources: Iterable[str] | None = None,
            on_result: Callable[[Prediction], None] | None = None, max_std: float | None = None,
            curvature_mm: float | None = None, base: str = "cylinder", curvature_axis: str = "x",
            texture_along: str = "normal", pixel_mm: float | None = None) -> list[Prediction]:
    """Predict the roughness V (dimensionless strain variation) of each heightmap.

    Parameters
    ----------
    heightmaps : Heightmap, 2-D array of heights (mm), or an iterable of them
        The textures; arrays need ``pixel_mm``.
    engine : {"auto", "surrogate", "spectral", "fem"}
        See the module docstring: ``auto`` is the surrogate, climbing to the spectral engine or the FEM where
        the input is outside its domain or too uncertain.
    model : SurrogateModel or path, optional
        The ONNX surrogate (default: the shipped one).
    centre_mm : (float, float), optional
        Centre (x, y) of the 10 mm skin footprint (mm; default: the map's centre).
    tile : bool
        The map is one period of a periodic texture.
    fidelity : str, optional
        The FEM's (default: the model's training labels'; ``converged`` refines to ``tolerance``, relative).
    batch_size : int
        Surrogate inputs per network call.
    sources : iterable of str, optional
        Names of the inputs in the results (default: ``heightmap 0``, ...).
    on_result : callable, optional
        Called with each ``Prediction`` as it is ready.
    max_std : float, optional
        Relative ensemble spread above which ``auto`` runs a physics engine (default: the model's).
    curvature_mm, base, curvature_axis, texture_along
        A curved base under the texture (radius in mm; ``SimConfig``'s fields): inside the ``CurvatureRange``
        the flat-trained surrogate answers; outside it ``auto`` runs the curved FEM.
    pixel_mm : float, optional
        Pixel size (mm) of array inputs.

    Returns
    -------
    list of Prediction
        One per input, in order: V, its error, engine, domain and place on the standard scale.

    Raises
    ------
    InputError
        A bad option or input (an array without ``pixel_mm``, NaN/Inf heights, not 2-D).
    """
    from roughness.perceptual_scale import load_scale
    from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel

    if engine not in PREDICT_ENGINES:
        raise InputError(f"unknown engine {engine!r}; choose one of {', '.join(PREDICT_ENGINES)}", parameter="engine")
    integer("batch_size", batch_size, minimum=1)
    heightmaps = heightmaps_of(heightmaps, pixel_mm)
    if engine == "spectral":
        return _predict_spectral(heightmaps, centre_mm, tile, fidelity, tolerance, sources, on_result, curvature_mm)
    model = model if isinstance(model, SurrogateModel) else SurrogateModel(model or DEFAULT_MODEL)
    max_std = uncertainty_limit(model, max_std)
    curved = {"curvature_mm": curvature_mm, "base": base, "curvature_axis": curvature_axis,
              "texture_along": texture_along} if curvature_mm is not None else {}
    simulation = {**model.meta.simulation, **({} if tolerance is None else {"tolerance": tolerance}), **curved}
    fem = FemEngine.of(fidelity or model.fidelity, simulation, centre_mm, tile)
    off_base = [CurvatureRange.load().outside(curvature_mm, base)] if curved else []
    off_base = [why for why in off_base if why]
    # auto climbs surrogate -> spectral -> FEM: the spectral engine answers for a flat base where its measured
    # error allows (``SPECTRAL_MIN_CONTACT``), unless a FEM fidelity was asked for
    spectral = SpectralEngine.of(simulation, centre_mm, tile) if engine == "auto" and not curved and fidelity is None \
        else None
    # converged FEM answers are placed on the most accurate tabulated scale, ``fine``'s
    surrogate_scale = load_scale(model.fidelity)
    fem_scale = load_scale("fine" if fem.fidelity == "converged" else fem.fidelity)
    names = iter(sources) if sources is not None else (f"heightmap {i}" for i in itertools.count())
    results: list[Prediction] = []
    batch: list[tuple[str, Heightmap]] = []
    # the surrogate's configuration is that of its training labels; the FEM's here comes from the model too
    surrogate_provenance = model_provenance(model)
    fem_provenance = make_provenance("fem", fem.fidelity, fem.identity, model)

    def flush() -> None:
        start = time.perf_counter()
        estimate = model.evaluate(np.stack([model.patch(hm, centre_mm, tile) for _, hm in batch]))
        share = (time.perf_counter() - start) / len(batch)
        spread = [None] * len(batch) if estimate.roughness_std is None else estimate.roughness_std.tolist()
        relative = [None] * len(batch) if estimate.relative_std is None else estimate.relative_std.tolist()
        for (source, hm), v, why, std, rel in zip(batch, estimate.roughness, estimate.reasons, spread, relative):
            why = list(why) + off_base
            notes = list(why)
            if max_std is not None and rel > max_std:
                notes.append(f"uncertain: relative spread {rel:.3g} above the limit {max_std:.3g}")
            climbed = _spectral_rung(spectral, hm, notes) if engine == "auto" and notes and spectral else None
            if climbed is not None:
                result = _spectral_prediction(source, climbed, not why, notes, spectral.identity, model)
            elif engine == "fem" or (engine == "auto" and notes):
                r = fem.simulate(hm)
                error = r.discretization_error
                if error is not None and not math.isfinite(error):  # relative to V = 0: undefined, not Infinity
                    error = None
                    notes.append("discretization error undefined: V is 0 at this mesh but not at the coarser one")
                result = Prediction(source, r.roughness, "fem", fem.fidelity, not why, r.seconds,
                                    fem_scale.place(r.roughness), notes, r.roughness_stderr,
                                    discretization_error=error, provenance=fem_provenance)
            else:
                v, curvature_error = float(v), None
                if curved:  # the flat-trained answer, corrected by the curvature study's measurement
                    v, curvature_error = _curvature_corrected(v, curvature_mm, base, texture_along, notes)
                result = Prediction(source, v, "surrogate", model.fidelity, not why, share,
                                    surrogate_scale.place(v), notes, roughness_std=std,
                                    provenance=surrogate_provenance, curvature_error=curvature_error)
            results.append(result)
            if on_result:
                on_result(result)
        batch.clear()

    for hm in heightmaps:
        batch.append((next(names), hm))
        if len(batch) >= batch_size:
            flush()
    if batch:
        flush()
    return results


def _curvature_corrected(roughness: float, radius_mm: float, base: str, texture_along: str,
                         notes: list[str]) -> tuple[float, float | None]:
    """A flat engine's V on a cylinder or sphere of signed radius (mm): times the curvature study's measured
    correction (``roughness.objects.correction``), with its error (V); a note says which (or why none)."""
    from roughness.objects.correction import for_base

    if texture_along != "normal":
        notes.append("curved base: no correction was measured for heights along z; the flat V is given")
        return roughness, None
    try:
        fix = for_base(radius_mm, base)
    except InputError as err:
        notes.append(f"curved base: {err}; the flat V is given")
        return roughness, None
    notes.append(fix.note)
    return roughness * fix.factor, abs(roughness) * fix.error


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


def _spectral_rung(spectral: SpectralEngine, hm: Heightmap, notes: list[str]):
    """The spectral engine's answer for ``auto`` where its measured error allows, else None (and a note why)."""
    try:
        result = spectral.simulate(hm)
    except InputError as err:
        notes.append(f"spectral engine: {err}; FEM")
        return None
    if not result.converged or result.contact_fraction < SPECTRAL_MIN_CONTACT:
        notes.append(f"spectral engine: contact fraction {result.contact_fraction:.2f} below {SPECTRAL_MIN_CONTACT}, "
                     "where its error grows; FEM" if result.converged else f"spectral engine: {result.message}; FEM")
        return None
    return result


def _spectral_prediction(source: str, result, in_domain: bool, notes: list[str], identity: str,
                         model: object | None = None) -> Prediction:
    """A ``SpectralResult`` as a prediction, placed on the spectral standard scale; ``notes`` come before its own.

    ``identity`` is the engine's configuration digest; ``model`` the surrogate consulted first (``auto``), if any."""
    from roughness.perceptual_scale import load_scale

    return Prediction(source, result.roughness, "spectral", "spectral", in_domain, result.seconds,
                      load_scale("spectral").place(result.roughness), notes + result.notes, result.roughness_stderr,
                      provenance=make_provenance("spectral", "spectral", identity, model))


def _predict_spectral(heightmaps: Iterable[Heightmap], centre_mm: tuple[float, float] | None, tile: bool,
                      fidelity: str | None, tolerance: float | None, sources: Iterable[str] | None,
                      on_result: Callable[[Prediction], None] | None, curvature_mm: float | None) -> list[Prediction]:
    """``predict`` with the spectral engine: the paper's parameters, no surrogate loaded."""
    for name, value in (("fidelity", fidelity), ("tolerance", tolerance)):
        if value is not None:
            raise InputError("the spectral engine has no mesh: this option is the FEM's", parameter=name)
    if curvature_mm is not None:
        raise InputError("the spectral engine models a flat skin layer; curved bases need --engine fem",
                         parameter="curvature_mm")
    spectral = SpectralEngine.of(centre_mm=centre_mm, tile=tile)
    names = iter(sources) if sources is not None else (f"heightmap {i}" for i in itertools.count())
    results = []
    for hm in heightmaps:
        result = _spectral_prediction(next(names), spectral.simulate(hm), True, [], spectral.identity)
        results.append(result)
        if on_result:
            on_result(result)
    return results


def uncertainty_limit(model, max_std: float | None) -> float | None:
    """The relative spread above which ``auto`` runs the FEM: ``max_std``, else the ensemble's measured default.

    InputError if ``max_std`` is given for a model without an uncertainty (a single network).
    """
    from roughness.core.checks import positive

    if max_std is None:
        return (model.meta.ensemble or {}).get("max_std") if model.has_std else None
    positive("max_std", max_std)
    if not model.has_std:
        raise InputError(f"{model.path.name} is a single network without an uncertainty; --max-std needs an "
                         "ensemble model (surrogate/ensemble.py)", parameter="max_std")
    return float(max_std)

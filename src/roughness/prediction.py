"""Prediction with automatic dispatch: ``roughness.predict``.

Engines: ``surrogate`` (milliseconds), ``spectral`` (the skin as an infinite layer: tens of
milliseconds, ``roughness.simulate.spectral``), ``fem`` (the reference; seconds) and ``auto`` (the
surrogate; for inputs outside the model's domain and, with an ensemble model, for inputs whose
relative spread roughness_std / (V + 0.001) exceeds ``max_std`` (by default the threshold measured
when the ensemble was exported, see surrogate/ensemble.py), the spectral engine on a flat base where
its contact fraction is at least ``SPECTRAL_MIN_CONTACT``, else the FEM). The FEM runs with the
model's simulation parameters at the fidelity of its training labels unless told otherwise (a given
``fidelity`` also makes ``auto`` skip the spectral rung); each answer is placed on the standard scale
of its own engine and fidelity.
"""
from __future__ import annotations

import math
import numbers
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.checks import choice, flag, function, in_range, integer, positive, real
from roughness.core.errors import InputError
from roughness.core.limits import MAX_BATCH, check_size
from roughness.core.provenance import Provenance, make_provenance
from roughness.core.reprs import short_repr, v_text
from roughness.models import MODELS_DIR
from roughness.simulate.config import CHOICES, CURVED_FIELDS, SimConfig
from roughness.surface.arguments import heightmap_argument
from roughness.surface.heightmap import Heightmap, check_centre
from roughness.surface.tiling import check_tile

from .engines import FEM_FIDELITIES, FemEngine, SpectralEngine, model_provenance

if TYPE_CHECKING:
    from roughness.perceptual_scale import Placement
    from roughness.simulate.spectral.engine import SpectralResult
    from roughness.surrogate.predictor import SurrogateModel

PREDICT_ENGINES = ("surrogate", "spectral", "fem", "auto")
# auto's spectral rung answers where its contact fraction is at least this: against FEM converged to 1% on the
# validation set, p95 error 6.0% there (145 of 160 textures), 17% below (studies/results/spectral_validation.md)
SPECTRAL_MIN_CONTACT = 0.9
CURVATURE_RANGE_PATH = MODELS_DIR / "curvature_range.json"
Inputs = Heightmap | np.ndarray | Mapping[str, Heightmap | np.ndarray] | Iterable[
    Heightmap | np.ndarray | tuple[str, Heightmap | np.ndarray]]


@dataclass(frozen=True)
class CurvedBase:
    """A cylinder or sphere under the texture (``SimConfig``'s curvature fields)."""

    radius_mm: float  # signed: positive convex, negative concave
    shape: str = "cylinder"  # "cylinder" or "sphere"
    axis: str = "x"  # a cylinder's axis
    texture_along: str = "normal"  # heights laid off along the base's normal, or along z

    def __post_init__(self) -> None:
        if real("radius_mm", self.radius_mm) == 0:
            raise InputError("radius_mm is a signed radius (> 0 convex, < 0 concave); 0 is not a radius (leave the "
                             "base out for a flat one)", parameter="radius_mm")
        choice("shape", self.shape, CHOICES["base"])
        choice("axis", self.axis, CHOICES["curvature_axis"])
        choice("texture_along", self.texture_along, CHOICES["texture_along"])

    def simulation(self) -> dict:
        """The ``SimConfig`` fields of this base."""
        return {"curvature_mm": self.radius_mm, "base": self.shape, "curvature_axis": self.axis,
                "texture_along": self.texture_along}


@dataclass(frozen=True)
class PredictOptions:
    """How ``predict`` answers; every field's default is what a plain call gets.

    ``centre_mm``: centre (x, y) of the 10 mm skin footprint (mm; default: the map's centre); ``tile``: each map is
    one period of a periodic texture; ``fidelity``: the FEM's (default: the model's training labels';
    ``converged`` refines to ``tolerance``, relative); ``max_std``: relative ensemble spread above which ``auto``
    runs a physics engine (default: the model's); ``batch_size``: surrogate inputs per network call; ``curved``: a
    curved base under the texture (inside the ``CurvatureRange`` the flat-trained surrogate answers, corrected by
    the curvature study; outside it ``auto`` runs the curved FEM).
    """

    centre_mm: tuple[float, float] | None = None
    tile: bool = False
    fidelity: str | None = None
    tolerance: float | None = None
    max_std: float | None = None
    batch_size: int = 256
    curved: CurvedBase | None = None

    def __post_init__(self) -> None:
        """Each field checked as the command line checks its option (InputError naming the field)."""
        tile = flag("tile", self.tile)
        if self.centre_mm is not None:
            check_centre(self.centre_mm, tile)
        if self.fidelity is not None:
            choice("fidelity", self.fidelity, FEM_FIDELITIES)
        if self.tolerance is not None:
            in_range("tolerance", positive("tolerance", self.tolerance), 0.0, 1.0)
        if self.max_std is not None:
            positive("max_std", self.max_std)
        check_size("inputs per surrogate batch", integer("batch_size", self.batch_size, minimum=1), MAX_BATCH,
                   "batch_size")
        if self.curved is not None and not isinstance(self.curved, CurvedBase):
            raise InputError(f"curved must be a CurvedBase (or None for a flat base), got {self.curved!r}",
                             parameter="curved")


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
                          domain_words(self, notes=False), self.placement.describe(), f"{len(self.domain_notes)} note(s)"
                          if self.domain_notes else "")

    def as_dict(self) -> dict:
        return {"input": self.source, "roughness": self.roughness, "roughness_stderr": self.roughness_stderr,
                "roughness_std": self.roughness_std, "discretization_error": self.discretization_error,
                "curvature_error": self.curvature_error,
                "engine": self.engine, "fidelity": self.fidelity, "in_domain": self.in_domain,
                "seconds": self.seconds, **self.placement.as_dict(), "domain_notes": self.domain_notes,
                "provenance": None if self.provenance is None else self.provenance.as_dict()}


def domain_words(p: Prediction, notes: bool = True) -> str:
    """Whose domain ``p.in_domain`` is, in words: the surrogate's, for every engine (``--engine spectral`` checks it
    too). A surrogate answer outside it is OUT OF DOMAIN; a physics engine's answer (``auto`` climbed, or asked for)
    is its own, so it only says that the surrogate's domain did not hold and which engine answered. ``notes``: with
    the reasons (the repr leaves them out and counts them)."""
    if p.in_domain:
        return "in domain"
    why = f" ({'; '.join(p.domain_notes)})" if notes else ""
    if p.engine == "surrogate":
        return f"OUT OF DOMAIN: {'; '.join(p.domain_notes)}" if notes else "out of domain"
    return f"outside the surrogate's domain{why}; the {p.engine} engine answered"


def predict(inputs: Inputs, engine: str = "auto", model: SurrogateModel | str | Path | None = None,
            options: PredictOptions | None = None, *, pixel_mm: float | None = None, units_ok: bool = False,
            on_result: Callable[[Prediction], None] | None = None) -> list[Prediction]:
    """Predict the roughness V (dimensionless strain variation) of each heightmap.

    Parameters
    ----------
    inputs : Heightmap, 2-D array of heights (mm), a mapping name -> either, or an iterable of them or of
        (name, heightmap) pairs
        The textures (arrays, and nested lists of rows, need ``pixel_mm``); names label the results (default:
        ``heightmap 0``, ...). Missing points (NaN, masked) are refused: ``as_heightmap(..., fill=True)`` fills them.
    engine : {"auto", "surrogate", "spectral", "fem"}
        See the module docstring: ``auto`` is the surrogate, climbing to the spectral engine or the FEM where
        the input is outside its domain or too uncertain.
    model : SurrogateModel or path, optional
        The ONNX surrogate (default: the shipped one).
    options : PredictOptions, optional
        Footprint position, periodic maps, FEM fidelity, auto's threshold, batch size, a curved base.
    pixel_mm : float, optional
        Pixel size (mm) of array inputs.
    units_ok : bool
        The heights and pixel size are mm even though their relief, slope or pixel size look like metres or
        micrometres (``roughness.surface.units``; default: refuse them, as the command line does).
    on_result : callable, optional
        Called with each ``Prediction`` as it is ready.

    Returns
    -------
    list of Prediction
        One per input, in order: V, its error, engine, domain and place on the standard scale.

    Raises
    ------
    InputError
        A bad argument or input (an array without ``pixel_mm``, missing or infinite heights, not 2-D, numbers that
        look like metres or micrometres, a map smaller than the footprint without ``tile``), named by its
        ``parameter``; every input is checked before an engine runs on it.
    """
    options = _options(options)
    function("on_result", on_result)
    flag("units_ok", units_ok)
    return predictions(_checked_inputs(inputs, pixel_mm, units_ok, options), engine, model, options, on_result)


def predictions(named: Iterable[tuple[str, Heightmap]], engine: str = "auto",
                model: SurrogateModel | str | Path | None = None, options: PredictOptions | None = None,
                on_result: Callable[[Prediction], None] | None = None) -> list[Prediction]:
    """``predict`` of (name, Heightmap) pairs already checked as inputs (by ``predict``, or by the command line
    as it loads each file; the design tools' own variants of a checked texture): the engines only."""
    engine = choice("engine", engine, PREDICT_ENGINES)
    options = _options(options)
    if engine == "spectral":
        return _predict_spectral(named, _spectral_engine(options), _domain_model(model), options, on_result)
    dispatch = _Dispatch.make(engine, model, options)
    results: list[Prediction] = []
    batch: list[tuple[str, Heightmap]] = []
    for item in named:
        batch.append(item)
        if len(batch) >= options.batch_size:
            results += dispatch.answer(batch, on_result)
            batch = []
    if batch:
        results += dispatch.answer(batch, on_result)
    return results


def _options(options: object) -> PredictOptions:
    """``options``, or the defaults for None; InputError for anything but a PredictOptions."""
    if options is None:
        return PredictOptions()
    if not isinstance(options, PredictOptions):
        raise InputError(f"options must be a roughness.PredictOptions (or None), got {type(options).__name__}",
                         parameter="options")
    return options


def _checked_inputs(inputs: Inputs, pixel_mm: float | None, units_ok: bool,
                    options: PredictOptions) -> Iterator[tuple[str, Heightmap]]:
    """The named inputs, each checked as the command line checks a file as it loads it, before an engine sees it:
    a Heightmap of heights in mm (``surface.arguments``: units too), the skin footprint on it (at
    ``options.centre_mm``, or tiled) and, for a tiled patch smaller than the footprint, its fitness as a tile
    (``surface.tiling``)."""
    footprint_mm = SimConfig.width_mm  # the skin footprint of every engine (the surrogate's patch too)
    for name, value in _named_inputs(inputs):
        hm = heightmap_argument(value, pixel_mm, "inputs", units_ok, name)
        hm.require_footprint(footprint_mm, options.centre_mm, options.tile)
        if options.tile:
            check_tile(hm, name, footprint_mm)
        yield name, hm


def _named_inputs(inputs: Inputs) -> Iterator[tuple[str, object]]:
    """(name, value) of each input, lazily: a mapping's keys, a pair's name, else ``heightmap i``.

    A Heightmap, an array or a nested list of numbers is one input (a 3-D array is refused later, not split).
    """
    if isinstance(inputs, (Heightmap, np.ndarray)) or _numbers(inputs):
        inputs = [inputs]
    elif isinstance(inputs, Mapping):
        inputs = inputs.items()
    elif isinstance(inputs, (str, bytes)) or not isinstance(inputs, Iterable):
        raise InputError(f"inputs must be a Heightmap, a 2-D array of heights (mm), a mapping of names to them or "
                         f"an iterable of them, got {type(inputs).__name__}", parameter="inputs")
    for i, item in enumerate(inputs):
        named = isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], str)
        yield item if named else (f"heightmap {i}", item)


def _numbers(value: object) -> bool:
    """True for a list or tuple of numbers or of lists or tuples of them: one map's heights (or a malformed one)."""
    if not isinstance(value, (list, tuple)) or not value:
        return False
    first = value[0]
    if isinstance(first, (list, tuple)):
        first = first[0] if first else None
    return isinstance(first, numbers.Number)


@dataclass
class _Dispatch:
    """The engines ``predict`` answers with, for one call: the surrogate, and the physics ``auto`` climbs to."""

    engine: str
    model: SurrogateModel
    options: PredictOptions
    max_std: float | None
    fem: FemEngine
    spectral: SpectralEngine | None  # auto's spectral rung (flat bases, no FEM fidelity asked for)
    off_base: list[str]  # why the flat-trained surrogate may not answer on this curved base (empty: it may)

    @classmethod
    def make(cls, engine: str, model: SurrogateModel | str | Path | None, options: PredictOptions) -> _Dispatch:
        model = _domain_model(model)
        simulation = _fem_simulation(model, options)
        fem = FemEngine.of(options.fidelity or model.fidelity, simulation, options.centre_mm, options.tile)
        off_base = [CurvatureRange.load().outside(options.curved.radius_mm, options.curved.shape)] \
            if options.curved else []
        # auto climbs surrogate -> spectral -> FEM: the spectral engine answers for a flat base where its measured
        # error allows (``SPECTRAL_MIN_CONTACT``), unless a FEM fidelity was asked for
        spectral = SpectralEngine.of(simulation, options.centre_mm, options.tile) \
            if engine == "auto" and not options.curved and options.fidelity is None else None
        return cls(engine, model, options, uncertainty_limit(model, options.max_std), fem, spectral,
                   [why for why in off_base if why])

    def answer(self, batch: list[tuple[str, Heightmap]], on_result: Callable[[Prediction], None] | None
               ) -> list[Prediction]:
        """Predictions of one batch: the surrogate's estimate of all, then each kept or climbed."""
        model, options = self.model, self.options
        start = time.perf_counter()
        estimate = model.evaluate(np.stack([model.patch(hm, options.centre_mm, options.tile) for _, hm in batch]))
        share = (time.perf_counter() - start) / len(batch)
        spread = [None] * len(batch) if estimate.roughness_std is None else estimate.roughness_std.tolist()
        relative = [None] * len(batch) if estimate.relative_std is None else estimate.relative_std.tolist()
        results = []
        for (source, hm), v, why, std, rel in zip(batch, estimate.roughness, estimate.reasons, spread, relative):
            why = list(why) + self.off_base
            notes = list(why)
            if self.max_std is not None and rel > self.max_std:
                notes.append(f"uncertain: relative spread {rel:.3g} above the limit {self.max_std:.3g}")
            result = self._climbed(source, hm, not why, notes) if self.engine == "fem" or notes and \
                self.engine == "auto" else self._surrogate(source, float(v), not why, notes, std, share)
            results.append(result)
            if on_result:
                on_result(result)
        return results

    def _climbed(self, source: str, hm: Heightmap, in_domain: bool, notes: list[str]) -> Prediction:
        """The physics answer: auto's spectral rung where it holds, else the FEM."""
        from roughness.perceptual_scale import load_scale

        climbed = _spectral_rung(self.spectral, hm, notes) if self.engine == "auto" and self.spectral else None
        if climbed is not None:
            return _spectral_prediction(source, climbed, in_domain, notes, self.spectral.identity, self.model)
        r = self.fem.simulate(hm)
        error = r.discretization_error
        if error is not None and not math.isfinite(error):  # relative to V = 0: undefined, not Infinity
            error = None
            notes.append("discretization error undefined: V is 0 at this mesh but not at the coarser one")
        # converged FEM answers are placed on the most accurate tabulated scale, ``fine``'s
        scale = load_scale("fine" if self.fem.fidelity == "converged" else self.fem.fidelity)
        return Prediction(source, r.roughness, "fem", self.fem.fidelity, in_domain, r.seconds,
                          scale.place(r.roughness), notes, r.roughness_stderr, discretization_error=error,
                          provenance=make_provenance("fem", self.fem.fidelity, self.fem.identity, self.model))

    def _surrogate(self, source: str, v: float, in_domain: bool, notes: list[str], std: float | None,
                   seconds: float) -> Prediction:
        """The surrogate's answer; on a curved base corrected by the curvature study's measurement."""
        from roughness.perceptual_scale import load_scale

        curvature_error = None
        if self.options.curved:
            v, curvature_error = _curvature_corrected(v, self.options.curved, notes)
        return Prediction(source, v, "surrogate", self.model.fidelity, in_domain, seconds,
                          load_scale(self.model.fidelity).place(v), notes, roughness_std=std,
                          provenance=model_provenance(self.model), curvature_error=curvature_error)


def _curvature_corrected(roughness: float, curved: CurvedBase, notes: list[str]) -> tuple[float, float | None]:
    """A flat engine's V on a cylinder or sphere of signed radius (mm): times the curvature study's measured
    correction (``roughness.curvature_correction``), with its error (V); a note says which (or why none)."""
    from roughness.curvature_correction import for_base

    if curved.texture_along != "normal":
        notes.append("curved base: no correction was measured for heights along z; the flat V is given")
        return roughness, None
    try:
        fix = for_base(curved.radius_mm, curved.shape)
    except InputError as err:
        notes.append(f"curved base: {err}; the flat V is given")
        return roughness, None
    notes.append(fix.note)
    return roughness * fix.factor, abs(roughness) * fix.error


def _spectral_rung(spectral: SpectralEngine, hm: Heightmap, notes: list[str]) -> SpectralResult | None:
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


def _spectral_prediction(source: str, result: SpectralResult, in_domain: bool, notes: list[str], identity: str,
                         model: SurrogateModel | None = None) -> Prediction:
    """A ``SpectralResult`` as a prediction, placed on the spectral standard scale; ``notes`` come before its own.

    ``identity`` is the engine's configuration digest; ``model`` the surrogate consulted first (``auto``), if any."""
    from roughness.perceptual_scale import load_scale

    return Prediction(source, result.roughness, "spectral", "spectral", in_domain, result.seconds,
                      load_scale("spectral").place(result.roughness), notes + result.notes, result.roughness_stderr,
                      provenance=make_provenance("spectral", "spectral", identity, model))


def _fem_simulation(model: SurrogateModel, options: PredictOptions) -> dict:
    """The FEM's ``SimConfig`` fields for this call: the model's, with the options' tolerance and curved base,
    checked together before any engine is made (a base the configuration refuses is an InputError naming
    ``curved``)."""
    curved = options.curved.simulation() if options.curved else {}
    tolerance = {} if options.tolerance is None else {"tolerance": options.tolerance}
    simulation = {**model.meta.simulation, **tolerance, **curved}
    try:
        SimConfig(**simulation)
    except InputError as err:
        if err.parameter in CURVED_FIELDS:  # SimConfig's name for a field of options.curved
            raise InputError(str(err), parameter="curved") from None
        raise
    return simulation


def _spectral_engine(options: PredictOptions) -> SpectralEngine:
    """The spectral engine with the paper's parameters; InputError for an option it has no use for."""
    for name in ("fidelity", "tolerance", "max_std"):
        if getattr(options, name) is not None:
            raise InputError(f"the spectral engine has no {'ensemble' if name == 'max_std' else 'mesh'}: this option "
                             f"is the {'surrogate' if name == 'max_std' else 'FEM'}'s", parameter=name)
    if options.curved is not None:
        raise InputError("the spectral engine models a flat skin layer; curved bases need engine='fem'",
                         parameter="curved")
    return SpectralEngine.of(centre_mm=options.centre_mm, tile=options.tile)


def _predict_spectral(named: Iterable[tuple[str, Heightmap]], spectral: SpectralEngine, model: SurrogateModel,
                      options: PredictOptions, on_result: Callable[[Prediction], None] | None) -> list[Prediction]:
    """``predict`` with the spectral engine. ``in_domain`` is the surrogate's domain, as where ``auto`` climbs to this
    engine, so one answer gets one verdict whichever way it was asked for (the surrogate's domain check only: a few
    milliseconds per input; it used to be True unchecked, "in domain" where auto said the opposite)."""
    results = []
    for source, hm in named:
        why = model.evaluate(np.stack([model.patch(hm, options.centre_mm, options.tile)])).reasons[0]
        result = _spectral_prediction(source, spectral.simulate(hm), not why, list(why), spectral.identity)
        results.append(result)
        if on_result:
            on_result(result)
    return results


def _domain_model(model: SurrogateModel | str | Path | None) -> SurrogateModel:
    """The surrogate that answers (and whose domain the spectral engine's answers are judged by): ``model``, else
    the shipped one (loaded once per process and file)."""
    from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel

    if isinstance(model, SurrogateModel):
        return model
    if not isinstance(model, str | Path | None):
        return SurrogateModel(model)  # refuses the type with an InputError naming it
    path = Path(model or DEFAULT_MODEL)
    stat = path.stat() if path.is_file() else None
    return _loaded_model(str(path), None if stat is None else (stat.st_mtime_ns, stat.st_size))


@lru_cache(maxsize=4)
def _loaded_model(path: str, version: tuple[int, int] | None) -> SurrogateModel:
    """The surrogate at ``path``; ``version`` (its modification time and size) keys the cache, so a changed file is
    loaded again."""
    from roughness.surrogate.predictor import SurrogateModel

    return SurrogateModel(path)


def uncertainty_limit(model: SurrogateModel, max_std: float | None) -> float | None:
    """The relative spread above which ``auto`` runs the FEM: ``max_std``, else the ensemble's measured default.

    InputError if ``max_std`` is given for a model without an uncertainty (a single network).
    """
    if max_std is None:
        return (model.meta.ensemble or {}).get("max_std") if model.has_std else None
    positive("max_std", max_std)
    if not model.has_std:
        raise InputError(f"{model.path.name} is a single network without an uncertainty; max_std needs an "
                         "ensemble model (surrogate/ensemble.py)", parameter="max_std")
    return float(max_std)

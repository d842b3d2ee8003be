"""Scale a texture so that it reaches a target roughness: the surrogate searches, the FEM verifies.

The knob is the heights (``by="height"``: H - min(H) times the factor) or the lateral size
(``by="lateral"``: the texture stretched about the map centre by the factor, read periodically, on
the same pixels and map size). The target is an equivalent wavelength on the standard scale, a V,
the FEM's V of a reference texture, or a number of JNDs from the texture itself (its FEM V's equivalent
wavelength times 1.19 per JND); errors are counted in JNDs of the equivalent wavelength.

Search: the surrogate's V on a grid of factors gives the reachable range and the factor that meets
the target. Where the surrogate cannot reach the target (outside its training domain its V may even
fall as the relief grows), the spectral engine searches instead: its equivalent wavelength, on its
own scale, put on the verifier's; a target that it reaches only outside the factor range is refused
with the factor that would reach it (the spectral engine looks up to ``WIDEN`` times beyond the range).
The FEM then verifies the factor. While the FEM answer misses the target by more than
``tolerance_jnd``, the factor is corrected: the first time by the search engine's bias at that factor
(V_fem / V_search, assumed to vary slowly with the factor),
then by the secant through the two FEM answers closest to the target in log V over log factor. The
result is the FEM-verified factor closest to the target.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import NoReturn

import numpy as np

from roughness.core.checks import flag, in_range, integer, positive
from roughness.core.errors import InputError
from roughness.core.limits import MAX_HEIGHT_MM, MAX_JND
from roughness.core.reprs import short_repr, v_text
from roughness.perceptual_scale import LOG_JND, WEBER_FRACTION, jnd
from roughness.surface.heightmap import Heightmap

from .evaluation import Evaluator, Verified

KNOBS = ("height", "lateral")
FACTOR_RANGE = {"height": (0.1, 3.0), "lateral": (0.4, 2.5)}  # default search range of the scale factor
GRID = 49  # surrogate evaluations over the factor range
TOLERANCE_JND = 0.1
MAX_FEM = 4
WIDEN = 3.0  # out of the surrogate's reach: the spectral engine also looks this much beyond each end of the range
SPECTRAL_GRID = 17  # spectral evaluations over that wider range (0.03 to 1 s each: tall reliefs take longest)
MAX_RELATIVE_JND = MAX_JND  # a relative target: at most this many JNDs from the input (a factor 184 in lambda)


@dataclass(frozen=True)
class Target:
    """What to reach: V (dimensionless) and its equivalent wavelength (mm) on the standard scale."""

    roughness: float
    lambda_mm: float
    given_as: str  # "lambda", "roughness", "like <source>" or "jnd"
    reference: Verified | None = None  # the verifier's answer on the reference (--like) or on the input (jnd)
    jnd: float | None = None  # a relative target: JNDs from the input (positive: rougher)

    @property
    def parameter(self) -> str:
        """The option the target came from (the CLI names it in errors about the target)."""
        return {"lambda": "target_lambda_mm", "roughness": "target_v", "jnd": "jnd"}.get(self.given_as, "like")

    def describe(self) -> str:
        """The target in words: ``V 0.0612, lambda 0.912 mm (+1 JND from the input: V 0.0501, lambda 0.800 mm)``."""
        text = f"V {self.roughness:.4f}, lambda {self.lambda_mm:.3f} mm"
        if self.jnd is not None:
            r = self.reference
            return (f"{text} ({self.jnd:+g} JND from the input: V {r.roughness:.4f} ± {r.roughness_stderr:.4f}, "
                    f"lambda {r.equivalent_lambda_mm:.3f} mm)")
        return f"{text} ({self.given_as})"


@dataclass(frozen=True)
class Step:
    """One FEM verification: the factor, the surrogate's V there, the FEM's answer, the signed JND error."""

    factor: float
    surrogate_roughness: float
    search_roughness: float  # the search engine's V (the surrogate's, or the spectral engine's on the verifier's scale)
    fem: Verified
    jnd_error: float  # FEM's equivalent lambda against the target's: positive = rougher than the target


@dataclass(frozen=True)
class TuneResult:
    heightmap: Heightmap  # the scaled texture (mm)
    by: str
    factor: float
    target: Target
    achieved: Verified  # FEM
    surrogate_roughness: float
    in_domain: bool  # the surrogate's domain at this factor
    jnd_error: float
    jnd_stderr: float  # of jnd_error, from the FEM's Monte Carlo standard error
    steps: tuple[Step, ...]
    reachable_roughness: tuple[float, float]  # surrogate V over the factor range
    factor_range: tuple[float, float]
    tolerance_jnd: float
    search_engine: str  # "surrogate", or "spectral" where the surrogate cannot reach the target
    notes: tuple[str, ...] = field(default=())

    def __repr__(self) -> str:
        a = self.achieved
        return short_repr(self, f"{self.by} x {self.factor:.4g}", f"target {self.target.describe()}",
                          f"achieved {v_text(a.roughness, a.roughness_stderr)}, lambda {a.equivalent_lambda_mm:.3f} mm",
                          f"{self.jnd_error:+.2f} ± {self.jnd_stderr:.2f} JND", "reached" if self.reached else
                          "NOT reached", f"{len(self.steps)} verification(s)", repr(self.heightmap))

    @property
    def reached(self) -> bool:
        return abs(self.jnd_error) <= self.tolerance_jnd

    def summary(self) -> dict:
        reference = self.target.reference
        relative = {} if self.target.jnd is None else {
            "target_jnd": self.target.jnd, "input_roughness": reference.roughness,
            "input_roughness_stderr": reference.roughness_stderr, "input_lambda_mm": reference.equivalent_lambda_mm}
        return {"by": self.by, "factor": self.factor, "target_roughness": self.target.roughness,
                "target_lambda_mm": self.target.lambda_mm, "target_given_as": self.target.given_as, **relative,
                "achieved_roughness": self.achieved.roughness, "achieved_roughness_stderr": self.achieved.roughness_stderr,
                "achieved_lambda_mm": self.achieved.equivalent_lambda_mm, "achieved_on_scale": self.achieved.on_scale,
                "surrogate_roughness": self.surrogate_roughness, "surrogate_in_domain": self.in_domain,
                "jnd_error": self.jnd_error, "jnd_stderr": self.jnd_stderr, "tolerance_jnd": self.tolerance_jnd,
                "reached": self.reached, "fem_runs": len(self.steps), "search_engine": self.search_engine,
                "steps": [{"factor": s.factor, "surrogate_roughness": s.surrogate_roughness,
                           "search_roughness": s.search_roughness,
                           "fem_roughness": s.fem.roughness, "jnd_error": s.jnd_error} for s in self.steps],
                "reachable_roughness": list(self.reachable_roughness), "factor_range": list(self.factor_range),
                "notes": list(self.notes)}


def scaled(heightmap: Heightmap, by: str, factor: float) -> Heightmap:
    """The texture with its heights (above their minimum) or its lateral size multiplied by ``factor``."""
    factor = positive("factor", factor)
    if by == "height":
        h = heightmap.heights
        return Heightmap(h.min() + (h - h.min()) * factor, heightmap.pixel_mm)
    if by == "lateral":
        ny, nx = heightmap.shape
        cx, cy = heightmap.centre_mm
        x = cx + ((np.arange(nx) + 0.5) * heightmap.pixel_mm - cx) / factor
        y = cy + ((np.arange(ny) + 0.5) * heightmap.pixel_mm - cy) / factor
        return Heightmap(heightmap.sample(x[None, :], y[:, None], periodic=True), heightmap.pixel_mm)
    raise InputError(f"unknown knob {by!r}; choose one of {', '.join(KNOBS)}", parameter="by")


def target_of(evaluator: Evaluator, lambda_mm: float | None = None, roughness: float | None = None,
              like: Heightmap | None = None, like_name: str = "reference", tile: bool = False,
              jnd: float | None = None, heightmap: Heightmap | None = None) -> Target:
    """The target from exactly one of an equivalent wavelength (mm), a V, a reference texture (its FEM V), or
    ``jnd`` JNDs from ``heightmap`` (the texture to tune: its FEM V's equivalent wavelength times 1.19^jnd)."""
    given = [name for name, v in (("target_lambda_mm", lambda_mm), ("target_v", roughness), ("like", like),
                                  ("jnd", jnd)) if v is not None]
    if len(given) != 1:
        raise InputError("give exactly one target: an equivalent wavelength, a V, a reference texture, or JNDs "
                         "from the input" + (f" (got {', '.join(given)})" if given else ""),
                         parameter=given[-1] if given else None)
    if jnd is not None:
        steps = in_range("jnd", jnd, -MAX_RELATIVE_JND, MAX_RELATIVE_JND)
        if heightmap is None:
            raise InputError("a relative target (jnd) needs the texture it is relative to", parameter="jnd")
        fem = _on_scale(evaluator, evaluator.verify(heightmap, tile=tile), "the input",
                        "it has no equivalent wavelength to count JNDs from", "jnd")
        lam = fem.equivalent_lambda_mm * (1 + WEBER_FRACTION) ** steps
        return Target(evaluator.scale.roughness_at(lam), lam, "jnd", fem, steps)
    if lambda_mm is not None:
        lam = positive("target_lambda_mm", lambda_mm)
        v = evaluator.scale.roughness_at(lam)
        if not 0 < v < math.inf:
            raise InputError(f"target lambda {lam:g} mm is beyond where the standard scale's power law gives a V "
                             f"(it spans {evaluator.scale.lambdas_mm[0]:g}..{evaluator.scale.lambdas_mm[-1]:g} mm)",
                             parameter="target_lambda_mm")
        return Target(v, lam, "lambda")
    if roughness is not None:
        v = positive("target_v", roughness)
        return Target(v, evaluator.lambda_of(v), "roughness")
    fem = _on_scale(evaluator, evaluator.verify(like, tile=tile), f"the reference {like_name}",
                    "a texture cannot be tuned to feel like no texture at all", "like")
    return Target(fem.roughness, fem.equivalent_lambda_mm, f"like {like_name}", fem)


def _on_scale(evaluator: Evaluator, fem, what: str, why: str, parameter: str):
    """``fem`` (a verified answer) if its V is on the standard scale (at or above its floor); else InputError:
    a flat or near-flat texture gives no target (its V is 0 or below what the scale can place)."""
    if not fem.roughness >= evaluator.scale.floor:
        raise InputError(f"{what}'s V {fem.roughness:.4g} ({evaluator.verifier}) is below the standard scale's floor "
                         f"{evaluator.scale.floor:.4g} (flat or nearly): {why}; give an absolute target "
                         "(--target-lambda or --target-v)", parameter=parameter)
    return fem


@dataclass(frozen=True)
class _Problem:
    """What tune scales: ``heightmap`` by knob ``by`` within factors ``lo``..``hi``, judged by ``evaluator``."""

    heightmap: Heightmap
    by: str
    evaluator: Evaluator
    tile: bool
    lo: float
    hi: float

    def scaled(self, factor: float) -> Heightmap:
        """The texture scaled by ``factor``."""
        return scaled(self.heightmap, self.by, factor)

    def surrogate(self, factors) -> tuple[np.ndarray, np.ndarray]:
        """The surrogate's V and in-domain flags of the texture scaled by each of ``factors``."""
        return self.evaluator.surrogate([self.scaled(f) for f in factors], tile=self.tile)


@dataclass
class _Search:
    """The engine that searches for the factor: its V (``values``) on a rising ``grid`` of factors over the range,
    ``evaluate(factors)`` for more, and the surrogate's V over the range (``reachable``)."""

    engine: str  # "surrogate" or "spectral"
    grid: np.ndarray
    values: np.ndarray
    evaluate: Callable[[Sequence[float]], np.ndarray]
    reachable: tuple[float, float]
    notes: list[str] = field(default_factory=list)


def tune(heightmap: Heightmap, target: Target, by: str = "height", evaluator: Evaluator | None = None,
         factor_range: tuple[float, float] | None = None, tolerance_jnd: float = TOLERANCE_JND,
         max_fem: int = MAX_FEM, tile: bool = False, progress=None) -> TuneResult:
    """Scale ``heightmap`` (by height or lateral size) to reach ``target`` (module docstring).

    ``progress(message)`` receives a line per FEM verification.
    """
    lo, hi = _factor_range(by, factor_range)
    _check_reach(heightmap, by, hi)
    tolerance_jnd = positive("tolerance_jnd", tolerance_jnd)
    max_fem, tile = integer("max_fem", max_fem, minimum=1), flag("tile", tile)
    evaluator = evaluator or Evaluator()
    if not tile:
        heightmap.require_footprint(evaluator.footprint_mm)
    problem = _Problem(heightmap, by, evaluator, tile, lo, hi)
    search = _search(problem, target)
    steps, stuck = _verify(problem, search, target, tolerance_jnd, max_fem, progress)
    return _result(problem, search, target, steps, tolerance_jnd, search.notes + stuck)


def _factor_range(by: str, factor_range: tuple[float, float] | None) -> tuple[float, float]:
    """The rising factor range for knob ``by`` (default ``FACTOR_RANGE[by]``), checked."""
    if by not in KNOBS:
        raise InputError(f"unknown knob {by!r}; choose one of {', '.join(KNOBS)}", parameter="by")
    lo, hi = factor_range or FACTOR_RANGE[by]
    lo, hi = positive("min_factor", lo), positive("max_factor", hi)
    if not lo < hi:
        raise InputError(f"the factor range must rise, got {lo:g}..{hi:g}", parameter="min_factor")
    return lo, hi


def _check_reach(heightmap: Heightmap, by: str, hi: float) -> None:
    """InputError (parameter ``max_factor``) if the height factor ``hi`` makes heights a heightmap cannot hold."""
    if by != "height":
        return
    h = heightmap.heights
    top = float(h.min()) + float(np.ptp(h)) * hi
    if max(abs(float(h.min())), abs(top)) > MAX_HEIGHT_MM:
        raise InputError(f"the largest height factor {hi:g} (max_factor) would raise the texture's {np.ptp(h):.3g} mm "
                         f"relief to {top:.4g} mm, beyond the {MAX_HEIGHT_MM:g} mm a heightmap may hold "
                         "(MAX_HEIGHT_MM): search a smaller range", parameter="max_factor")


def _search(problem: _Problem, target: Target) -> _Search:
    """The surrogate over the factor range, or the spectral engine where the surrogate cannot reach the target."""
    grid = np.geomspace(problem.lo, problem.hi, GRID)
    values, _ = problem.surrogate(grid)
    reachable = (float(values.min()), float(values.max()))
    if reachable[0] <= target.roughness <= reachable[1]:
        search = _Search("surrogate", grid, values, lambda factors: problem.surrogate(factors)[0], reachable)
    else:
        search = _spectral_fallback(problem, target, reachable)
    if np.any(np.diff(search.values) <= 0):
        searcher = "surrogate" if search.engine == "surrogate" else "spectral engine"
        search.notes.append(f"the {searcher}'s V does not rise monotonically with the {problem.by} factor; the first "
                            "crossing is used")
    return search


def _spectral_fallback(problem: _Problem, target: Target, reachable: tuple[float, float]) -> _Search:
    """The spectral engine's search over the factor range; InputError if it cannot reach the target there either."""
    lo, hi = problem.lo, problem.hi
    spectral = _spectral_search(problem.heightmap, problem.by, problem.evaluator, problem.tile)
    wide = np.geomspace(lo / WIDEN, hi * WIDEN, SPECTRAL_GRID)
    wide = np.concatenate([wide[wide < lo], [lo], wide[(wide > lo) & (wide < hi)], [hi], wide[wide > hi]])
    inside = (wide >= lo) & (wide <= hi)
    v_wide = np.full(len(wide), np.nan)
    v_wide[inside] = spectral(wide[inside])
    if not v_wide[inside].min() <= target.roughness <= v_wide[inside].max():
        _refuse(problem, target, reachable, spectral, wide, v_wide)
    lam_lo, lam_hi = problem.evaluator.lambda_of(reachable[0]), problem.evaluator.lambda_of(reachable[1])
    note = (f"the surrogate reaches only lambda {lam_lo:.3f}..{lam_hi:.3f} mm by {problem.by} factors {lo:g}..{hi:g} "
            "(outside its training domain it is not to be trusted): the spectral engine searched instead")
    return _Search("spectral", wide[inside], v_wide[inside], spectral, reachable, [note])


def _refuse(problem: _Problem, target: Target, reachable: tuple[float, float], spectral, wide: np.ndarray,
            v_wide: np.ndarray) -> NoReturn:
    """InputError for a target out of reach in the factor range (``v_wide``: the spectral V on ``wide``, NaN
    outside the range): looks outwards, one factor at a time, for one that reaches it, to name in the message."""
    inside = (wide >= problem.lo) & (wide <= problem.hi)
    above = target.roughness > v_wide[inside].max()
    outward = np.nonzero(wide > problem.hi)[0] if above else np.nonzero(wide < problem.lo)[0][::-1]
    for i in outward:  # one factor at a time, outwards from the range, until one reaches the target
        v_wide[i] = spectral(wide[i:i + 1])[0]
        if (v_wide[i] >= target.roughness) == above:
            break
    seen = ~np.isnan(v_wide)
    raise InputError(_out_of_reach(problem, target, reachable, wide[seen], v_wide[seen]), parameter=target.parameter)


def _factor_for(problem: _Problem, search: _Search, v_wanted: float, bias: float) -> float:
    """The factor where bias * search V = v_wanted: grid crossing, then bisection on the surrogate (the spectral
    engine: interpolation between the grid's points, 1.4x apart; the verifier's answers correct the rest)."""
    values = search.values * bias
    above = np.nonzero(values >= v_wanted)[0]
    if len(above) == 0:
        return problem.hi
    k = int(above[0])
    if k == 0:
        return problem.lo
    a, b = math.log(search.grid[k - 1]), math.log(search.grid[k])
    if search.engine == "spectral":  # each evaluation up to a second: log V interpolated over log factor instead
        va, vb = math.log(values[k - 1]), math.log(values[k])
        return math.exp(a + (b - a) * (math.log(v_wanted) - va) / (vb - va)) if vb > va else math.exp(b)
    for _ in range(12):  # bisection in log factor: 2^-12 of one grid step
        mid = (a + b) / 2
        if search.evaluate([math.exp(mid)])[0] * bias >= v_wanted:
            b = mid
        else:
            a = mid
    return math.exp((a + b) / 2)


def _verify(problem: _Problem, search: _Search, target: Target, tolerance_jnd: float, max_fem: int,
            progress) -> tuple[list[Step], list[str]]:
    """FEM verifications from the search's factor, corrected (``_next_factor``) until within ``tolerance_jnd`` or
    ``max_fem`` runs; and a note if the factor can move no closer."""
    steps: list[Step] = []
    factor = _factor_for(problem, search, target.roughness, 1.0)
    for _ in range(max_fem):
        steps.append(_step(problem, search, target, factor))
        if progress:
            progress(_step_line(problem, search, steps[-1]))
        if abs(steps[-1].jnd_error) <= tolerance_jnd:
            break
        factor = _next_factor(problem, search, steps, target)
        if any(math.isclose(factor, s.factor, rel_tol=1e-6) for s in steps):
            return steps, [f"the {problem.by} factor cannot move closer to the target within "
                           f"{problem.lo:g}..{problem.hi:g}"]
    return steps, []


def _step(problem: _Problem, search: _Search, target: Target, factor: float) -> Step:
    """One FEM verification at ``factor``, with the surrogate's and the search engine's V there."""
    v_sur = float(problem.surrogate([factor])[0][0])
    v_search = v_sur if search.engine == "surrogate" else float(search.evaluate([factor])[0])
    fem = problem.evaluator.verify(problem.scaled(factor), tile=problem.tile)
    return Step(factor, v_sur, v_search, fem, jnd(fem.equivalent_lambda_mm, target.lambda_mm))


def _step_line(problem: _Problem, search: _Search, step: Step) -> str:
    """The progress line of one FEM verification."""
    return (f"{problem.evaluator.verifier} at {problem.by} factor {step.factor:.4f}: V {step.fem.roughness:.4f} "
            f"(surrogate {step.surrogate_roughness:.4f}"
            + (f", spectral {step.search_roughness:.4f}" if search.engine == "spectral" else "")
            + f"), {step.jnd_error:+.2f} JND from the target")


def _result(problem: _Problem, search: _Search, target: Target, steps: list[Step], tolerance_jnd: float,
            notes: list[str]) -> TuneResult:
    """The result at the FEM-verified factor closest to the target, with notes on how far to trust it."""
    best = min(steps, key=lambda s: abs(s.jnd_error))
    se = best.fem.roughness_stderr / best.fem.roughness / problem.evaluator.scale.power_law[1] / LOG_JND
    if not best.fem.on_scale:
        notes.append("the achieved V lies off the standard scale: its equivalent lambda is extrapolated")
    in_domain = bool(problem.surrogate([best.factor])[1][0])
    if not in_domain:
        notes.append("the scaled texture lies outside the surrogate's training domain "
                     f"(verified by {problem.evaluator.verifier})")
    return TuneResult(problem.scaled(best.factor), problem.by, best.factor, target, best.fem,
                      best.surrogate_roughness, in_domain, best.jnd_error, se, tuple(steps), search.reachable,
                      (problem.lo, problem.hi), tolerance_jnd, search.engine, tuple(notes))


def _next_factor(problem: _Problem, search: _Search, steps: list[Step], target: Target) -> float:
    """A corrected factor: the search engine's bias at the last step, or the secant through the two closest FEM
    answers."""
    def biased(step: Step) -> float:
        return _factor_for(problem, search, target.roughness, step.fem.roughness / step.search_roughness)

    if len(steps) == 1:
        return biased(steps[0])
    a, b = sorted(steps, key=lambda s: abs(s.jnd_error))[:2]
    if math.isclose(a.factor, b.factor) or math.isclose(a.fem.roughness, b.fem.roughness):
        return biased(a)
    slope = (math.log(a.fem.roughness) - math.log(b.fem.roughness)) / (math.log(a.factor) - math.log(b.factor))
    if slope <= 0:  # not rising here: fall back on the search engine's bias at the best step
        return biased(a)
    step = (math.log(target.roughness) - math.log(a.fem.roughness)) / slope
    return float(np.clip(a.factor * math.exp(np.clip(step, -0.5, 0.5)), problem.lo, problem.hi))


def _spectral_search(heightmap: Heightmap, by: str, evaluator: Evaluator, tile: bool):
    """V of the scaled texture by the spectral engine, as V on the verifier's scale (same equivalent wavelength)."""
    spectral = evaluator if evaluator.fidelity == "spectral" else Evaluator(evaluator.model_path, "spectral")

    def search(factors) -> np.ndarray:
        lams = [spectral.verify(scaled(heightmap, by, float(f)), tile=tile).equivalent_lambda_mm for f in factors]
        return np.array([evaluator.scale.roughness_at(lam) for lam in lams])

    return search


def _out_of_reach(problem: _Problem, target: Target, reachable: tuple[float, float], wide: np.ndarray,
                  v_wide: np.ndarray) -> str:
    """Why the target is refused, and the factor that would reach it on the spectral engine, if any."""
    by, evaluator, lo, hi = problem.by, problem.evaluator, problem.lo, problem.hi
    lams = [evaluator.lambda_of(v) for v in reachable]
    text = (f"target V {target.roughness:.4f} (equivalent lambda {target.lambda_mm:.3f} mm) is out of reach by {by} "
            f"factors {lo:g}..{hi:g}: this texture reaches V {reachable[0]:.4f}..{reachable[1]:.4f} (lambda "
            f"{lams[0]:.3f}..{lams[1]:.3f} mm) on the surrogate")
    side = np.sign(np.log(np.maximum(v_wide, 1e-300)) - math.log(target.roughness))
    crossings = np.nonzero(side[1:] != side[:-1])[0]
    if len(crossings) == 0:
        wide_lams = [evaluator.lambda_of(v) for v in (v_wide.min(), v_wide.max())]
        return (f"{text}, and no {by} factor in {wide[0]:.3g}..{wide[-1]:.3g} reaches it on the spectral engine "
                f"(lambda {wide_lams[0]:.3f}..{wide_lams[1]:.3f} mm)")
    k = int(crossings[0]) + 1  # interpolate the first crossing in log V over log factor
    t = (math.log(target.roughness) - math.log(v_wide[k - 1])) / (math.log(v_wide[k]) - math.log(v_wide[k - 1]))
    factor = math.exp(math.log(wide[k - 1]) + t * (math.log(wide[k]) - math.log(wide[k - 1])))
    flag = f"max_factor={_two_digits(factor * 1.1, True)}" if factor > hi else \
        f"min_factor={_two_digits(factor / 1.1, False)}"
    return (f"{text}; the spectral engine reaches it at a {by} factor of about {factor:.2f}: widen the range "
            f"({flag}) to search there, the verifier checks the result")


def _two_digits(x: float, up: bool) -> str:
    """``x`` rounded up or down to two significant digits: a bound that still includes ``x``."""
    unit = 10.0 ** (math.floor(math.log10(x)) - 1)
    return f"{(math.ceil(x / unit) if up else math.floor(x / unit)) * unit:.2g}"

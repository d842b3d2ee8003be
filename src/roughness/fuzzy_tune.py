"""Fuzzy skin settings that reach a target feel: one knob (thickness or point distance) searched and verified by
the spectral engine, the other settings fixed.

``design.tune`` scales one heightmap and verifies it with one run; a fuzzy-skin setting makes a new wall, and one
wall is one draw of the slicer's random numbers. So here every evaluation is ``fuzzy_skin_feel`` on ``draws`` walls
(seeds ``seed``, ``seed`` + 1, ...: the same seeds at every knob value, so that differences between settings are
not the draws' spread), and V is their mean. The target is ``design.tune``'s ``Target`` (an equivalent wavelength on
the spectral standard scale, or JNDs from given settings: their mean V's wavelength times 1.19 per JND); errors are
JNDs of the equivalent wavelength.

Search: the knob's range on a log grid (``GRID`` values); the first crossing of the target, interpolated in log V
over log knob, is verified; while the verified mean misses the target by more than ``tolerance_jnd``, the secant
through the two answers closest to the target (in log V over log knob) gives the next value, up to ``max_runs``
verifications. The result is the verified value closest to the target, with the standard error of its mean V
(the spread between walls over the square root of the draws, and the engine's error) in JND. Classic thickness
scales the offsets of the same points, so V rises smoothly with it; point distance moves the points and redraws the
noise, so V over it carries the spread between walls and is not monotonic (it peaks near 1 mm): the first
crossing from the small end is used.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from roughness.core.checks import in_range, integer, positive
from roughness.core.errors import InputError
from roughness.core.limits import MAX_JND
from roughness.design.evaluation import Verified
from roughness.design.tune import TOLERANCE_JND, Target
from roughness.fuzzy_feel import FuzzyFeel, fuzzy_skin_feel
from roughness.perceptual_scale import LOG_JND, WEBER_FRACTION, jnd, load_scale
from roughness.surface.fuzzy_skin import RANGES, FuzzySkin
from roughness.surface.printing import FdmProfile, printer_profile

ENGINE = "spectral"  # searches and verifies: tens of ms per wall, so several draws per setting
KNOBS = {"thickness": "fuzzy_skin_thickness", "point-distance": "fuzzy_skin_point_distance"}
KNOB_RANGE = {"thickness": (0.05, 1.0), "point-distance": (0.2, 1.0)}  # mm: default search ranges (V peaks near 1 mm)
GRID = 6  # knob values over the range for the search
DRAWS = 8  # walls per setting: the mean's standard error ~0.07 JND at the slicers' default (0.2 JND per wall)
MAX_RUNS = 4  # verifications after the grid
DIGITS = 3  # a tuned setting is rounded to 0.001 mm


@dataclass(frozen=True)
class Run:
    """One setting judged: the knob's value (mm), the feel over the draws, its signed JND error from the target."""

    value_mm: float
    feel: FuzzyFeel
    jnd_error: float


@dataclass(frozen=True)
class KnobScan:
    """The feel over a knob's range: the search grid, shared by a palette's members."""

    knob: str
    values_mm: tuple[float, ...]  # rising
    feels: tuple[FuzzyFeel, ...]  # one per value, all over the same seeds

    @property
    def reach_lambda_mm(self) -> tuple[float, float]:
        """The smallest and largest equivalent wavelength (mm) the grid reached."""
        lams = [equivalent_lambda(f) for f in self.feels]
        return min(lams), max(lams)


@dataclass(frozen=True)
class FuzzyTune:
    """The setting that reaches ``target`` (or comes closest), verified over the draws."""

    skin: FuzzySkin
    knob: str
    feel: FuzzyFeel
    target: Target
    jnd_error: float  # achieved against target (positive: rougher)
    jnd_stderr: float  # of jnd_error: the mean V's standard error over the draws and the engine's error
    draw_jnd: float | None  # the spread of one wall (one print) in JND
    runs: tuple[Run, ...]  # the verifications, in order
    reach_lambda_mm: tuple[float, float]
    knob_range_mm: tuple[float, float]
    tolerance_jnd: float
    notes: tuple[str, ...] = field(default=())

    @property
    def value_mm(self) -> float:
        return getattr(self.skin, KNOBS[self.knob])

    @property
    def reached(self) -> bool:
        return abs(self.jnd_error) <= self.tolerance_jnd

    def summary(self) -> dict:
        reference = self.target.reference
        relative = {} if self.target.jnd is None else {
            "target_jnd": self.target.jnd, "reference_roughness": reference.roughness,
            "reference_roughness_stderr": reference.roughness_stderr,
            "reference_lambda_mm": reference.equivalent_lambda_mm}
        return {"tune": self.knob, "value_mm": self.value_mm, "target_roughness": self.target.roughness,
                "target_lambda_mm": self.target.lambda_mm, "target_given_as": self.target.given_as, **relative,
                "achieved_lambda_mm": equivalent_lambda(self.feel), "jnd_error": self.jnd_error,
                "jnd_stderr": self.jnd_stderr, "draw_jnd": self.draw_jnd, "tolerance_jnd": self.tolerance_jnd,
                "reached": self.reached, "engine": ENGINE, "verifications": len(self.runs),
                "runs": [{"value_mm": r.value_mm, "roughness": r.feel.roughness, "jnd_error": r.jnd_error}
                         for r in self.runs],
                "reach_lambda_mm": list(self.reach_lambda_mm), "knob_range_mm": list(self.knob_range_mm),
                "notes": list(self.notes), "feel": self.feel.as_dict()}

    def describe(self) -> str:
        """The result in words: the setting, the target, what was achieved and how sure."""
        spread = "" if self.draw_jnd is None else f"; one print differs from the next by ±{self.draw_jnd:.2f} JND"
        return (f"{self.knob.replace('-', ' ')} {self.value_mm:.3f} mm: {self.skin.describe()}\n"
                f"target: {self.target.describe()}\n"
                f"achieved ({ENGINE}, mean of {len(self.feel.predictions)} walls): V {self.feel.roughness:.4f}, lambda "
                f"{equivalent_lambda(self.feel):.3f} mm; error {self.jnd_error:+.2f} ± {self.jnd_stderr:.2f} JND "
                f"({'within' if self.reached else 'NOT within'} {self.tolerance_jnd:g} JND after {len(self.runs)} "
                f"verification(s)){spread}")


def equivalent_lambda(feel: FuzzyFeel) -> float:
    """The equivalent wavelength (mm) of a feel's mean V on the spectral scale (extrapolated off its ends)."""
    return load_scale(ENGINE).equivalent_lambda(max(feel.roughness, 1e-12))[0]


def mean_stderr_jnd(feel: FuzzyFeel) -> float:
    """Standard error (JND) of the equivalent wavelength of a feel's mean V: the spread between walls over the root
    of their number, and the engine's error."""
    spread = (feel.draw_std or 0.0) / math.sqrt(len(feel.predictions))
    return math.hypot(spread, feel.engine_error or 0.0) / feel.roughness / load_scale(ENGINE).power_law[1] / LOG_JND


def draw_jnd(feel: FuzzyFeel) -> float | None:
    """The spread of V between walls (one standard deviation) in JND (None for one draw)."""
    if feel.draw_std is None:
        return None
    return feel.draw_std / feel.roughness / load_scale(ENGINE).power_law[1] / LOG_JND


def knob_range(knob: str, tune_range: tuple[float, float] | None = None) -> tuple[float, float]:
    """The rising search range (mm) of ``knob`` (default ``KNOB_RANGE``), within the setting's domain."""
    if knob not in KNOBS:
        raise InputError(f"unknown knob {knob!r}; choose one of {', '.join(KNOBS)}", parameter="tune")
    lo, hi = tune_range or KNOB_RANGE[knob]
    low, high = RANGES[KNOBS[knob]]
    lo, hi = (in_range("tune_range", positive("tune_range", v), low, high) for v in (lo, hi))
    if not lo < hi:
        raise InputError(f"the {knob} range must rise, got {lo:g}..{hi:g} mm", parameter="tune_range")
    return lo, hi


@dataclass(frozen=True)
class _Judge:
    """Feels of ``skin`` with ``knob`` set, on ``profile``, over ``draws`` walls from ``seed``."""

    skin: FuzzySkin
    knob: str
    profile: FdmProfile
    seed: int
    draws: int
    tile_mm: float
    pixel_mm: float
    radius_mm: float | None

    def __call__(self, value_mm: float) -> FuzzyFeel:
        """The feel at ``value_mm`` rounded to ``DIGITS`` decimals (a setting a slicer takes as typed)."""
        skin = replace(self.skin, **{KNOBS[self.knob]: round(float(value_mm), DIGITS)})
        return fuzzy_skin_feel(skin, self.profile, ENGINE, self.seed, self.draws, self.tile_mm, self.pixel_mm,
                               self.radius_mm)


def _judge(skin: FuzzySkin, knob: str, printer: FdmProfile | str, seed: int, draws: int, tile_mm: float,
           pixel_mm: float, radius_mm: float | None) -> _Judge:
    profile = printer_profile(printer) if isinstance(printer, str) else printer
    if knob not in KNOBS:
        raise InputError(f"unknown knob {knob!r}; choose one of {', '.join(KNOBS)}", parameter="tune")
    return _Judge(skin, knob, profile, integer("seed", seed, 0), integer("draws", draws, 2), tile_mm, pixel_mm,
                  radius_mm)


def scan(skin: FuzzySkin, knob: str = "thickness", printer: FdmProfile | str = "fdm-0.4-0.2",
         tune_range: tuple[float, float] | None = None, seed: int = 0, draws: int = DRAWS, tile_mm: float = 12.0,
         pixel_mm: float = 0.05, radius_mm: float | None = None,
         progress: Callable[[str], None] | None = None) -> KnobScan:
    """The spectral feel of ``skin`` at ``GRID`` values of ``knob`` over its range (log spaced, mm), on a cylinder
    of signed ``radius_mm`` if given (``fuzzy_skin_feel``)."""
    lo, hi = knob_range(knob, tune_range)
    judge = _judge(skin, knob, printer, seed, draws, tile_mm, pixel_mm, radius_mm)
    values, feels = [float(v) for v in np.geomspace(lo, hi, GRID)], []
    for value in values:
        feels.append(judge(value))
        if progress:
            progress(f"search: {knob} {value:.3f} mm: V {feels[-1].roughness:.4f} "
                     f"(lambda {equivalent_lambda(feels[-1]):.3f} mm)")
    return KnobScan(knob, tuple(values), tuple(feels))


def relative_target(feel: FuzzyFeel, steps_jnd: float) -> Target:
    """The target ``steps_jnd`` JNDs from ``feel`` (positive: rougher), on the spectral scale."""
    steps = in_range("target_jnd", steps_jnd, -MAX_JND, MAX_JND)
    lam = equivalent_lambda(feel)
    if feel.placement is None or feel.placement.below_scale:
        raise InputError(f"the given settings' V {feel.roughness:.4g} is below the spectral scale's floor: no "
                         "equivalent wavelength to count JNDs from; give --target-lambda", parameter="target_jnd")
    seconds = sum(p.seconds for p in feel.predictions)
    se = (feel.draw_std or 0.0) / math.sqrt(len(feel.predictions))
    reference = Verified(feel.roughness, math.hypot(se, feel.engine_error or 0.0), lam, feel.placement.on_scale,
                         seconds)
    target_lam = lam * (1 + WEBER_FRACTION) ** steps
    return Target(load_scale(ENGINE).roughness_at(target_lam), target_lam, "jnd", reference, steps)


def lambda_target(lambda_mm: float) -> Target:
    """The target equivalent wavelength (mm) on the spectral scale."""
    lam = positive("target_lambda_mm", lambda_mm)
    return Target(load_scale(ENGINE).roughness_at(lam), lam, "lambda")


def tune_fuzzy_skin(skin: FuzzySkin, target: Target, knob: str = "thickness",
                    printer: FdmProfile | str = "fdm-0.4-0.2", tune_range: tuple[float, float] | None = None,
                    tolerance_jnd: float = TOLERANCE_JND, max_runs: int = MAX_RUNS, seed: int = 0,
                    draws: int = DRAWS, tile_mm: float = 12.0, pixel_mm: float = 0.05, radius_mm: float | None = None,
                    grid: KnobScan | None = None, progress: Callable[[str], None] | None = None) -> FuzzyTune:
    """The value of ``knob`` (other settings of ``skin`` fixed) whose walls (on a cylinder of signed ``radius_mm``
    if given) reach ``target`` (module docstring); ``grid``: a ``scan`` of the same knob, range, draws and radius to
    search on (made here if not given)."""
    tolerance_jnd = positive("tolerance_jnd", tolerance_jnd)
    max_runs = integer("max_runs", max_runs, 1)
    lo, hi = knob_range(knob, tune_range)
    judge = _judge(skin, knob, printer, seed, draws, tile_mm, pixel_mm, radius_mm)
    grid = grid or scan(skin, knob, judge.profile, (lo, hi), seed, draws, tile_mm, pixel_mm, radius_mm, progress)
    if grid.knob != knob or [w.seed for w in grid.feels[0].walls] != list(range(seed, seed + draws)):
        raise InputError(f"the grid scans {grid.knob} over seeds {[w.seed for w in grid.feels[0].walls]}: make it for "
                         f"{knob} over seeds {seed}..{seed + draws - 1}", parameter="grid")
    values = np.array(grid.values_mm)
    v = np.array([f.roughness for f in grid.feels])
    reach = grid.reach_lambda_mm
    if not v.min() <= target.roughness <= v.max():
        raise InputError(f"target lambda {target.lambda_mm:.3f} mm (V {target.roughness:.4f}) is out of reach by "
                         f"{knob} {lo:g}..{hi:g} mm: these settings reach lambda {reach[0]:.3f}..{reach[1]:.3f} mm "
                         f"(V {v.min():.4f}..{v.max():.4f}, {ENGINE}); widen the range (tune_range) or tune the other "
                         "knob", parameter="tune_range")
    notes = [] if np.all(np.diff(v) > 0) else [
        f"V does not rise monotonically with {knob} over {lo:g}..{hi:g} mm: the first crossing is used"]
    value = _crossing(values, v, target.roughness)
    searched = [Run(x, f, jnd(equivalent_lambda(f), target.lambda_mm)) for x, f in zip(grid.values_mm, grid.feels)]
    runs: list[Run] = []
    for _ in range(max_runs):
        feel = judge(value)
        value = getattr(feel.skin, KNOBS[knob])
        runs.append(Run(value, feel, jnd(equivalent_lambda(feel), target.lambda_mm)))
        if progress:
            progress(f"verify: {knob} {value:.4f} mm: V {feel.roughness:.4f}, {runs[-1].jnd_error:+.2f} JND from "
                     "the target")
        if abs(runs[-1].jnd_error) <= tolerance_jnd:
            break
        value = _secant(runs + searched, target, lo, hi)
        if any(math.isclose(value, r.value_mm, rel_tol=1e-6) for r in runs):
            notes.append(f"the {knob} cannot move closer to the target within {lo:g}..{hi:g} mm")
            break
    best = min(runs, key=lambda r: abs(r.jnd_error))
    return FuzzyTune(best.feel.skin, knob, best.feel, target, best.jnd_error, mean_stderr_jnd(best.feel),
                     draw_jnd(best.feel), tuple(runs), reach, (lo, hi), tolerance_jnd, tuple(notes))


def _crossing(values: np.ndarray, v: np.ndarray, wanted: float) -> float:
    """The first knob value where V reaches ``wanted``, interpolated in log V over log knob between grid values."""
    k = int(np.nonzero(v >= wanted)[0][0])
    if k == 0:
        return float(values[0])
    a, b = math.log(values[k - 1]), math.log(values[k])
    va, vb = math.log(v[k - 1]), math.log(v[k])
    return math.exp(a + (b - a) * (math.log(wanted) - va) / (vb - va))


def _secant(runs: Sequence[Run], target: Target, lo: float, hi: float) -> float:
    """The next value: the secant through the two answers closest to the target, in log V over log knob (steps of
    at most a factor e^0.5, within lo..hi); where they do not rise, halfway to the nearer one on the target's side."""
    a, b = sorted(runs, key=lambda r: abs(r.jnd_error))[:2]
    slope = (math.log(a.feel.roughness) - math.log(b.feel.roughness)) / (math.log(a.value_mm) - math.log(b.value_mm)) \
        if not math.isclose(a.value_mm, b.value_mm) else 0.0
    if slope <= 0:
        return float(np.clip(math.sqrt(a.value_mm * b.value_mm), lo, hi))
    step = (math.log(target.roughness) - math.log(a.feel.roughness)) / slope
    return float(np.clip(a.value_mm * math.exp(np.clip(step, -0.5, 0.5)), lo, hi))

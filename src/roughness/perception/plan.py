"""Planning an experiment: how many trials until R is within a tolerance of its limit?

For every candidate number of trials, ``experiments`` simulated experiments are run: a balanced
design (design.py), the simulated observer's answers (observer.py) about stimuli whose true V is
known (an engine or a table), and the Thurstone scale (thurstone.py, started from the SDP at
lambda_max / 10; no cross-validation or bootstrap, which do not change the scale; the default
lapse rate of ``embed --scale thurstone``). Each experiment
gives the Pearson R of V against its scale, as ``perception fit`` would report it. With unlimited
trials the scale is the observer's coordinate ln(V)/2 (in noise SDs), so R tends to
R_inf = Pearson(V, ln V); the plan reports, per number of trials, the 5-95% range of R over the
experiments and the share with |R - R_inf| <= tolerance, and the smallest number of trials where
that share reaches ``share`` (default 90%).

The answer assumes the observer model: real subjects with more noise, lapses or a scale other than
ln V need more trials (try ``sigma``, ``lapse``).
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import pearsonr, spearmanr

from roughness.core.checks import in_range, integer, positive
from roughness.core.errors import InputError

from .design import FIELDNAMES, balanced_design
from .embed import TripletSDP, lambda_max, oriented
from .observer import Observer, perceptual_coordinate
from .thurstone import DEFAULT_LAPSE, thurstone_scale
from .trials import Trials

START_FRACTION = 0.1  # the SDP start at lambda_max / 10


@dataclass(frozen=True)
class PlanStep:
    """Simulated experiments with one number of trials."""

    trials: int
    pearson: np.ndarray  # (experiments,) R of V against the recovered scale
    spearman_truth: np.ndarray  # (experiments,) rank correlation of the scale with the observer's truth


@dataclass(frozen=True)
class Plan:
    stimuli: tuple[str, ...]
    roughness: np.ndarray  # true V per stimulus
    limit: float  # R_inf = Pearson(V, ln V)
    tolerance: float
    share: float
    steps: list[PlanStep]

    def within(self, step: PlanStep) -> float:
        """Share of the experiments whose R is within the tolerance of R_inf."""
        return float(np.mean(np.abs(step.pearson - self.limit) <= self.tolerance))

    @property
    def needed(self) -> int | None:
        """The smallest number of trials whose share within the tolerance reaches ``share`` (None: none does)."""
        return next((s.trials for s in self.steps if self.within(s) >= self.share), None)

    def summary(self) -> dict:
        return {"stimuli": len(self.stimuli), "limit_pearson": self.limit, "tolerance": self.tolerance,
                "share": self.share, "needed_trials": self.needed,
                "steps": [{"trials": s.trials, "experiments": len(s.pearson),
                           "pearson_mean": float(np.mean(s.pearson)),
                           "pearson_5": float(np.percentile(s.pearson, 5)),
                           "pearson_95": float(np.percentile(s.pearson, 95)),
                           "within_tolerance": self.within(s),
                           "spearman_truth_mean": float(np.mean(s.spearman_truth))} for s in self.steps]}


def simulated_trials(ids: Sequence[str], truth: np.ndarray, trials: int, observer: Observer, seed: int) -> Trials:
    """A balanced design of ``trials`` rows answered by ``observer`` about coordinates ``truth``."""
    design = balanced_design(list(ids), trials, seed=seed)
    index = {s: i for i, s in enumerate(ids)}
    asked = np.array([[index[t.reference], index[t.left], index[t.right]] for t in design])
    left = observer.answer(truth, asked, np.random.default_rng([seed, 1]))
    closer = np.where(left, asked[:, 1], asked[:, 2])
    farther = np.where(left, asked[:, 2], asked[:, 1])
    return Trials(tuple(ids), np.c_[asked[:, 0], closer, farther], tuple(t.subject for t in design), (),
                  tuple(FIELDNAMES))


def recovered_scale(trials: Trials, lapse: float) -> np.ndarray:
    """The Thurstone scale of ``trials``, started from the SDP at START_FRACTION * lambda_max."""
    unique, inverse = trials.unique()
    weights = np.bincount(inverse, minlength=len(unique)).astype(float)
    n = len(trials.stimuli)
    start = TripletSDP(n, unique).solve(weights, START_FRACTION * lambda_max(n, unique, weights))
    return thurstone_scale(unique, weights, start.coordinates(1)[:, 0], lapse).coordinate


def plan_trials(ids: Sequence[str], roughness: np.ndarray, trial_counts: Sequence[int], experiments: int = 20,
                observer: Observer | None = None, tolerance: float = 0.05, share: float = 0.9, seed: int = 0,
                progress: Callable[[int, int], None] | None = None) -> Plan:
    """Simulated experiments for every number of trials in ``trial_counts`` (see the module docstring)."""
    observer = observer or Observer()
    integer("experiments", experiments, minimum=2)
    positive("tolerance", tolerance)
    in_range("share", share, 0.0, 1.0)
    if len(ids) < 3 or len(ids) != len(roughness):
        raise InputError(f"need at least 3 stimuli with one V each, got {len(ids)} ids and {len(roughness)} values")
    if not trial_counts:
        raise InputError("give at least one number of trials", parameter="trials")
    for count in trial_counts:
        integer("trials", count, minimum=1)
    v = np.asarray(roughness, dtype=float)
    truth = perceptual_coordinate(v, ids)
    if np.ptp(truth) == 0:
        raise InputError("all stimuli have the same V: there is no scale to recover")
    counts = sorted(set(int(c) for c in trial_counts))
    roughest = int(np.argmax(v))
    steps, done, total = [], 0, len(counts) * experiments
    for count in counts:
        pearson, rank = np.empty(experiments), np.empty(experiments)
        for k in range(experiments):
            experiment_seed = int(np.random.SeedSequence([seed, count, k]).generate_state(1)[0])
            scale = recovered_scale(simulated_trials(ids, truth, count, observer, experiment_seed), DEFAULT_LAPSE)
            scale = oriented(scale, roughest)  # as `embed --roughest` would
            pearson[k] = pearsonr(v, scale)[0]
            rank[k] = spearmanr(scale, truth)[0]
            done += 1
            if progress:
                progress(done, total)
        steps.append(PlanStep(count, pearson, rank))
    return Plan(tuple(ids), v, float(pearsonr(v, truth)[0]), tolerance, share, steps)

"""Bootstrap intervals of the 1-D embedding (the paper's Fig. 9): resample trials, re-embed.

Each resample draws as many rows as the trials file has, with replacement (rows are independent
judgements), and either solves the SDP at the chosen lam (its first principal coordinate given the
sign that agrees with the full-data embedding) or re-fits the Thurstone scale from the full-data
scale. The 5th and 95th percentiles over resamples are each stimulus's interval.

Measured in benchmarks/perception_recovery.py (30 stimuli, 2,000 trials, 3 seeds): the SDP's
percentile intervals contain the truth 71% of the time; basic (59%), bias-corrected (64%) and normal
(68%) intervals do worse and aligning each resample's scale to the full one changes nothing (71%):
the shortfall is the SDP's own bias, which no interval built from resamples can see. The Thurstone
scale's percentile intervals contain the truth 90.0% of the time (20 seeds).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import integer

from .embed import aligned
from .parallel import SolveTask, solve_tasks
from .thurstone import DEFAULT_LAPSE, thurstone_scale
from .trials import Trials

PERCENTILES = (5.0, 95.0)


@dataclass(frozen=True)
class Bootstrap:
    samples: np.ndarray  # (resamples, n) coordinates, sign-aligned to the full-data embedding
    failed_solves: int

    @property
    def low(self) -> np.ndarray:
        return np.percentile(self.samples, PERCENTILES[0], axis=0)

    @property
    def high(self) -> np.ndarray:
        return np.percentile(self.samples, PERCENTILES[1], axis=0)


def resample_weights(trials: Trials, resamples: int, seed: int) -> list[np.ndarray]:
    """Per resample, the count of each distinct triplet among rows drawn with replacement."""
    unique, inverse = trials.unique()
    rng = np.random.default_rng(seed)
    rows = len(trials)
    return [np.bincount(inverse, weights=rng.multinomial(rows, np.full(rows, 1.0 / rows)), minlength=len(unique))
            for _ in range(resamples)]


def bootstrap(trials: Trials, lam: float, coordinate: np.ndarray, resamples: int = 500, seed: int = 0,
              workers: int = 1, progress: Callable[[int, int], None] | None = None) -> Bootstrap:
    """Resampled 1-D coordinates at ``lam``, aligned to ``coordinate`` (the full-data embedding)."""
    integer("resamples", resamples, minimum=2)
    unique, _ = trials.unique()
    tasks = [SolveTask(w, lam) for w in resample_weights(trials, resamples, seed)]
    results = solve_tasks(len(trials.stimuli), unique, tasks, workers, progress)
    ok = [r for r in results if r.success]
    samples = np.array([aligned(r.coordinates(1)[:, 0], coordinate) for r in ok])
    return Bootstrap(samples, len(results) - len(ok))


def thurstone_bootstrap(trials: Trials, coordinate: np.ndarray, resamples: int = 500, seed: int = 0,
                        lapse: float = DEFAULT_LAPSE,
                        progress: Callable[[int, int], None] | None = None) -> Bootstrap:
    """Resampled Thurstone scales, each fitted from ``coordinate`` (the full-data scale); serial (fast)."""
    integer("resamples", resamples, minimum=2)
    unique, _ = trials.unique()
    samples, failed = [], 0
    for i, weights in enumerate(resample_weights(trials, resamples, seed)):
        fit = thurstone_scale(unique, weights, coordinate, lapse)
        if fit.success:
            samples.append(fit.coordinate)
        else:
            failed += 1
        if progress:
            progress(i + 1, resamples)
    return Bootstrap(np.array(samples), failed)

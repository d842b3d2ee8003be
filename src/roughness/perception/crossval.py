"""k-fold cross-validation of the regulariser lam (the paper's Fig. 10, left).

Rows of the trials file (not distinct triplets) are dealt into ``folds`` random folds; for each lam
and fold the SDP is solved on the other folds, and the triplet error (fraction of triplets the
embedding orders wrongly) is measured on the training rows and on the held-out rows. The chosen lam
minimises the mean held-out error (ties go to the larger lam: the simpler, lower-rank embedding).
The default grid spans three decades below ``lambda_max`` of the training folds (where the
embedding collapses to K = 0), so it adapts to the number of trials.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import integer
from roughness.core.errors import InputError

from .embed import lambda_max, triplet_error
from .parallel import SolveTask, solve_tasks
from .trials import Trials

GRID_DECADES = 3.0  # default grid: lambda_max * 10**(-3 ... 0), four values per decade
GRID_POINTS = 13


@dataclass(frozen=True)
class CrossValidation:
    lambdas: np.ndarray  # (L,)
    train_error: np.ndarray  # (L, folds)
    test_error: np.ndarray  # (L, folds)
    failed_solves: int

    @property
    def best_lambda(self) -> float:
        mean = self.test_error.mean(axis=1)
        best = np.flatnonzero(mean <= mean.min() + 1e-12)
        return float(self.lambdas[best[-1]])

    @property
    def one_se_lambda(self) -> float:
        """The largest lam whose mean held-out error is within one standard error of the minimum."""
        mean = self.test_error.mean(axis=1)
        sem = self.test_error.std(axis=1, ddof=1) / np.sqrt(self.test_error.shape[1])
        best = int(np.argmin(mean))
        return float(self.lambdas[np.flatnonzero(mean <= mean[best] + sem[best])[-1]])

    def summary(self) -> dict:
        return {"lambdas": self.lambdas.tolist(), "train_error": self.train_error.mean(axis=1).tolist(),
                "test_error": self.test_error.mean(axis=1).tolist(),
                "test_error_sem": (self.test_error.std(axis=1, ddof=1) / np.sqrt(self.test_error.shape[1])).tolist(),
                "folds": int(self.test_error.shape[1]), "best_lambda": self.best_lambda,
                "one_se_lambda": self.one_se_lambda,
                "failed_solves": self.failed_solves}


def fold_of_rows(rows: int, folds: int, seed: int) -> np.ndarray:
    """Fold number (0..folds-1) of each row, as equal as possible, randomly assigned."""
    return np.random.default_rng(seed).permutation(rows) % folds


def default_lambdas(trials: Trials, folds: int) -> np.ndarray:
    """lambda_max of a training fold (all rows but one fold's share) times 10**(-3 ... 0)."""
    unique, inverse = trials.unique()
    weights = np.bincount(inverse, minlength=len(unique)) * (folds - 1) / folds
    top = lambda_max(len(trials.stimuli), unique, weights)
    return top * np.logspace(-GRID_DECADES, 0.0, GRID_POINTS)


def cross_validate(trials: Trials, lambdas: Sequence[float] | None = None, folds: int = 10, seed: int = 0,
                   workers: int = 1, progress: Callable[[int, int], None] | None = None) -> CrossValidation:
    """Train and held-out triplet error for every lam (default: ``default_lambdas``) and fold."""
    integer("folds", folds, minimum=2)
    if folds > len(trials):
        raise InputError(f"{folds} folds need at least {folds} trials, got {len(trials)}", parameter="folds")
    lambdas = default_lambdas(trials, folds) if lambdas is None else np.asarray(sorted(lambdas), dtype=float)
    if len(lambdas) == 0 or np.any(~np.isfinite(lambdas)) or np.any(lambdas < 0):
        raise InputError("lambdas must be finite numbers >= 0", parameter="lambdas")
    unique, inverse = trials.unique()
    fold = fold_of_rows(len(trials), folds, seed)
    train_weights = [np.bincount(inverse[fold != k], minlength=len(unique)).astype(float) for k in range(folds)]
    tasks = [SolveTask(train_weights[k], lam) for lam in lambdas for k in range(folds)]
    results = solve_tasks(len(trials.stimuli), unique, tasks, workers, progress)
    train = np.empty((len(lambdas), folds))
    test = np.empty((len(lambdas), folds))
    for i, result in enumerate(results):
        li, k = divmod(i, folds)
        train[li, k] = triplet_error(result.gram, unique, train_weights[k])
        test[li, k] = triplet_error(result.gram, trials.triplets[fold == k])
    return CrossValidation(lambdas, train, test, sum(not r.success for r in results))

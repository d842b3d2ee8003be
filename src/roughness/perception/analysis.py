"""The embedding pipeline: cross-validate lam, embed all trials, bootstrap intervals, write the results.

The 1-D coordinate is the SDP's (``scale="sdp"``, the paper's) or the Thurstone maximum-likelihood
scale started from it (``scale="thurstone"``: metric, in units of the observer's noise SD; its
intervals contain the truth about 90% of the time where the SDP's do 63-77%, see thurstone.py).

Outputs (in the output folder): ``embedding.csv`` (stimulus, coordinate, low, high; rows ordered as
the stimuli), ``embedding.json`` (summary: lam, CV curves, spectrum, solver statistics, provenance)
and the figures (see plots.py).
"""
from __future__ import annotations

import csv
import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError, SimulationError
from roughness.core.files import atomic_write, write_csv

from .bootstrap import PERCENTILES, Bootstrap, bootstrap, thurstone_bootstrap
from .crossval import CrossValidation, cross_validate
from .embed import EmbedResult, TripletSDP, oriented, triplet_error
from .thurstone import DEFAULT_LAPSE, ThurstoneFit, thurstone_scale
from .trials import Trials, disconnection_warning, id_problem, listed

SCALES = ("sdp", "thurstone")
EMBEDDING_COLUMNS = ("stimulus", "coordinate", "low", "high")


@dataclass
class EmbeddingAnalysis:
    stimuli: tuple[str, ...]
    coordinate: np.ndarray  # (n,) 1-D embedding, oriented
    low: np.ndarray | None  # bootstrap 5% (None without bootstrap)
    high: np.ndarray | None
    fit: EmbedResult  # the full-data solve
    cv: CrossValidation | None
    boot: Bootstrap | None
    orientation: str
    seconds: dict[str, float]
    scale: str = "sdp"
    thurstone: ThurstoneFit | None = None
    lapse: float | None = None

    def summary(self, trials: Trials) -> dict:
        spectrum = self.fit.eigenvalues
        unique, inverse = trials.unique()
        weights = np.bincount(inverse, minlength=len(unique)).astype(float)
        groups = trials.groups()
        return {
            "stimuli": len(self.stimuli), "trials": len(trials), "distinct_triplets": len(unique),
            "disconnected_groups": [list(g) for g in groups] if len(groups) > 1 else None,
            "warnings": [w for w in (disconnection_warning(groups),) if w],
            "subjects": len(set(trials.subjects)), "lambda": self.fit.lam,
            "lambda_source": "cross-validation" if self.cv else "given",
            "cross_validation": self.cv.summary() if self.cv else None,
            "spectrum": spectrum.tolist(),
            "first_dimension_share": float(spectrum[0] / spectrum.sum()) if spectrum.sum() > 0 else None,
            "training_error": triplet_error(self.fit.gram, unique, weights),
            "training_error_1d": triplet_error(_gram_1d(self.coordinate), unique, weights),
            "orientation": self.orientation,
            "scale": self.scale,
            "thurstone": None if self.thurstone is None else {
                "units": "noise SD of the observer model", "lapse": self.lapse,
                "log_likelihood": self.thurstone.log_likelihood, "iterations": self.thurstone.iterations,
                "success": self.thurstone.success, "message": self.thurstone.message},
            "bootstrap": None if self.boot is None else {
                "resamples": len(self.boot.samples), "failed_solves": self.boot.failed_solves,
                "percentiles": list(PERCENTILES)},
            "solver": {"name": "SCS via cvxpy", "status": self.fit.status, "iterations": self.fit.iterations,
                       "seconds": self.fit.seconds, "objective": self.fit.objective},
            "seconds": self.seconds,
        }


def _gram_1d(coordinate: np.ndarray) -> np.ndarray:
    return np.outer(coordinate, coordinate)


def analyse(trials: Trials, lam: float | None = None, lambdas: Sequence[float] | None = None, folds: int = 10,
            resamples: int = 500, seed: int = 0, workers: int = 1, roughest: str | None = None,
            progress: Callable[[str], Callable[[int, int], None] | None] = lambda what: None,
            scale: str = "sdp", lapse: float = DEFAULT_LAPSE) -> EmbeddingAnalysis:
    """Cross-validate lam (unless given), embed all trials at it, bootstrap (unless resamples == 0).

    ``scale``: "sdp" (the SDP's first principal coordinate) or "thurstone" (the maximum-likelihood
    scale of thurstone.py with lapse rate ``lapse``, started from the SDP coordinate).

    ``roughest`` is a stimulus id that must come out on the positive (rough) side; without it the
    sign is fixed by the stimulus farthest from the centre. ``progress(what)`` gives a callback for
    each stage.
    """
    if scale not in SCALES:
        raise InputError(f"scale must be one of {', '.join(SCALES)}, got {scale!r}", parameter="scale")
    if roughest is not None and roughest not in trials.stimuli:
        raise InputError(f"roughest stimulus {roughest!r} is not among the trials' stimuli", parameter="roughest")
    seconds: dict[str, float] = {}
    cv = None
    if lam is None:
        start = time.perf_counter()
        cv = cross_validate(trials, lambdas, folds, seed, workers, progress("cross-validation"))
        seconds["cross_validation"] = time.perf_counter() - start
        lam = cv.best_lambda
    unique, inverse = trials.unique()
    start = time.perf_counter()
    fit = TripletSDP(len(trials.stimuli), unique).solve(np.bincount(inverse, minlength=len(unique)), lam)
    seconds["embedding"] = time.perf_counter() - start
    if not fit.success:
        raise SimulationError(f"the embedding SDP failed: {fit.message}")
    pivot = trials.stimuli.index(roughest) if roughest is not None else None
    coordinate = oriented(fit.coordinates(1)[:, 0], pivot)
    metric = None
    if scale == "thurstone":
        start = time.perf_counter()
        metric = thurstone_scale(unique, np.bincount(inverse, minlength=len(unique)), coordinate, lapse)
        seconds["thurstone"] = time.perf_counter() - start
        if not metric.success:
            raise SimulationError(f"the Thurstone scale did not converge: {metric.message}")
        coordinate = oriented(metric.coordinate, pivot)
    orientation = (f"{roughest} on the positive side" if roughest is not None
                   else "arbitrary sign (pass the roughest stimulus to orient rough-positive)")
    boot = None
    if resamples:
        start = time.perf_counter()
        boot = (bootstrap(trials, lam, coordinate, resamples, seed + 1, workers, progress("bootstrap"))
                if metric is None else
                thurstone_bootstrap(trials, coordinate, resamples, seed + 1, lapse, progress("bootstrap")))
        seconds["bootstrap"] = time.perf_counter() - start
        if len(boot.samples) < 2:
            raise SimulationError(f"the bootstrap failed: {boot.failed_solves} of {resamples} solves failed")
    return EmbeddingAnalysis(trials.stimuli, coordinate, boot.low if boot else None, boot.high if boot else None,
                             fit, cv, boot, orientation, seconds, scale, metric, lapse if metric else None)


def write_embedding_csv(path: str | Path, analysis: EmbeddingAnalysis) -> Path:
    def interval(bound: np.ndarray | None, i: int) -> str:
        return "" if bound is None else f"{bound[i]:.6g}"

    rows = ([stimulus, f"{analysis.coordinate[i]:.6g}", interval(analysis.low, i), interval(analysis.high, i)]
            for i, stimulus in enumerate(analysis.stimuli))
    return write_csv(path, EMBEDDING_COLUMNS, rows)


@dataclass(frozen=True)
class EmbeddingTable:
    """An ``embedding.csv`` as read back: ids, coordinates and (possibly missing) intervals."""

    stimuli: tuple[str, ...]
    coordinate: np.ndarray
    low: np.ndarray  # NaN where the file has no interval
    high: np.ndarray


def read_embedding_csv(path: str | Path) -> EmbeddingTable:
    path = Path(path)
    if not path.is_file():
        raise InputError(f"embedding file not found: {path}", parameter="embedding")
    try:
        return _embedding_table(path)
    except (UnicodeDecodeError, csv.Error) as err:
        raise InputError(f"{path}: not a readable CSV table ({err})", parameter="embedding") from None


def _embedding_table(path: Path) -> EmbeddingTable:
    with open(path, newline="", encoding="utf-8-sig") as f:
        reader = csv.DictReader(f)
        missing = [c for c in ("stimulus", "coordinate") if c not in (reader.fieldnames or ())]
        if missing:
            raise InputError(f"{path}: missing column(s) {', '.join(missing)}; expected "
                             f"{','.join(EMBEDDING_COLUMNS)}", parameter="embedding")
        ids, values = [], []
        for row in reader:
            try:
                values.append([float(row["coordinate"]), _optional(row.get("low")), _optional(row.get("high"))])
            except (TypeError, ValueError):
                raise InputError(f"{path}, line {reader.line_num}: coordinate, low and high must be numbers",
                                 parameter="embedding") from None
            ids.append((row["stimulus"] or "").strip())
    if len(ids) < 3 or len(set(ids)) != len(ids) or "" in ids:
        raise InputError(f"{path}: need at least 3 rows with distinct, non-empty stimulus ids", parameter="embedding")
    refused = [why for why in map(id_problem, ids) if why]
    if refused:
        raise InputError(listed(f"{path}: refused stimulus ids", refused), parameter="embedding")
    array = np.array(values, dtype=float)
    if not np.all(np.isfinite(array[:, 0])):
        raise InputError(f"{path}: coordinates must be finite", parameter="embedding")
    return EmbeddingTable(tuple(ids), array[:, 0], array[:, 1], array[:, 2])


def _optional(text: str | None) -> float:
    return float("nan") if text is None or not text.strip() else float(text)


def write_json(path: str | Path, data: dict) -> Path:
    return atomic_write(path, lambda tmp: Path(tmp).write_text(json.dumps(data, indent=2, allow_nan=False) + "\n"))

"""Perception analysis with plain arguments (file paths, numbers, strings), for Python and notebooks.

``roughness.embed_trials`` and ``roughness.fit_embedding`` are these functions: what ``roughness perception
embed`` and ``roughness perception fit`` compute, returned instead of written (``plots`` draws them).
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from roughness.core.checks import choice, file_path, in_range, integer, non_negative
from roughness.core.errors import InputError
from roughness.core.limits import MAX_PARALLEL, check_size

from .analysis import SCALES, EmbeddingAnalysis, analyse, read_embedding_csv
from .fit import Fit, classical_measures
from .thurstone import DEFAULT_LAPSE


def embed_trials(trials: str | Path, stimuli: str | Path | None = None, *, lam: float | None = None,
                 folds: int = 10, resamples: int = 500, seed: int = 0, workers: int = 1,
                 roughest: str | None = None, scale: str = "sdp", lapse: float = DEFAULT_LAPSE,
                 repeats: str = "keep") -> EmbeddingAnalysis:
    """The 1-D perceptual scale of the stimuli from triplet trials ("which of B, C is more like A?").

    Parameters
    ----------
    trials : path
        The trials CSV file (columns as for ``roughness perception embed``).
    stimuli : path, optional
        The stimuli table: the trials' ids must be among its stimuli.
    lam : float, optional
        Regulariser (trace weight) of the SDP; default: chosen by ``folds``-fold cross-validation.
    resamples : int
        Bootstrap resamples for the 5-95% intervals (0: none).
    seed : int
        Seed of the folds and resamples.
    workers : int
        Processes for cross-validation and bootstrap.
    roughest : str, optional
        A stimulus id to orient the scale (rough to the positive side).
    scale : {"sdp", "thurstone"}
        The SDP's first principal coordinate (embedding units), or the Thurstone scale (noise SDs).
    lapse : float
        Lapse rate of the Thurstone observer (fraction of random answers).
    repeats : {"keep", "error"}
        What to do with repeated trials.

    Returns
    -------
    EmbeddingAnalysis
        ``.stimuli``, ``.coordinate`` (n,), ``.low``/``.high`` (bootstrap interval), ``.fit`` (the SDP solve).
    """
    from .embed import require_cvxpy
    from .stimuli import read_stimuli
    from .trials import read_trials

    _check_embedding_options(lam, folds, resamples, seed, workers, roughest, scale, lapse)
    trials, stimuli = file_path("trials", trials), None if stimuli is None else file_path("stimuli", stimuli)
    require_cvxpy()
    ids = [s.stimulus for s in read_stimuli(stimuli)] if stimuli is not None else None
    return analyse(read_trials(trials, ids, repeats), lam=lam, folds=folds, resamples=resamples, seed=seed,
                   workers=workers, roughest=roughest, scale=scale, lapse=lapse)


def _check_embedding_options(lam: object, folds: object, resamples: object, seed: object, workers: object,
                             roughest: object, scale: object, lapse: object) -> None:
    """InputError naming the first of ``embed_trials``'s options that is out of its domain (before any solve)."""
    if lam is not None:
        non_negative("lam", lam)
    integer("folds", folds, minimum=2)
    integer("resamples", resamples, minimum=0)
    integer("seed", seed, minimum=0)
    check_size("worker processes", integer("workers", workers, minimum=1), MAX_PARALLEL, "workers")
    if roughest is not None and not isinstance(roughest, str):
        raise InputError(f"roughest must be a stimulus id (a string), got {roughest!r}", parameter="roughest")
    choice("scale", scale, SCALES)
    in_range("lapse", lapse, 0.0, 1.0)


def fit_embedding(embedding: EmbeddingAnalysis | str | Path, stimuli: str | Path, *, engine: str = "surrogate",
                  exclude: Sequence[str] = (), cache: str | Path | None = None) -> Fit:
    """V of each stimulus against its perceptual coordinate, with the classical measures beside it.

    Parameters
    ----------
    embedding : EmbeddingAnalysis or path
        An ``embed_trials`` result or an ``embedding.csv`` written by ``roughness perception embed``.
    stimuli : path
        The stimuli table: each embedded stimulus's heightmap (file with units, or a named texture).
    engine : {"surrogate", "auto", "fem:coarse", "fem:default", "fem:fine"}
        What computes V (dimensionless).
    exclude : sequence of str
        Stimulus ids left out of the "included" correlations (at least 3 must remain).
    cache : path, optional
        Folder of cached FEM results (FEM engines need one).

    Returns
    -------
    Fit
        ``.roughness`` (V per stimulus), ``.coordinate``, ``.correlations()`` (Pearson and Spearman, all and
        included); ``plots.plot_fit(fit)`` draws it.
    """
    from .stimuli import read_stimuli
    from .trials import listed
    from .values import check_engine, stimulus_values

    check_engine(engine)
    if isinstance(exclude, str) or not isinstance(exclude, (list, tuple, set)) or \
            not all(isinstance(i, str) for i in exclude):
        raise InputError(f"exclude must be a list of stimulus ids (strings), got {exclude!r}", parameter="exclude")
    cache = None if cache is None else file_path("cache", cache)
    if not isinstance(embedding, (str, Path, EmbeddingAnalysis)):
        raise InputError(f"embedding must be an embed_trials result or the path of an embedding.csv, got "
                         f"{type(embedding).__name__}", parameter="embedding")
    table = read_embedding_csv(embedding) if isinstance(embedding, (str, Path)) else embedding
    stimuli = file_path("stimuli", stimuli)
    ids = list(table.stimuli)
    by_id = {s.stimulus: s for s in read_stimuli(stimuli)}
    missing = [i for i in ids if i not in by_id]
    if missing:
        raise InputError(listed("stimuli not in the stimuli table", missing), parameter="stimuli")
    unknown = [i for i in exclude if i not in ids]
    if unknown:
        raise InputError(listed("excluded stimuli not in the embedding", unknown), parameter="exclude")
    if len(ids) - len(set(exclude)) < 3:
        raise InputError(f"{len(set(exclude))} of {len(ids)} stimuli excluded: the fit needs at least 3",
                         parameter="exclude")
    heightmaps = [by_id[i].heightmap() for i in ids]
    values = stimulus_values(ids, heightmaps, engine, cache)
    nan = np.full(len(ids), np.nan)
    low = nan if table.low is None else table.low
    high = nan if table.high is None else table.high
    included = np.array([i not in exclude for i in ids])
    return Fit(tuple(ids), table.coordinate, low, high, values, included, classical_measures(heightmaps))

"""A simulated observer: answers triplet trials about stimuli of known roughness.

Noise model (Thurstone-like, Weber on the roughness scale). The observer's perceptual coordinate of
a stimulus of strain variation V is

    p = ln(V) / 2        (V grows about as lambda^2 on the standard scale, so p = ln(lambda) + const)

On every trial it perceives each of the three stimuli independently as p + e, e ~ Normal(0, sigma^2),
and answers the comparison whose perceived coordinate is closer to the perceived reference; with
probability ``lapse`` it answers at random instead. Constant noise on a log scale is Weber's law: the
just-noticeable difference is a fixed ratio. The default sigma = 0.18 follows from the paper's Weber
fraction 0.19 on lambda: a 19% step (ln 1.19 = 0.174 in p) is discriminated 75% of the time when
Phi(0.174 / (sigma sqrt 2)) = 0.75, i.e. sigma = 0.174 / (0.674 sqrt 2) = 0.18.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import in_range, non_negative
from roughness.core.errors import InputError
from roughness.perceptual_scale import LOG_JND

from .trials import listed

DEFAULT_SIGMA = LOG_JND / (0.6744897501960817 * math.sqrt(2))  # 0.182


def perceptual_coordinate(roughness: np.ndarray, stimuli: Sequence[str] | None = None) -> np.ndarray:
    """p = ln(V) / 2 of strain variations V (> 0); ``stimuli`` (their ids) name the offending ones in the error."""
    v = np.asarray(roughness, dtype=float)
    bad = ~(np.isfinite(v) & (v > 0))
    if np.any(bad):
        names = [f"{stimuli[i] if stimuli is not None else f'#{i + 1}'} (V = {v[i]:g})" for i in np.flatnonzero(bad)]
        raise InputError(listed("the observer needs a positive finite roughness V for every stimulus (it compares "
                                "ln V; a flat or featureless texture has none); not so for", names))
    return 0.5 * np.log(v)


@dataclass(frozen=True)
class Observer:
    """Thurstone observer with Gaussian noise ``sigma`` on the coordinate p and a lapse rate."""

    sigma: float = DEFAULT_SIGMA
    lapse: float = 0.0

    def __post_init__(self) -> None:
        non_negative("sigma", self.sigma)
        in_range("lapse", self.lapse, 0.0, 1.0)

    def answer(self, coordinate: np.ndarray, triplets: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """For (reference, left, right) index rows: True where the observer answers "left"."""
        p = np.asarray(coordinate, dtype=float)
        ref, left, right = np.asarray(triplets).T
        e = rng.normal(0.0, 1.0, (3, len(ref))) * self.sigma
        seen_ref, seen_left, seen_right = p[ref] + e[0], p[left] + e[1], p[right] + e[2]
        says_left = np.abs(seen_left - seen_ref) < np.abs(seen_right - seen_ref)
        lapsed = rng.uniform(size=len(ref)) < self.lapse
        return np.where(lapsed, rng.uniform(size=len(ref)) < 0.5, says_left)


def noiseless_answer(coordinate: np.ndarray, triplets: np.ndarray) -> np.ndarray:
    """The answer of a noise-free observer (True = "left"); ties go to "right"."""
    p = np.asarray(coordinate, dtype=float)
    ref, left, right = np.asarray(triplets).T
    return np.abs(p[left] - p[ref]) < np.abs(p[right] - p[ref])

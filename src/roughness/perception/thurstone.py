"""A metric 1-D scale from triplets: maximum likelihood under the Thurstone observer model.

The SDP's coordinate (embed.py) is non-metric: it orders the stimuli, but its spacing is a nonlinear
function of the perceptual scale (measured in benchmarks/perception_recovery.py: the SDP's large-sample
limit compresses the ends and follows the stimuli's local spacing, by up to 8-12% of the range, about
the half-width of a 5-95% interval). This module fits the scale itself.

Model (the simulated observer's, observer.py): stimulus i has coordinate p_i; on every trial the
observer perceives p + e, e ~ N(0, 1) independently for the three stimuli (the unit of p is the
noise SD), and answers that comparison c is closer to the reference r than f is when
|c' - r'| < |f' - r'|. With u = c' - f' and v = c' + f' - 2 r' (independent Gaussians: their
covariance var(c') - var(f') is 0), |c'-r'| < |f'-r'| iff u v < 0, so

    P(c closer) = Phi(-mu/sqrt2) Phi(nu/sqrt6) + Phi(mu/sqrt2) Phi(-nu/sqrt6),
    mu = p_c - p_f,  nu = p_c + p_f - 2 p_r.

A lapse rate ``lapse`` mixes in random answers: P = lapse / 2 + (1 - lapse) P (it also keeps one
careless answer on an easy triplet from dominating the likelihood). A weak Gaussian prior p ~ N(0,
PRIOR_SD^2) keeps the scale finite where the answers do not bound it (a stimulus that is always
judged farther than all others, as in noise-free answers); at PRIOR_SD = 10 noise SDs it moves the
estimates by under 0.1% of the scale's range (measured: 30 stimuli spanning 5 SDs, 2,000 trials). The scale is centred (sum p = 0) and has the start's
orientation; it is found with L-BFGS from the start (e.g. the SDP coordinate) rescaled by a 1-D
search.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize, minimize_scalar
from scipy.special import ndtr

from roughness.core.checks import in_range

DEFAULT_LAPSE = 0.01
PRIOR_SD = 10.0  # noise SDs
SQRT2, SQRT6 = np.sqrt(2.0), np.sqrt(6.0)


@dataclass(frozen=True)
class ThurstoneFit:
    """The maximum-likelihood scale (units: the observer's noise SD), like scipy.optimize results."""

    coordinate: np.ndarray  # (n,) centred
    success: bool
    message: str
    iterations: int
    log_likelihood: float


def answer_probability(p: np.ndarray, triplets: np.ndarray, lapse: float):
    """P(answer) per triplet (reference, closer, farther) and its derivatives in mu and nu."""
    r, c, f = triplets.T
    a, b = (p[c] - p[f]) / SQRT2, (p[c] + p[f] - 2 * p[r]) / SQRT6
    pa, pb = ndtr(a), ndtr(b)
    prob = (1 - pa) * pb + pa * (1 - pb)
    da = np.exp(-0.5 * a * a) / np.sqrt(2 * np.pi)
    db = np.exp(-0.5 * b * b) / np.sqrt(2 * np.pi)
    d_mu = da / SQRT2 * (1 - 2 * pb)
    d_nu = db / SQRT6 * (1 - 2 * pa)
    return lapse / 2 + (1 - lapse) * prob, (1 - lapse) * d_mu, (1 - lapse) * d_nu


def negative_log_likelihood(p: np.ndarray, triplets: np.ndarray, weights: np.ndarray, lapse: float = DEFAULT_LAPSE):
    """-sum_t w_t ln P_t and its gradient in p."""
    prob, d_mu, d_nu = answer_probability(p, triplets, lapse)
    prob = np.maximum(prob, 1e-300)
    g = -weights / prob
    r, c, f = triplets.T
    grad = (np.bincount(c, g * (d_mu + d_nu), len(p)) + np.bincount(f, g * (d_nu - d_mu), len(p))
            - 2 * np.bincount(r, g * d_nu, len(p)))
    return float(-np.sum(weights * np.log(prob))), grad


def thurstone_scale(triplets: np.ndarray, weights: np.ndarray, start: np.ndarray,
                    lapse: float = DEFAULT_LAPSE) -> ThurstoneFit:
    """Maximum-likelihood coordinates of the stimuli from distinct triplets (reference, closer, farther)
    answered ``weights`` times, starting from ``start`` (any scale, e.g. the SDP coordinate)."""
    in_range("lapse", lapse, 0.0, 1.0)
    triplets = np.asarray(triplets, dtype=np.int64)
    weights = np.asarray(weights, dtype=float)
    start = np.asarray(start, dtype=float) - np.mean(start)
    spread = np.std(start)
    if spread > 0:  # the unit of p is the noise SD: first the best multiple of the start
        best = minimize_scalar(lambda s: negative_log_likelihood(s * start / spread, triplets, weights, lapse)[0]
                               + 0.5 * s * s * len(start) / PRIOR_SD**2, bounds=(1e-3, 1e3), method="bounded")
        start = best.x * start / spread

    def objective(p):  # the prior, and (sum p)^2 / 2 to fix the translation
        value, grad = negative_log_likelihood(p, triplets, weights, lapse)
        total = float(np.sum(p))
        return (value + 0.5 * float(p @ p) / PRIOR_SD**2 + 0.5 * total * total,
                grad + p / PRIOR_SD**2 + total)

    result = minimize(objective, start, jac=True, method="L-BFGS-B", options={"maxiter": 2000, "gtol": 1e-8})
    p = result.x - np.mean(result.x)
    if float(p @ start) < 0:
        p = -p
    return ThurstoneFit(p, bool(result.success), str(result.message), int(result.nit),
                        -negative_log_likelihood(p, triplets, weights, lapse)[0])

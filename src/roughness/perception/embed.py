"""Non-metric embedding of triplet judgements: the trace-regularised SDP of Wills et al. (2009).

Given triplets (r, c, f), "c is closer to r than f is", find the Gram matrix K of n points:

    minimise    sum_t w_t xi_t + lam * trace(K)
    subject to  d(r, f) - d(r, c) >= 1 - xi_t,  xi_t >= 0     (one per distinct triplet t)
                K positive semidefinite,  K 1 = 0              (centred)

with d(i, j) = K_ii + K_jj - 2 K_ij (squared distance). The weights w_t count how often triplet t
was answered (bootstrap resamples and cross-validation folds only change w). The margins of all
triplets are one sparse matrix times vec(K). The problem is compiled once (cvxpy parameters for w
and lam) and re-solved for every weight vector and lam, which is what makes 500 resamples cheap.

Solver: SCS (cvxpy's open-source splitting conic solver), measured against Clarabel (interior
point) on 46 stimuli x 3,000 simulated triplets (benchmarks/perception_speed.py, shared 2-core
machine): at lambda = 1, SCS 1.1 s against Clarabel 4.6 s; at the cross-validated lambda = 30,
SCS 3.7 s against 3.4 s. Both reach the same objective (to 1e-5 relative), but Clarabel ends with
status "optimal_inaccurate" on these problems (cvxpy warns on every solve) where SCS reports
"optimal", and small lambda (where Clarabel was 4x slower) is where cross-validation spends most.

Each solve starts cold (no warm start), so a result depends only on its weights and lam, never on
which solves a worker process did before: bootstrap and cross-validation are deterministic per seed.

Above ``lambda_max`` (the largest eigenvalue of the weighted constraint matrix on the centred
subspace) K = 0 is optimal: every triplet is a tie. Cross-validation searches below it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from roughness.core.errors import InputError

SOLVER = "SCS"
SOLVER_EPS = 1e-4  # SCS tolerance (eps_abs = eps_rel, its default); objectives agree with 1e-5 to ~1e-6 relative
TIE_MARGIN = 1e-3  # |d(r,f) - d(r,c)| below this (unit margin 1; 10x the solver tolerance) is a tie
INSTALL_HINT = "the perception tools need cvxpy: pip install 'roughness[perception]' (or pip install cvxpy)"


def require_cvxpy():
    """The cvxpy module, or InputError with the install hint."""
    try:
        import cvxpy
    except ImportError:
        raise InputError(INSTALL_HINT) from None
    return cvxpy


@dataclass
class EmbedResult:
    """One solve of the SDP, reported like scipy.optimize results."""

    gram: np.ndarray  # (n, n) K, symmetric PSD, centred
    success: bool
    status: str
    message: str
    iterations: int
    seconds: float
    objective: float
    lam: float

    @property
    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of K, largest first (the spectrum of the embedding)."""
        return np.linalg.eigvalsh(self.gram)[::-1]

    def coordinates(self, dims: int = 1) -> np.ndarray:
        """(n, dims) principal coordinates: eigenvectors of K scaled by sqrt(eigenvalue)."""
        values, vectors = np.linalg.eigh(self.gram)
        order = np.argsort(values)[::-1][:dims]
        return vectors[:, order] * np.sqrt(np.maximum(values[order], 0.0))


class TripletSDP:
    """The SDP over fixed distinct triplets, compiled once; ``solve`` for any weights and lam."""

    def __init__(self, n: int, triplets: np.ndarray) -> None:
        cp = require_cvxpy()
        triplets = np.asarray(triplets, dtype=np.int64)
        if n < 3 or triplets.ndim != 2 or triplets.shape[1] != 3 or len(triplets) == 0:
            raise InputError(f"need at least 3 stimuli and one triplet, got {n} stimuli and shape {triplets.shape}")
        if triplets.min() < 0 or triplets.max() >= n:
            raise InputError(f"triplet indices must lie in 0..{n - 1}")
        self.n, self.triplets = n, triplets
        self.weights = cp.Parameter(len(triplets), nonneg=True)
        self.lam = cp.Parameter(nonneg=True)
        self.gram = cp.Variable((n, n), PSD=True)
        self.slack = cp.Variable(len(triplets))
        margins = margin_matrix(n, triplets) @ cp.vec(self.gram, order="F")
        self.problem = cp.Problem(cp.Minimize(self.weights @ self.slack + self.lam * cp.trace(self.gram)),
                                  [self.slack >= 0, self.slack >= 1 - margins, cp.sum(self.gram, axis=0) == 0])

    def solve(self, weights: np.ndarray, lam: float) -> EmbedResult:
        """Solve for triplet weights (counts, >= 0) and regulariser lam (>= 0)."""
        cp = require_cvxpy()
        weights = np.asarray(weights, dtype=float)
        if weights.shape != (len(self.triplets),) or np.any(weights < 0) or not np.all(np.isfinite(weights)):
            raise InputError(f"weights must be {len(self.triplets)} finite numbers >= 0")
        if not (np.isfinite(lam) and lam >= 0):
            raise InputError(f"lam must be a finite number >= 0, got {lam}", parameter="lam")
        self.weights.value, self.lam.value = weights, float(lam)
        start = time.perf_counter()
        try:
            self.problem.solve(solver=SOLVER, eps_abs=SOLVER_EPS, eps_rel=SOLVER_EPS, warm_start=False)
        except cp.error.SolverError as err:
            return EmbedResult(np.zeros((self.n, self.n)), False, "solver_error", str(err), 0,
                               time.perf_counter() - start, float("nan"), float(lam))
        seconds = time.perf_counter() - start
        status = str(self.problem.status)
        gram = self.gram.value if self.gram.value is not None else np.zeros((self.n, self.n))
        gram = project_gram(gram)
        stats = self.problem.solver_stats
        success = status in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE)
        return EmbedResult(gram, success, status, f"{SOLVER}: {status}", int(stats.num_iters or 0), seconds,
                           float(self.problem.value), float(lam))


def margin_matrix(n: int, triplets: np.ndarray) -> sp.csr_matrix:
    """(T, n*n) sparse A with (A vec(K))_t = d(r, f) - d(r, c) for column-major vec(K)."""
    r, c, f = np.asarray(triplets).T
    t = len(r)
    cols = np.c_[f + f * n, c + c * n, r + f * n, r + c * n].ravel()
    vals = np.tile([1.0, -1.0, -2.0, 2.0], t)
    return sp.csr_matrix((vals, (np.repeat(np.arange(t), 4), cols)), shape=(t, n * n))


def lambda_max(n: int, triplets: np.ndarray, weights: np.ndarray) -> float:
    """The smallest lam at which K = 0 is optimal: K = 0, xi = 1 satisfy the optimality conditions iff
    lam I - G is PSD on the centred subspace, G = sum_t w_t M_t with <M_t, K> the margin of triplet t."""
    g = (margin_matrix(n, triplets).T @ np.asarray(weights, dtype=float)).reshape(n, n, order="F")
    centre = np.eye(n) - 1.0 / n
    return float(max(np.linalg.eigvalsh(centre @ ((g + g.T) / 2) @ centre)[-1], 0.0))


def project_gram(gram: np.ndarray) -> np.ndarray:
    """The nearest symmetric, centred, PSD matrix (removes the solver's tolerance-level violations)."""
    n = len(gram)
    centre = np.eye(n) - 1.0 / n
    sym = centre @ ((gram + gram.T) / 2) @ centre
    values, vectors = np.linalg.eigh(sym)
    return (vectors * np.maximum(values, 0.0)) @ vectors.T


def triplet_margins(gram: np.ndarray, triplets: np.ndarray) -> np.ndarray:
    """d(r, f) - d(r, c) per triplet: positive when the embedding agrees with the answer."""
    r, c, f = np.asarray(triplets).T
    diag = np.diag(gram)
    return diag[f] - diag[c] - 2 * gram[r, f] + 2 * gram[r, c]


def triplet_error(gram: np.ndarray, triplets: np.ndarray, weights: np.ndarray | None = None) -> float:
    """Weighted fraction of triplets the embedding gets wrong; ties count half.

    A margin below TIE_MARGIN (in the SDP's unit margin) is a tie: the embedding does not decide it.
    """
    margins = triplet_margins(gram, triplets)
    wrong = np.where(np.abs(margins) <= TIE_MARGIN, 0.5, (margins < 0).astype(float))
    weights = np.ones(len(margins)) if weights is None else np.asarray(weights, dtype=float)
    return float(np.sum(weights * wrong) / np.sum(weights))


def oriented(coordinate: np.ndarray, roughest: int | None = None) -> np.ndarray:
    """The 1-D coordinate with a fixed sign: ``roughest`` positive, else the largest |value| positive."""
    pivot = roughest if roughest is not None else int(np.argmax(np.abs(coordinate)))
    return -coordinate if coordinate[pivot] < 0 else coordinate


def aligned(coordinate: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``coordinate`` with the sign that agrees best with ``reference`` (bootstrap resamples)."""
    return -coordinate if float(coordinate @ reference) < 0 else coordinate

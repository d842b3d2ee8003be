"""Constrained linear elasticity solves: AMG-preconditioned CG with a reusable hierarchy.

A solve prescribes some degrees of freedom. The system keeps its
smoothed-aggregation hierarchy (pyamg) across solves and rebuilds it only when the set
of prescribed DOFs has drifted or CG needed clearly more iterations than on a fresh
hierarchy, so that a contact loop pays the set-up cost about once per texture.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pyamg
import scipy.sparse as sp
import scipy.sparse.linalg as sla


class SolverError(RuntimeError):
    """The linear solver did not reach its tolerance."""


@dataclass
class SolveStats:
    """Counters for the benchmark: seconds are filled in by the caller."""

    setups: int = 0
    solves: int = 0
    cg_iterations: int = 0
    history: list[int] = field(default_factory=list)


class ConstrainedSystem:
    """K u = f with u prescribed on a subset of DOFs."""

    def __init__(
        self,
        stiffness: sp.csr_matrix,
        near_null: np.ndarray,
        rtol: float = 1e-6,
        maxiter: int = 2000,
        rebuild_drift: float = 0.01,
    ) -> None:
        self.k = stiffness.tocsr()
        self.near_null = near_null
        self.rtol = rtol
        self.maxiter = maxiter
        self.rebuild_drift = rebuild_drift
        self.stats = SolveStats()
        self._amg = None
        self._amg_fixed: np.ndarray | None = None
        self._fresh_iterations = 0
        self._matrix: sp.csr_matrix | None = None

    def set_constraints(self, fixed: np.ndarray) -> None:
        """Prescribe the DOFs in the boolean mask ``fixed``."""
        self.fixed = fixed
        keep = sp.diags((~fixed).astype(float))
        # Prescribed rows keep their stiffness diagonal (not 1): a hierarchy built for a
        # slightly different set then stays well scaled on the DOFs that changed.
        self._diag = np.where(fixed, self.k.diagonal(), 0.0)
        self._matrix = (keep @ self.k @ keep + sp.diags(self._diag)).tocsr()
        drift = 0 if self._amg_fixed is None else int(np.count_nonzero(fixed != self._amg_fixed))
        if self._amg is None or drift > self.rebuild_drift * len(fixed):
            self._build()

    def _build(self) -> None:
        self._amg = pyamg.smoothed_aggregation_solver(self._matrix, B=self.near_null, symmetry="symmetric")
        self._amg_fixed = self.fixed.copy()
        self._fresh_iterations = 0
        self.stats.setups += 1

    def solve(
        self, values: np.ndarray, load: np.ndarray | None = None, x0: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Displacements u (mm) and reactions K u - f (N) for prescribed ``values`` (mm).

        ``values`` is read where fixed; ``load`` holds external nodal forces f (N);
        ``x0`` is a warm start.
        """
        fixed = self.fixed
        vp = np.where(fixed, values, 0.0)
        f = np.zeros_like(vp) if load is None else load
        b = np.where(fixed, self._diag * vp, f - self.k @ vp)
        u = self._cg(b, None if x0 is None else np.where(fixed, vp, x0))
        if self._fresh_iterations and self.stats.history[-1] > 2 * self._fresh_iterations + 5:
            self._build()
        return u, self.k @ u - f

    def _cg(self, b: np.ndarray, x0: np.ndarray | None) -> np.ndarray:
        count = [0]

        def tick(_: np.ndarray) -> None:
            count[0] += 1

        m = self._amg.aspreconditioner(cycle="V")
        atol = self.rtol * float(np.linalg.norm(b))
        x, info = sla.cg(self._matrix, b, x0=x0, M=m, rtol=0.0, atol=atol, maxiter=self.maxiter, callback=tick)
        self.stats.solves += 1
        self.stats.cg_iterations += count[0]
        self.stats.history.append(count[0])
        if not self._fresh_iterations:
            self._fresh_iterations = count[0]
        if info != 0 or not np.all(np.isfinite(x)):
            res = np.linalg.norm(b - self._matrix @ x) / max(np.linalg.norm(b), 1e-300)
            raise SolverError(
                f"CG did not converge in {self.maxiter} iterations (relative residual {res:.2e}); "
                "the system is ill-conditioned (Poisson ratio close to 0.5 with P1 elements? try --element p2)"
            )
        return x

"""Constrained linear elasticity solves: AMG-preconditioned CG with a reusable hierarchy.

``constrain(stiffness, fixed, amg)`` returns a new ``ConstrainedSystem`` for one set of
prescribed degrees of freedom (like scikit-fem's ``condense``, but keeping the full size so
reactions come for free; a system for a contact set that differs in a few nodes is the last
one updated in their rows and columns). The smoothed-aggregation hierarchy (pyamg) lives in an explicit
``AMGCache`` passed to every system of the same stiffness matrix: it is rebuilt only when the
prescribed set has drifted or CG needed clearly more iterations than on a fresh hierarchy, so
that a contact loop pays the set-up cost about once per texture. A contact loop works on its own
``AMGCache.fork()`` of a starting state, so that what it rebuilds never reaches another solve: a
texture's answer does not depend on which textures were solved before, or in other threads. A
hierarchy is a function of its matrix alone (``_hierarchy`` seeds pyamg's random start vectors).

``solve_plate`` adds one unknown, the displacement of a rigid plate (the bone) loaded by a
force: the contact loop's force control in one solve per round instead of two (texture gaps
with the bone held, then a unit bone displacement, combined). Its extra row is preconditioned
by the plate's stiffness; the plate's motion is extended into the block by an earlier free
response, so the coupling to the free DOFs is small and CG needs about the iterations of one
held solve.

CG runs in float64; the preconditioner is one V-cycle of that hierarchy in float32
(``AMG_PRECISION``), applied directly to the levels (pyamg's own ``aspreconditioner`` also
computes two residuals per call that CG does not use). Halving the bytes the cycle reads is
what makes it faster: it is memory-bound. Single-precision rounding in the preconditioner
changes the CG iterates, not what CG converges to: the stopping test is on the float64
residual, so the answers agree to the CG tolerance.
"""
from __future__ import annotations

import copy
import threading
from dataclasses import dataclass, field, replace

import numpy as np
import pyamg
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from pyamg.relaxation.smoothing import change_smoothers

CG_RTOL = 1e-6  # relative residual |b - A u| / |b| at which CG stops
CG_MAXITER = 2000
AMG_PRECISION = np.float32  # arithmetic of the preconditioner's V-cycle (CG itself is float64)
SMOOTHER = ("block_gauss_seidel", {"sweep": "symmetric"})  # pyamg's default for smoothed aggregation
AMG_SEED = 0  # numpy's global generator is seeded with this for every hierarchy set-up (see _hierarchy)
_GLOBAL_RANDOM = threading.Lock()  # held while the global generator is seeded


class SolverError(RuntimeError):
    """The linear solver did not reach its tolerance."""


class VCycle:
    """One V-cycle of a pyamg multilevel hierarchy in ``dtype``: ``cycle(b)`` ~ A^-1 b, a fixed linear map.

    Copies the hierarchy's operators to ``dtype`` and sets up its smoothers for them; the
    coarsest level is solved with its pseudo-inverse (as pyamg's default ``pinv`` coarse solver).
    """

    def __init__(self, hierarchy: pyamg.multilevel.MultilevelSolver, dtype: type = AMG_PRECISION,
                 smoother: tuple = SMOOTHER) -> None:
        self.dtype = dtype
        levels = hierarchy.levels
        for level in levels:
            level.A = _cast(level.A, dtype)
            if hasattr(level, "P"):
                level.P, level.R = _cast(level.P, dtype), _cast(level.R, dtype)
        change_smoothers(hierarchy, smoother, smoother)
        self.levels = levels[:-1]
        self.coarse = np.linalg.pinv(levels[-1].A.toarray().astype(float)).astype(dtype)

    def __call__(self, b: np.ndarray) -> np.ndarray:
        b = b.astype(self.dtype)
        return (self._cycle(0, b) if self.levels else self.coarse @ b).astype(float)  # one level: solved directly

    def _cycle(self, i: int, b: np.ndarray) -> np.ndarray:
        level = self.levels[i]
        x = np.zeros_like(b)
        level.presmoother(level.A, x, b)
        coarse_b = level.R @ (b - level.A @ x)
        coarse_x = self.coarse @ coarse_b if i == len(self.levels) - 1 else self._cycle(i + 1, coarse_b)
        x += level.P @ coarse_x
        level.postsmoother(level.A, x, b)
        return x


def _hierarchy(matrix: sp.csr_matrix, near_null: np.ndarray) -> pyamg.multilevel.MultilevelSolver:
    """pyamg's smoothed-aggregation hierarchy of ``matrix``, the same every time for the same matrix.

    pyamg starts the spectral-radius estimates of its prolongation smoothing from random vectors of
    numpy's global generator, so a hierarchy (and, within the CG tolerance, every answer) depended
    on how much of that stream earlier set-ups, or other threads, had drawn. The generator is seeded
    with ``AMG_SEED`` for the set-up under a lock, and its state restored afterwards; code of other
    threads that draws from the global generator meanwhile would still interfere (none here does).
    """
    with _GLOBAL_RANDOM:
        state = np.random.get_state()
        np.random.seed(AMG_SEED)
        try:
            return pyamg.smoothed_aggregation_solver(matrix, B=near_null, symmetry="symmetric")
        finally:
            np.random.set_state(state)


def _cast(matrix: sp.csr_matrix | sp.bsr_matrix, dtype: type) -> sp.csr_matrix | sp.bsr_matrix:
    """``matrix`` with its values in ``dtype``, sharing its index arrays (scipy's ``astype`` first
    re-sums duplicate entries, which pyamg's products do not have, at the cost of a sort)."""
    return type(matrix)((matrix.data.astype(dtype), matrix.indices, matrix.indptr), shape=matrix.shape)


@dataclass
class AMGCache:
    """The smoothed-aggregation hierarchy shared by the constrained systems of one stiffness matrix.

    Reuse policy: a new system rebuilds it when its prescribed set differs from the one the
    hierarchy was built for in more than ``rebuild_drift`` of the DOFs; a solve rebuilds it when
    CG took more than ``slow_factor`` x (iterations on the fresh hierarchy) + ``slow_margin``.
    ``precision``: the V-cycle's float type. Not thread-safe: each contact loop works on a ``fork``.
    """

    near_null: np.ndarray
    rebuild_drift: float = 0.01
    slow_factor: float = 2.0
    slow_margin: int = 5
    precision: type = AMG_PRECISION
    hierarchy: VCycle | None = field(default=None, repr=False)
    built_for: np.ndarray | None = field(default=None, repr=False)
    fresh_iterations: int = 0
    setups: int = 0
    layout: _Layout | None = field(default=None, repr=False)

    def fork(self) -> AMGCache:
        """An independent copy that starts from this state: it shares the built hierarchy and the matrix
        layout (neither is changed once made) and replaces them on its own when it rebuilds."""
        return replace(self, layout=copy.copy(self.layout))

    def fits(self, fixed: np.ndarray) -> bool:
        """True if the hierarchy exists and was built for a prescribed set close to ``fixed``."""
        if self.hierarchy is None:
            return False
        return np.count_nonzero(fixed != self.built_for) <= self.rebuild_drift * len(fixed)

    def build(self, matrix: sp.csr_matrix, fixed: np.ndarray) -> None:
        compact = matrix.copy()  # without the stored zeros of prescribed rows and columns (and own indices)
        compact.eliminate_zeros()
        self.hierarchy = VCycle(_hierarchy(compact, self.near_null), self.precision)
        self.built_for = fixed.copy()
        self.fresh_iterations = 0
        self.setups += 1

    def too_slow(self, iterations: int) -> bool:
        """Record a solve's CG iterations; True if the hierarchy has gone stale."""
        if not self.fresh_iterations:
            self.fresh_iterations = iterations
            return False
        return iterations > self.slow_factor * self.fresh_iterations + self.slow_margin

    def layout_of(self, stiffness: sp.csr_matrix) -> _Layout:
        """Row index and diagonal positions of ``stiffness``'s entries, computed once per matrix."""
        if self.layout is None or self.layout.stiffness is not stiffness:
            self.layout = _Layout(stiffness)
        return self.layout


class _Layout:
    """Where the entries of a CSR matrix sit: their rows, the diagonal, and each entry's transpose.

    ``constrained`` returns the stiffness with the rows and columns of prescribed DOFs zeroed but
    for their diagonal, keeping the stiffness's sparsity (zeros stored, index arrays shared): a
    contact round that changes a few nodes then updates only their rows and columns of the last
    matrix instead of masking every entry (at ``fine``, 0.18 s per round before).
    """

    # above this share of changed DOFs, the matrix is masked afresh instead of updated
    UPDATE_LIMIT = 0.05

    def __init__(self, stiffness: sp.csr_matrix) -> None:
        if not stiffness.has_sorted_indices:
            raise ValueError("the stiffness matrix needs sorted column indices")
        self.stiffness = stiffness
        index = np.int32 if stiffness.nnz < 2**31 else np.int64
        self.rows = np.repeat(np.arange(stiffness.shape[0], dtype=index), np.diff(stiffness.indptr))
        self.diagonal = np.flatnonzero(self.rows == stiffness.indices)
        if len(self.diagonal) != stiffness.shape[0]:
            raise ValueError("the stiffness matrix has a row without a stored diagonal entry")
        self.diagonal_values = stiffness.data[self.diagonal]
        # position of entry (j, i) for each entry (i, j): in CSC order the entries come in the CSR
        # order of their transposes, as the structure is symmetric (checked)
        positions = sp.csr_matrix((np.arange(stiffness.nnz, dtype=float), stiffness.indices, stiffness.indptr),
                                  shape=stiffness.shape).tocsc()
        positions.sort_indices()
        self.transpose = positions.data.astype(index)
        if not (np.array_equal(positions.indptr, stiffness.indptr)
                and np.array_equal(stiffness.indices[self.transpose], self.rows)):
            raise ValueError("the stiffness matrix is not structurally symmetric")
        self._last: tuple[np.ndarray, np.ndarray] | None = None  # (fixed, data) of the last matrix

    def constrained(self, fixed: np.ndarray) -> sp.csr_matrix:
        """The stiffness with the rows and columns of ``fixed`` zeroed except their diagonal entries."""
        k = self.stiffness
        changed = None if self._last is None else np.flatnonzero(fixed != self._last[0])
        if changed is None or len(changed) > self.UPDATE_LIMIT * len(fixed):
            data = np.where(fixed[self.rows] | fixed[k.indices], 0.0, k.data)
            data[self.diagonal] = self.diagonal_values
        else:
            data = self._last[1].copy()
            starts, lengths = k.indptr[changed], np.diff(k.indptr)[changed]
            before = np.cumsum(lengths) - lengths  # entries of the earlier changed rows
            in_rows = np.arange(lengths.sum()) + np.repeat(starts - before, lengths)
            touched = np.concatenate([in_rows, self.transpose[in_rows]])
            data[touched] = np.where(fixed[self.rows[touched]] | fixed[k.indices[touched]], 0.0, k.data[touched])
            data[self.diagonal[changed]] = self.diagonal_values[changed]
        self._last = (fixed.copy(), data)
        matrix = sp.csr_matrix((data, k.indices, k.indptr), shape=k.shape, copy=False)
        matrix.has_sorted_indices = True
        return matrix


@dataclass(frozen=True)
class LinearSolution:
    """Displacements u (mm), reactions K u - f (N), CG iterations and the achieved relative residual;
    ``plate_mm``: the plate's displacement d of a ``solve_plate`` solve."""

    u: np.ndarray
    reaction: np.ndarray
    iterations: int
    residual: float
    plate_mm: float = 0.0


class ConstrainedSystem:
    """K u = f with u prescribed on the DOFs of the boolean mask ``fixed``; build with ``constrain``."""

    def __init__(self, stiffness: sp.csr_matrix, fixed: np.ndarray, amg: AMGCache,
                 rtol: float = CG_RTOL, maxiter: int = CG_MAXITER) -> None:
        self.k = stiffness
        self.fixed = fixed
        self.amg = amg
        self.rtol = rtol
        self.maxiter = maxiter
        # Prescribed rows keep their stiffness diagonal (not 1): a hierarchy built for a
        # slightly different set then stays well scaled on the DOFs that changed.
        layout = amg.layout_of(stiffness)
        self.diag = np.where(fixed, layout.diagonal_values, 0.0)
        self.matrix = layout.constrained(fixed)
        if not amg.fits(fixed):
            amg.build(self.matrix, fixed)

    def solve(self, values: np.ndarray, load: np.ndarray | None = None,
              x0: np.ndarray | None = None) -> LinearSolution:
        """Solution for prescribed ``values`` (mm, read where fixed), nodal forces ``load`` (N), warm start ``x0``."""
        fixed = self.fixed
        vp = np.where(fixed, values, 0.0)
        f = np.zeros_like(vp) if load is None else load
        b = np.where(fixed, self.diag * vp, f - self.k @ vp)
        norm_b = float(np.linalg.norm(b))
        m = sla.LinearOperator(self.matrix.shape, self.amg.hierarchy, dtype=float)
        u, iterations, residual = self._cg(self.matrix, b, None if x0 is None else np.where(fixed, vp, x0), m, norm_b)
        if self.amg.too_slow(iterations):
            self.amg.build(self.matrix, fixed)
        # The preconditioner couples prescribed and free DOFs, so CG honours prescribed values only to its
        # tolerance (~1e-5 mm); on a steep texture wall that lateral error becomes a height mismatch of
        # ~2e-4 mm, beyond the contact's gap tolerance. Prescribed DOFs are therefore set exactly.
        u = np.where(fixed, vp, u)
        return LinearSolution(u, self.k @ u - f, iterations, residual)

    def solve_plate(self, values: np.ndarray, plate: np.ndarray, force: float,
                    x0: np.ndarray | None = None, rtol: float | None = None) -> LinearSolution:
        """Prescribed DOFs at ``values`` + d ``plate`` (mm), with the plate displacement d such that the
        plate's force ``plate`` . (K u) is ``force`` (N): a force-controlled rigid plate in one solve.

        ``plate`` is the plate's unit motion on the prescribed DOFs; on the free DOFs it is any
        extension of it (the closer to the free response, e.g. an earlier solve's, the better the
        preconditioner). The unknowns are the free DOFs and d: an SPD system of one more row, CG
        preconditioned by the V-cycle on the free block and the plate's stiffness on d. ``x0``: warm
        start displacements (mm), ``plate_mm`` of the result is d.
        """
        fixed, n = self.fixed, len(self.fixed)
        vp = np.where(fixed, values, 0.0)
        k_plate = self.k @ plate
        coupling = np.where(fixed, 0.0, k_plate)
        stiffness = float(plate @ k_plate)
        k_vp = self.k @ vp
        b = np.append(np.where(fixed, 0.0, -k_vp), force - plate @ k_vp)
        # Stop at the scale of ``solve``'s right-hand side, which carries the prescribed values too.
        norm_b = float(np.hypot(np.linalg.norm(b), np.linalg.norm(self.diag * vp)))

        def matvec(v: np.ndarray) -> np.ndarray:
            return np.append(self.matrix @ v[:n] + coupling * v[n], coupling @ v[:n] + stiffness * v[n])

        def precondition(r: np.ndarray) -> np.ndarray:
            return np.append(self.amg.hierarchy(r[:n]), r[n] / stiffness)

        a = sla.LinearOperator((n + 1, n + 1), matvec, dtype=float)
        m = sla.LinearOperator((n + 1, n + 1), precondition, dtype=float)
        start = None
        if x0 is not None:
            d0 = float(np.median(x0[fixed & (plate != 0)] / plate[fixed & (plate != 0)]))
            start = np.append(np.where(fixed, 0.0, x0 - vp - d0 * plate), d0)
        z, iterations, residual = self._cg(a, b, start, m, norm_b, rtol)
        if rtol is None and self.amg.too_slow(iterations):
            self.amg.build(self.matrix, fixed)
        d = float(z[n])
        u = vp + d * plate + np.where(fixed, 0.0, z[:n])
        return LinearSolution(u, self.k @ u, iterations, residual, d)

    def _cg(self, a, b: np.ndarray, x0: np.ndarray | None, m: sla.LinearOperator,
            norm_b: float, rtol: float | None = None) -> tuple[np.ndarray, int, float]:
        count = 0

        def tick(_: np.ndarray) -> None:
            nonlocal count
            count += 1

        norm_b = max(norm_b, 1e-300)
        x, info = sla.cg(a, b, x0=x0, M=m, rtol=0.0, atol=(rtol or self.rtol) * norm_b, maxiter=self.maxiter,
                         callback=tick)
        residual = float(np.linalg.norm(b - a @ x)) / norm_b
        if info != 0 or not np.all(np.isfinite(x)):
            raise SolverError(
                f"CG did not converge in {self.maxiter} iterations (relative residual {residual:.2e}); "
                "the system is ill-conditioned (Poisson ratio close to 0.5 with P1 elements? try element=\"p2\")"
            )
        return x, count, residual


def constrain(stiffness: sp.csr_matrix, fixed: np.ndarray, amg: AMGCache, rtol: float = CG_RTOL,
              maxiter: int = CG_MAXITER) -> ConstrainedSystem:
    """The system of ``stiffness`` with the DOFs in ``fixed`` prescribed, preconditioned from ``amg``."""
    return ConstrainedSystem(stiffness.tocsr(), fixed, amg, rtol, maxiter)

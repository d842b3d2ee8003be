"""Force-controlled contact of the skin block on a rigid texture: a primal-dual active-set solve.

The contact conditions on every contact-face node, with gap g = u_z - H (mm) and nodal contact
pressure p (MPa, compressive positive) from the nodal z reactions r (``ContactFace.pressure``:
r / area with P1; with P2 the pressure in a modified quadratic basis, simulate/face.py):

    no penetration  g >= -GAP_TOL_MM
    no tension      p >= -tension_tol, tension_tol = TENSION_TOL x (force / face area)
    complementarity p = 0 off contact (free nodes), g = 0 on contact (to GAP_TOL_MM)

Contact nodes stick (u_x = u_y = 0) or slide (frictionless, in the small-slope model of
rough-surface contact: the texture pushes along z only, u_z = H(x + u_x, y + u_y) - z0,
iterated as the nodes slide). With stick, a node can have no consistent state at the edge of
contact on a slope: held at its undeformed x, y it pulls; released, it moves sideways into the
texture. Such a node (released under tension ``RESTICK_AFTER_RELEASES`` times) sticks where
it touches when it is added again: u_x, u_y are held at its free lateral displacement and
u_z at the texture height there. ``ContactCheck.restuck_nodes`` counts them.

With P2 elements the pressure that decides tension matters: recovered as M^-1 r with the face
mass matrix (as in the first version of this solve) it oscillates in sign at the edge of contact,
so a mid-side node with a compressive reaction looked under tension, and the set cycled between
two states neither of which satisfied both conditions (Hertz sphere, nu 0.499, h 0.9 mm: two
mid-side nodes swapped for 24 rounds). studies/results/contact_partial.md (part 3) has the
measured choice.

Each round is one semismooth Newton step on these conditions (a primal-dual active-set
step; the problem is linear for a fixed contact set): one solve of the linear problem for the
current set with the bone as a force-controlled rigid plate (``ConstrainedSystem.solve_plate``:
the texture gaps prescribed, the bone's displacement one more unknown, its force the load),
so that the total contact reaction equals the force; then release contact
nodes under tension beyond the tolerance and add free nodes that penetrate beyond it.
Rounds solve to a loose CG tolerance (``SETTLE_RTOL``) until the set settles; a settled set is
then confirmed by one more round solved to the full tolerance, which decides success.
Safeguard against cycling: once a contact set recurs (or a node has changed state
``DAMP_AFTER_FLIPS`` times) the step is damped: only the nodes whose violation is at least
``DAMPING`` times the largest (tension and penetration in units of their tolerances, over both)
change state, which leaves a cycle's path (no case measured in studies/results/contact_partial.md
needed it). Termination is guaranteed by ``max_rounds``:
the loop ends when every condition holds (``success``) or after ``max_rounds`` rounds
(``success`` false, and the result says what is left: nodes, largest penetration, largest
tension and the tensile force as a fraction of the applied force).

``solve_contact`` returns a ``ContactResult`` (like scipy.optimize's OptimizeResult: success,
message, iteration counts) and calls an optional ``callback`` with a ``ContactRound`` after
every round. ``check_contact`` measures the conditions on any state. Between rounds the loop is a
``LoopState`` (active set, iterate, record); a round is ``_solve_round`` (a ``RoundSolve``), then
``_changes``, ``_record`` (with the damping) and ``_advance``, each a new value, nothing changed in place.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from .face import ContactFace
from .linsolve import CG_RTOL, AMGCache, ConstrainedSystem, constrain

# height(x, y) -> texture height (mm) relative to the undeformed contact face, block coordinates (mm)
Surface = Callable[[np.ndarray, np.ndarray], np.ndarray]

# Tolerances of the contact conditions. The displacements of a CG solve at CG_RTOL = 1e-6 are
# good to about 1e-5 mm and the recovered pressures to about 1e-6 MPa (measured on coarse
# blocks at 0.1-2 N), so the tolerances sit an order of magnitude above that noise.
GAP_TOL_MM = 1e-4  # largest penetration of any node, and height mismatch of a (sliding) contact node
TENSION_TOL = 1e-2  # largest tension at a contact node, as a fraction of the mean pressure force / face area
RESTICK_AFTER_RELEASES = 1  # stick: a node released this often sticks where it touches when added again
DAMP_AFTER_FLIPS = 8  # a node changing state this often (or a recurring contact set) switches damping on
DAMPING = 0.5  # damped step: only nodes whose violation is at least this share of the largest change
# CG tolerance of the rounds before the contact set settles: they only decide which nodes change
# state. Once a set survives such a round, one solve to the full tolerance (``rtol``) confirms it.
# 1e-4 halves the CG iterations of a warm default texture and changes V by at most 1e-5
# relative (1e-3: more rounds, as the confirming solve then finds changes; README, Performance).
SETTLE_RTOL = 1e-4


class ContactError(RuntimeError):
    """The contact problem has no answer (e.g. nothing touches the skin)."""


@dataclass(frozen=True)
class ContactCheck:
    """How far a contact state is from satisfying the contact conditions (mm, MPa, N).

    ``tension_nodes``: contact nodes with pressure below -``tension_tol_mpa``;
    ``penetrating_nodes``: free nodes deeper than ``gap_tol_mm`` into the texture;
    ``mismatched_nodes``: contact nodes off the texture height by more than ``gap_tol_mm``
    (frictionless nodes that have slid); ``tension_n``: the total tensile force of all
    contact nodes (pressure x nodal area), ``tension_fraction`` that force over the applied force;
    ``restuck_nodes``: stick contact nodes held where they touched, not at their undeformed x, y
    (module docstring).
    """

    tension_nodes: int
    penetrating_nodes: int
    mismatched_nodes: int
    max_penetration_mm: float
    max_tension_mpa: float
    tension_n: float
    tension_fraction: float
    gap_tol_mm: float
    tension_tol_mpa: float
    restuck_nodes: int = 0

    @property
    def violations(self) -> int:
        """Nodes that violate a condition beyond its tolerance."""
        return self.tension_nodes + self.penetrating_nodes + self.mismatched_nodes

    @property
    def satisfied(self) -> bool:
        return self.violations == 0


@dataclass(frozen=True)
class ContactResult:
    """The converged (or last) state of the contact loop and what it cost.

    ``success``: every contact condition holds within tolerance (``check`` says what is left
    otherwise, ``message`` says why); ``unresolved``: nodes that still violate a condition;
    ``cycled``: a contact set recurred; ``damped_rounds``: rounds taken with the damped step;
    ``warm``: the displacements and the bone's unit motion extended into the block
    (``solve_plate``'s plate), to warm-start a related problem.
    """

    u: np.ndarray
    indentation_mm: float
    in_contact: np.ndarray
    normal_reaction: np.ndarray
    success: bool
    message: str
    rounds: int
    linear_solves: int
    cg_iterations: int
    amg_setups: int
    unresolved: int
    cycled: bool
    contact_history: list[int]
    max_penetration_mm: float
    max_tension_mpa: float
    warm: tuple[np.ndarray, np.ndarray] = field(repr=False)
    check: ContactCheck | None = None
    damped_rounds: int = 0


@dataclass(frozen=True)
class ContactRound:
    """Statistics of one round of the contact loop, passed to ``solve_contact``'s callback."""

    round: int
    in_contact: int
    released: int
    added: int
    cg_iterations: int
    amg_setups: int


@dataclass
class ContactProblem:
    """Texture-independent parts of the contact problem: the block's stiffness (N/mm), the AMG
    state its contact loops start from (each on a fork of it), the contact face (bottom) and the bone face (top),
    and the CG tolerances (relative residual): ``rtol`` of the solve that confirms a contact set,
    ``settle_rtol`` of the rounds before the set settles."""

    stiffness: sp.csr_matrix
    amg: AMGCache
    bottom: np.ndarray
    bottom_xy: np.ndarray
    top: np.ndarray
    n_dofs: int
    face: ContactFace
    rtol: float = CG_RTOL
    settle_rtol: float = SETTLE_RTOL

    def constraints(self, contact: np.ndarray, frictionless: bool | np.ndarray) -> np.ndarray:
        """Prescribed DOFs: the bone face, and z (sliding nodes: ``frictionless``, for all or per node)
        or x, y, z (sticking nodes) of contact nodes."""
        fixed = np.zeros(self.n_dofs, dtype=bool)
        for a in range(3):
            fixed[3 * self.top + a] = True
        fixed[3 * self.bottom[contact] + 2] = True
        stick = self.bottom[contact & ~np.asarray(frictionless, dtype=bool)]
        for a in (0, 1):
            fixed[3 * stick + a] = True
        return fixed


def tension_tolerance(problem: ContactProblem, force_n: float) -> float:
    """The largest admissible tension (MPa) at a contact node: TENSION_TOL x the mean pressure."""
    return TENSION_TOL * force_n / float(problem.face.area.sum())


def _penetration(problem: ContactProblem, surface: Surface, u: np.ndarray) -> np.ndarray:
    """Depth (mm) of each contact-face node below the texture at its deformed x, y (negative: a gap)."""
    disp = u.reshape(-1, 3)[problem.bottom]
    moved = problem.bottom_xy + disp[:, :2]
    return surface(moved[:, 0], moved[:, 1]) - disp[:, 2]


def check_contact(problem: ContactProblem, surface: Surface, force_n: float, u: np.ndarray,
                  in_contact: np.ndarray, normal_reaction: np.ndarray) -> ContactCheck:
    """The contact conditions measured on a state: displacements ``u`` (mm), contact set, z reactions (N)."""
    return _check(problem, force_n, in_contact, problem.face.pressure(normal_reaction),
                  _penetration(problem, surface, u))


def _check(problem: ContactProblem, force_n: float, contact: np.ndarray, pressure: np.ndarray,
           penetration: np.ndarray) -> ContactCheck:
    tol_p = tension_tolerance(problem, force_n)
    pulled = np.where(contact, np.maximum(-pressure, 0.0), 0.0)
    tension_n = float((pulled * problem.face.area).sum())
    return ContactCheck(
        tension_nodes=int(np.count_nonzero(pulled > tol_p)),
        penetrating_nodes=int(np.count_nonzero(~contact & (penetration > GAP_TOL_MM))),
        mismatched_nodes=int(np.count_nonzero(contact & (np.abs(penetration) > GAP_TOL_MM))),
        max_penetration_mm=float(max(0.0, penetration.max(initial=0.0))),
        max_tension_mpa=float(pulled.max(initial=0.0)),
        tension_n=tension_n,
        tension_fraction=tension_n / force_n,
        gap_tol_mm=GAP_TOL_MM,
        tension_tol_mpa=tol_p,
    )


def _damped(violation: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """The candidates whose (positive, scaled) violation is at least DAMPING x the largest."""
    if not candidates.any():
        return candidates
    return candidates & (violation >= DAMPING * violation[candidates].max())


@dataclass(frozen=True)
class LoopState:
    """The contact loop between rounds: the active set, the iterate the next round starts from, and the
    loop's record; each round makes a new one (``_record``, ``_advance``).

    Per contact-face node: ``contact`` (held on the texture), ``slides`` (slides when held: frictionless),
    ``lateral`` (n, 2; mm: the x, y displacement at which it meets the texture, the last one of a sliding node,
    where it touched for a restuck one), ``flips`` and ``releases`` (state changes, releases), ``restuck``
    (sticks where it touches). ``u``, ``plate``: the last displacements and the bone's unit motion (mm; None
    before the first solve); ``loose``: rounds still solve to ``settle_rtol``; ``history``: the contact-set size
    of each round; ``seen``: the contact sets met (packed bits); ``cycled``: one recurred; ``damping``: steps are
    damped from now on; ``damped_rounds``, ``linear_solves``, ``cg_iterations``: counts so far.
    """

    contact: np.ndarray
    slides: np.ndarray
    lateral: np.ndarray
    flips: np.ndarray
    releases: np.ndarray
    restuck: np.ndarray
    u: np.ndarray | None
    plate: np.ndarray | None
    loose: bool
    history: tuple[int, ...] = ()
    seen: frozenset[bytes] = frozenset()
    cycled: bool = False
    damping: bool = False
    damped_rounds: int = 0
    linear_solves: int = 0
    cg_iterations: int = 0


@dataclass(frozen=True)
class RoundSolve:
    """One round's solve for its contact set: displacements ``u`` and the bone's unit motion ``plate`` (mm),
    the bone's displacement (mm), z reactions of the contact nodes (N), their ``pressure`` (MPa), every node's
    ``penetration`` (mm, ``_penetration``), and the linear solves and CG iterations it took."""

    u: np.ndarray
    plate: np.ndarray
    indentation_mm: float
    normal_reaction: np.ndarray
    pressure: np.ndarray
    penetration: np.ndarray
    linear_solves: int
    cg_iterations: int


def solve_contact(problem: ContactProblem, surface: Surface, force_n: float, frictionless: bool = False,
                  initial: np.ndarray | None = None, max_rounds: int = 30,
                  warm: tuple[np.ndarray, np.ndarray] | None = None,
                  callback: Callable[[ContactRound], None] | None = None, amg: AMGCache | None = None) -> ContactResult:
    """Primal-dual active-set solve with force control; see the module docstring.

    ``initial``: starting contact set (default: every node); ``warm``: a related result's
    ``warm`` solutions; ``callback``: called with each round's ``ContactRound``; ``amg``: the AMG
    state the loop works on and leaves as it ended (e.g. a fork of a related solve's), default a fork
    of ``problem.amg``. Nothing shared is changed: solves of one problem may run in any order, in threads.
    """
    amg = problem.amg.fork() if amg is None else amg
    setups_before = amg.setups
    tol_p = tension_tolerance(problem, force_n)
    state = _start(problem, surface, frictionless, initial, warm)
    system = None
    for rounds in range(1, max_rounds + 1):
        round_setups = amg.setups
        system = _system(problem, problem.constraints(state.contact, state.slides), system, amg)
        solve = _solve_round(problem, surface, force_n, state, system)
        release, add, drift = _changes(state, solve, tol_p)
        state, release, add = _record(state, solve, release, add, tol_p)
        if callback is not None:
            callback(ContactRound(rounds, int(state.contact.sum()), int(release.sum()), int(add.sum()),
                                  solve.cg_iterations, amg.setups - round_setups))
        settled = not (release.any() or add.any() or drift)
        if settled and state.loose and rounds < max_rounds:
            # settled on inexact solves: confirm with a solve to the full tolerance
            state = replace(state, loose=False, seen=state.seen - {np.packbits(state.contact).tobytes()})
            continue
        if settled or rounds == max_rounds:
            break
        state = _advance(problem, state, release, add)
    return _result(problem, force_n, state, solve, rounds, max_rounds, amg.setups - setups_before)


def _start(problem: ContactProblem, surface: Surface, frictionless: bool, initial: np.ndarray | None,
           warm: tuple[np.ndarray, np.ndarray] | None) -> LoopState:
    """The loop before its first round: ``initial`` in contact (default every node; none: the node the texture
    is highest under), nothing moved or flipped, the iterate from ``warm``."""
    nb = len(problem.bottom)
    contact = np.ones(nb, dtype=bool) if initial is None else initial.copy()
    if not contact.any():
        contact[np.argmax(surface(*problem.bottom_xy.T))] = True
    u, plate = warm if warm is not None else (None, None)
    return LoopState(contact=contact, slides=np.full(nb, frictionless), lateral=np.zeros((nb, 2)),
                     flips=np.zeros(nb, dtype=int), releases=np.zeros(nb, dtype=int), restuck=np.zeros(nb, dtype=bool),
                     u=u, plate=plate, loose=problem.settle_rtol > problem.rtol)


def _system(problem: ContactProblem, fixed: np.ndarray, system: ConstrainedSystem | None,
            amg: AMGCache) -> ConstrainedSystem:
    """The constrained system for the prescribed DOFs ``fixed``: ``system`` again if they are its own
    (sliding rounds)."""
    if system is None or not np.array_equal(fixed, system.fixed):
        return constrain(problem.stiffness, fixed, amg, problem.rtol)
    return system


def _prescribed(problem: ContactProblem, surface: Surface, state: LoopState) -> np.ndarray:
    """Prescribed displacements (mm) of the contact nodes: z at the texture height where each meets it, and
    x, y of sticking nodes at their held lateral displacement."""
    contact, lateral = state.contact, state.lateral
    moved = problem.bottom_xy + lateral
    values = np.zeros(problem.n_dofs)
    values[3 * problem.bottom[contact] + 2] = surface(moved[contact, 0], moved[contact, 1])
    stick = contact & ~state.slides
    stuck = problem.bottom[stick]
    values[3 * stuck] = lateral[stick, 0]
    values[3 * stuck + 1] = lateral[stick, 1]
    return values


def _solve_round(problem: ContactProblem, surface: Surface, force_n: float, state: LoopState,
                 system: ConstrainedSystem) -> RoundSolve:
    """The linear problem for the state's contact set, with the bone a rigid plate loaded by ``force_n`` (N)
    (``ConstrainedSystem.solve_plate``), warm-started from the state's iterate."""
    unit = np.zeros(problem.n_dofs)
    unit[3 * problem.top + 2] = -1.0
    plate, solves, cg = state.plate, 1, 0
    if plate is None:  # the bone's unit motion, extended into the block by its free response
        first = system.solve(unit)
        plate, solves, cg = first.u, 2, first.iterations
    plate = np.where(system.fixed, unit, plate)
    solved = system.solve_plate(_prescribed(problem, surface, state), plate, force_n, x0=state.u,
                                rtol=problem.settle_rtol if state.loose else None)
    delta = solved.plate_mm
    if not delta > 0 or not np.isfinite(delta):
        raise ContactError("the skin does not touch the texture: no force can be transmitted")
    normal_reaction = np.where(state.contact, solved.reaction[3 * problem.bottom + 2], 0.0)
    return RoundSolve(solved.u, plate, float(delta), normal_reaction, problem.face.pressure(normal_reaction),
                      _penetration(problem, surface, solved.u), solves, cg + solved.iterations)


def _changes(state: LoopState, solve: RoundSolve, tol_p: float) -> tuple[np.ndarray, np.ndarray, bool]:
    """Contact nodes to release (tension beyond ``tol_p``, MPa), free nodes to add (penetrating beyond
    GAP_TOL_MM), and whether a sliding node has moved off the texture height (its prescribed height
    follows its new position)."""
    release = state.contact & (solve.pressure < -tol_p)
    add = ~state.contact & (solve.penetration > GAP_TOL_MM)
    drift = bool(np.any(np.abs(solve.penetration[state.contact & state.slides]) > GAP_TOL_MM))
    return release, add, drift


def _record(state: LoopState, solve: RoundSolve, release: np.ndarray, add: np.ndarray,
            tol_p: float) -> tuple[LoopState, np.ndarray, np.ndarray]:
    """The round on the loop's record (iterate, set size, recurrence, counts), and its ``release`` and ``add``,
    damped once a contact set has recurred or a node has flipped DAMP_AFTER_FLIPS times (module docstring)."""
    key = np.packbits(state.contact).tobytes()
    recurred = key in state.seen and bool(release.any() or add.any())
    damping = state.damping or recurred or bool(state.flips.max(initial=0) >= DAMP_AFTER_FLIPS)
    if damping:
        # Violations in units of their tolerances, so tension and penetration compare.
        scaled = np.where(state.contact, -solve.pressure / tol_p, solve.penetration / GAP_TOL_MM)
        keep = _damped(scaled, release | add)
        release, add = release & keep, add & keep
    recorded = replace(state, u=solve.u, plate=solve.plate, history=(*state.history, int(state.contact.sum())),
                       seen=state.seen | {key}, cycled=state.cycled or recurred, damping=damping,
                       damped_rounds=state.damped_rounds + int(damping),
                       linear_solves=state.linear_solves + solve.linear_solves,
                       cg_iterations=state.cg_iterations + solve.cg_iterations)
    return recorded, release, add


def _advance(problem: ContactProblem, state: LoopState, release: np.ndarray, add: np.ndarray) -> LoopState:
    """The next round's active set: ``release`` off the texture, ``add`` onto it. Sliding nodes, and stick nodes
    added after RESTICK_AFTER_RELEASES releases (they restick, module docstring), are held at their lateral
    displacement in the state's iterate."""
    restick = add & ~state.slides & (state.releases >= RESTICK_AFTER_RELEASES)
    lateral = np.where((state.slides | restick)[:, None], state.u.reshape(-1, 3)[problem.bottom, :2], state.lateral)
    return replace(state, contact=(state.contact & ~release) | add, lateral=lateral,
                   flips=state.flips + (release | add), releases=state.releases + release,
                   restuck=state.restuck | restick)


def _result(problem: ContactProblem, force_n: float, state: LoopState, solve: RoundSolve, rounds: int,
            max_rounds: int, amg_setups: int) -> ContactResult:
    """The loop's answer from its last state and round: the contact conditions measured on them."""
    check = replace(_check(problem, force_n, state.contact, solve.pressure, solve.penetration),
                    restuck_nodes=int(np.count_nonzero(state.contact & state.restuck)))
    return ContactResult(
        u=solve.u, indentation_mm=solve.indentation_mm, in_contact=state.contact,
        normal_reaction=solve.normal_reaction, success=check.satisfied, message=_message(check, rounds, max_rounds),
        rounds=rounds, linear_solves=state.linear_solves, cg_iterations=state.cg_iterations, amg_setups=amg_setups,
        unresolved=check.violations, cycled=state.cycled, contact_history=list(state.history),
        max_penetration_mm=check.max_penetration_mm, max_tension_mpa=check.max_tension_mpa,
        warm=(solve.u, solve.plate), check=check, damped_rounds=state.damped_rounds,
    )


def _message(check: ContactCheck, rounds: int, max_rounds: int) -> str:
    """Why the loop ended: the set settled, or what is left of the contact conditions after ``rounds``."""
    if check.satisfied:
        return "contact set settled"
    return (f"contact conditions not satisfied after {rounds} rounds"
            f"{' (max_rounds)' if rounds == max_rounds else ' (nothing left to release or add)'}: "
            f"{check.tension_nodes} "
            f"nodes in contact under tension (largest {check.max_tension_mpa:.2e} MPa, tensile force "
            f"{100 * check.tension_fraction:.2g}% of the load), {check.penetrating_nodes} free nodes "
            f"penetrating (largest {check.max_penetration_mm:.2e} mm)"
            + (f", {check.mismatched_nodes} sliding nodes off the texture" if check.mismatched_nodes else ""))

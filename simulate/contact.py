"""Force-controlled active-set contact of the skin block on a rigid texture.

Each round solves the linear problem for a fixed contact set, twice (texture gaps
with the bone held, and a unit bone displacement), and combines the two so that the
total contact reaction equals the force. Contact nodes stick (u_x = u_y = 0) or slide
(frictionless, in the small-slope model of rough-surface contact: the texture pushes
along z only, u_z = H(x + u_x, y + u_y) - z0, iterated as the nodes slide). Nodes whose
contact pressure pulls the skin toward the texture are released; free nodes that penetrate
the texture are added.
A node may change state at most ``MAX_FLIPS`` times; after that it is held in contact
(the state that cannot penetrate), so the loop terminates. It is also capped at
``max_rounds``. Nodes held with a tensile reaction, repeated contact sets (cycling)
and the largest remaining violations are reported, never hidden.

``solve_contact`` returns a ``ContactResult`` (like scipy.optimize's OptimizeResult: success,
message, iteration counts) and calls an optional ``callback`` with a ``ContactRound`` after
every round.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .face import ContactFace
from .linsolve import CG_RTOL, AMGCache, constrain

# height(x, y) -> texture height (mm) relative to the undeformed contact face, block coordinates (mm)
Surface = Callable[[np.ndarray, np.ndarray], np.ndarray]


MAX_FLIPS = 2
SLIDE_TOL_MM = 1e-4  # frictionless: largest height mismatch of a sliding contact node


class ContactError(RuntimeError):
    """The contact problem has no answer (e.g. nothing touches the skin)."""


@dataclass
class ContactResult:
    """The converged (or last) state of the contact loop and what it cost.

    ``success``: no node left to release or add (``message`` says why not); ``unresolved``:
    nodes that still violate contact (held in contact under tension, or penetrating);
    ``warm``: the texture and unit-bone solutions, to warm-start a related problem.
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
    hierarchy its constrained systems share, the contact face (bottom) and the bone face (top),
    and the CG tolerance (relative residual) of every linear solve."""

    stiffness: sp.csr_matrix
    amg: AMGCache
    bottom: np.ndarray
    bottom_xy: np.ndarray
    top: np.ndarray
    n_dofs: int
    face: ContactFace
    rtol: float = CG_RTOL

    def constraints(self, contact: np.ndarray, frictionless: bool) -> np.ndarray:
        """Prescribed DOFs: the bone face, and z (frictionless) or x, y, z (stick) of contact nodes."""
        fixed = np.zeros(self.n_dofs, dtype=bool)
        for a in range(3):
            fixed[3 * self.top + a] = True
        for a in (2,) if frictionless else (0, 1, 2):
            fixed[3 * self.bottom[contact] + a] = True
        return fixed


def solve_contact(
    problem: ContactProblem,
    surface: Surface,
    force_n: float,
    frictionless: bool = False,
    initial: np.ndarray | None = None,
    max_rounds: int = 30,
    warm: tuple[np.ndarray, np.ndarray] | None = None,
    callback: Callable[[ContactRound], None] | None = None,
) -> ContactResult:
    """Active-set loop with force control; see the module docstring.

    ``initial``: starting contact set (default: every node); ``warm``: a related result's
    ``warm`` solutions; ``callback``: called with each round's ``ContactRound``.
    """
    nb = len(problem.bottom)
    contact = np.ones(nb, dtype=bool) if initial is None else initial.copy()
    if not contact.any():
        contact[np.argmax(surface(*problem.bottom_xy.T))] = True
    lateral = np.zeros((nb, 2))
    flips = np.zeros(nb, dtype=int)
    tol_gap = 1e-6
    tol_pressure = 1e-4 * force_n / problem.face.area.sum()
    seen: set[bytes] = set()
    history: list[int] = []
    cycled = False
    solves = cg_iterations = 0
    setups_before = problem.amg.setups
    u_tex, u_unit = warm if warm is not None else (None, None)
    unit = np.zeros(problem.n_dofs)
    unit[3 * problem.top + 2] = -1.0
    for rounds in range(1, max_rounds + 1):
        round_setups = problem.amg.setups
        system = constrain(problem.stiffness, problem.constraints(contact, frictionless), problem.amg, problem.rtol)
        idx = problem.bottom[contact]
        moved = problem.bottom_xy + lateral
        values = np.zeros(problem.n_dofs)
        values[3 * idx + 2] = surface(moved[contact, 0], moved[contact, 1])
        tex = system.solve(values, x0=u_tex)
        unit_bone = system.solve(unit, x0=u_unit)
        u_tex, u_unit = tex.u, unit_bone.u
        solves += 2
        round_cg = tex.iterations + unit_bone.iterations
        cg_iterations += round_cg
        r_unit_z = unit_bone.reaction[3 * idx + 2].sum()
        if not r_unit_z > 0:
            raise ContactError("the skin does not touch the texture: no force can be transmitted")
        delta = (force_n - tex.reaction[3 * idx + 2].sum()) / r_unit_z
        u = u_tex + delta * u_unit
        normal_reaction = np.where(contact, (tex.reaction + delta * unit_bone.reaction)[3 * problem.bottom + 2], 0.0)
        pressure = problem.face.pressure(normal_reaction)
        disp = u.reshape(-1, 3)[problem.bottom]
        moved = problem.bottom_xy + disp[:, :2]
        penetration = surface(moved[:, 0], moved[:, 1]) - disp[:, 2]
        settled = flips >= MAX_FLIPS
        release = contact & ~settled & (pressure < -tol_pressure)
        add = ~contact & (penetration > tol_gap)
        # Frictionless nodes slide: their prescribed height follows their new position.
        drift = frictionless and bool(np.any(np.abs(penetration[contact]) > SLIDE_TOL_MM))
        history.append(int(contact.sum()))
        key = np.packbits(contact).tobytes()
        cycled |= key in seen and bool(release.any() or add.any())
        seen.add(key)
        if callback is not None:
            callback(ContactRound(rounds, int(contact.sum()), int(release.sum()), int(add.sum()), round_cg,
                                  problem.amg.setups - round_setups))
        if not (release.any() or add.any() or drift) or rounds == max_rounds:
            break
        lateral = disp[:, :2] if frictionless else lateral
        flips += release | add
        contact = (contact & ~release) | add
    success = not (release.any() or add.any() or drift)
    violated = (contact & (pressure < -tol_pressure)) | (~contact & (penetration > tol_gap))
    if success:
        message = "contact set settled"
    else:
        message = (f"contact set still changing after {rounds} rounds (max_rounds): {int(release.sum())} nodes "
                   f"to release, {int(add.sum())} to add" + ("; frictionless nodes still sliding" if drift else ""))
    return ContactResult(
        u=u,
        indentation_mm=float(delta),
        in_contact=contact,
        normal_reaction=normal_reaction,
        success=success,
        message=message,
        rounds=rounds,
        linear_solves=solves,
        cg_iterations=cg_iterations,
        amg_setups=problem.amg.setups - setups_before,
        unresolved=int(np.count_nonzero(violated)),
        cycled=cycled,
        contact_history=history,
        max_penetration_mm=float(max(0.0, penetration[~contact].max(initial=0.0))),
        max_tension_mpa=float(max(0.0, -pressure[contact].min(initial=0.0))),
        warm=(u_tex, u_unit),
    )

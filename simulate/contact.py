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
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .face import ContactFace
from .linsolve import ConstrainedSystem

# height(x, y) -> texture height (mm) relative to the undeformed contact face, block coordinates (mm)
Surface = Callable[[np.ndarray, np.ndarray], np.ndarray]


MAX_FLIPS = 2
SLIDE_TOL_MM = 1e-4  # frictionless: largest height mismatch of a sliding contact node


class ContactError(RuntimeError):
    """The contact problem has no answer (e.g. nothing touches the skin)."""


@dataclass
class ContactState:
    """The converged (or last) state of the contact loop."""

    u: np.ndarray
    indentation_mm: float
    in_contact: np.ndarray
    normal_reaction: np.ndarray
    rounds: int
    converged: bool
    unresolved: int
    cycled: bool
    contact_history: list[int] = field(default_factory=list)
    max_penetration_mm: float = 0.0
    max_tension_mpa: float = 0.0


@dataclass
class ContactProblem:
    """Texture-independent description of the contact face and the bone face."""

    system: ConstrainedSystem
    bottom: np.ndarray
    bottom_xy: np.ndarray
    top: np.ndarray
    n_dofs: int
    face: ContactFace

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
) -> tuple[ContactState, tuple[np.ndarray, np.ndarray]]:
    """Active-set loop with force control; see the module docstring.

    Returns the state and the two unit solutions, to warm-start a related problem.
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
    u_tex, u_unit = warm if warm is not None else (None, None)
    unit = np.zeros(problem.n_dofs)
    unit[3 * problem.top + 2] = -1.0
    for rounds in range(1, max_rounds + 1):
        problem.system.set_constraints(problem.constraints(contact, frictionless))
        idx = problem.bottom[contact]
        moved = problem.bottom_xy + lateral
        values = np.zeros(problem.n_dofs)
        values[3 * idx + 2] = surface(moved[contact, 0], moved[contact, 1])
        u_tex, r_tex = problem.system.solve(values, x0=u_tex)
        u_unit, r_unit = problem.system.solve(unit, x0=u_unit)
        r_unit_z = r_unit[3 * idx + 2].sum()
        if not r_unit_z > 0:
            raise ContactError("the skin does not touch the texture: no force can be transmitted")
        delta = (force_n - r_tex[3 * idx + 2].sum()) / r_unit_z
        u = u_tex + delta * u_unit
        normal_reaction = np.where(contact, (r_tex + delta * r_unit)[3 * problem.bottom + 2], 0.0)
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
        cycled |= key in seen and (release.any() or add.any())
        seen.add(key)
        if not (release.any() or add.any() or drift) or rounds == max_rounds:
            break
        lateral = disp[:, :2] if frictionless else lateral
        flips += release | add
        contact = (contact & ~release) | add
    violated = (contact & (pressure < -tol_pressure)) | (~contact & (penetration > tol_gap))
    return ContactState(
        u=u,
        indentation_mm=float(delta),
        in_contact=contact,
        normal_reaction=normal_reaction,
        rounds=rounds,
        converged=not (release.any() or add.any() or drift),
        unresolved=int(np.count_nonzero(violated)),
        cycled=cycled,
        contact_history=history,
        max_penetration_mm=float(max(0.0, penetration[~contact].max(initial=0.0))),
        max_tension_mpa=float(max(0.0, -pressure[contact].min(initial=0.0))),
    ), (u_tex, u_unit)

"""Force-controlled active-set contact of the skin block on a rigid texture.

Each round solves the linear problem for a fixed contact set, twice (texture gaps
with the bone held, and a unit bone displacement), and combines the two so that the
total contact reaction equals the force. Nodes whose normal reaction pulls the skin
toward the texture are released; free nodes that penetrate the texture are added.
A node may change state at most ``MAX_FLIPS`` times; after that it is held in contact
(the state that cannot penetrate), so the loop terminates. It is also capped at
``max_rounds``. Nodes held with a tensile reaction, repeated contact sets (cycling)
and the largest remaining violations are reported, never hidden.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .linsolve import ConstrainedSystem, nodal_rotation

# height(x, y) -> texture height (mm) relative to the undeformed contact face, and its gradient
Surface = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


MAX_FLIPS = 2


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
    max_tension_n: float = 0.0


@dataclass
class ContactProblem:
    """Texture-independent description of the contact face and the bone face."""

    system: ConstrainedSystem
    bottom: np.ndarray
    bottom_xy: np.ndarray
    top: np.ndarray
    n_dofs: int

    def _constraints(self, contact: np.ndarray, frictionless: bool, normals: np.ndarray | None):
        fixed = np.zeros(self.n_dofs, dtype=bool)
        for a in range(3):
            fixed[3 * self.top + a] = True
        nodes = self.bottom[contact]
        comps = (2,) if frictionless else (0, 1, 2)
        for a in comps:
            fixed[3 * nodes + a] = True
        rotation = nodal_rotation(self.n_dofs, nodes, normals[contact]) if frictionless else None
        return fixed, rotation


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
        contact[np.argmax(surface(*problem.bottom_xy.T)[0])] = True
    lateral = np.zeros((nb, 2))
    flips = np.zeros(nb, dtype=int)
    tol_gap = 1e-6
    tol_force = 1e-4 * force_n / nb
    seen: dict[bytes, int] = {}
    history: list[int] = []
    cycled = False
    u_tex, u_unit = warm if warm is not None else (None, None)
    for rounds in range(1, max_rounds + 1):
        xy = problem.bottom_xy + lateral
        height, grad = surface(xy[:, 0], xy[:, 1])
        normals = np.c_[-grad, np.ones(nb)] / np.sqrt(1 + (grad**2).sum(axis=1))[:, None]
        fixed, rotation = problem._constraints(contact, frictionless, normals)
        problem.system.set_constraints(fixed, rotation)
        values = np.zeros(problem.n_dofs)
        idx = problem.bottom[contact]
        if frictionless:
            n = normals[contact]
            values[3 * idx + 2] = n[:, 0] * lateral[contact, 0] + n[:, 1] * lateral[contact, 1] + n[:, 2] * height[contact]
        else:
            values[3 * idx + 2] = height[contact]
        u_tex, r_tex = problem.system.solve(values, x0=u_tex)
        unit = np.zeros(problem.n_dofs)
        unit[3 * problem.top + 2] = -1.0
        u_unit, r_unit = problem.system.solve(_local(unit, rotation), x0=u_unit)
        r_unit_z = r_unit[3 * idx + 2].sum()
        if not r_unit_z > 0:
            raise ContactError("the skin does not touch the texture: no force can be transmitted")
        delta = (force_n - r_tex[3 * idx + 2].sum()) / r_unit_z
        u = u_tex + delta * u_unit
        reaction = (r_tex + delta * r_unit).reshape(-1, 3)[problem.bottom]
        disp = u.reshape(-1, 3)[problem.bottom]
        normal_reaction = np.einsum("ij,ij->i", reaction, normals) if frictionless else reaction[:, 2]
        normal_reaction = np.where(contact, normal_reaction, 0.0)
        moved = problem.bottom_xy + disp[:, :2]
        penetration = surface(moved[:, 0], moved[:, 1])[0] - disp[:, 2]
        settled = flips >= MAX_FLIPS
        release = contact & ~settled & (normal_reaction < -tol_force)
        add = ~contact & (penetration > tol_gap)
        history.append(int(contact.sum()))
        key = np.packbits(contact).tobytes()
        cycled |= key in seen
        seen[key] = rounds
        lateral = disp[:, :2] if frictionless else lateral
        if not (release.any() or add.any()) or rounds == max_rounds:
            break
        flips += release | add
        contact = (contact & ~release) | add
    unresolved = int(np.count_nonzero((contact & (normal_reaction < -tol_force)) | (~contact & (penetration > tol_gap))))
    return ContactState(
        u=u,
        indentation_mm=float(delta),
        in_contact=contact,
        normal_reaction=normal_reaction,
        rounds=rounds,
        converged=not (release.any() or add.any()),
        unresolved=unresolved,
        cycled=cycled,
        contact_history=history,
        max_penetration_mm=float(max(0.0, penetration[~contact].max(initial=0.0))),
        max_tension_n=float(max(0.0, -normal_reaction[contact].min(initial=0.0))),
    ), (u_tex, u_unit)


def _local(values: np.ndarray, rotation) -> np.ndarray:
    """Global prescribed values expressed in the local frames (top nodes are unrotated)."""
    return values if rotation is None else rotation.T @ values

"""What the FEM model returns: ``Result`` with its ``Note``s and the mesh ``Level``s solved for it."""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.hashing import canonical_json
from roughness.core.reprs import short_repr, v_text

if TYPE_CHECKING:
    from .config import SimConfig
    from .contact import ContactCheck, ContactResult


@dataclass(frozen=True)
class Note:
    """A remark on how a result was obtained; ``unusual`` ones are worth a user's attention.

    Codes: ``indentation`` (deeper than the tissue: outside small strain, as in the paper's
    model; unusual beyond ``DEEP_INDENTATION_TISSUES``), ``not_converged`` (the contact
    conditions do not hold within tolerance: what is left), ``cycled`` (a contact set recurred,
    so the contact steps were damped; unusual if it did not converge), ``locking`` (P1 near
    incompressibility), ``unresolved_texture`` (features finer than the contact mesh), ``tolerance_not_met``
    (``converged`` stopped at its finest level above the tolerance), ``discretization_error_undefined`` (V is 0
    at this mesh but not at the coarser one: no relative error; written by ``Result.summary``).
    """

    code: str
    message: str
    unusual: bool


@dataclass(frozen=True)
class Level:
    """One solved rung: contact spacing (mm), element, V, its estimated relative error, contact
    rounds and seconds."""

    h_contact_mm: float
    element: str
    roughness: float
    discretization_error: float | None
    contact_rounds: int
    seconds: float


@dataclass(frozen=True)
class Result:
    """Roughness of one texture and how it was obtained (mm, N, s).

    ``iterations``: contact rounds; ``cg_iterations``, ``amg_setups``: linear-solver work of
    this texture's contact solve; ``converged``: every contact condition holds within tolerance,
    ``contact_check``: how far each is from holding (nodes, largest penetration and tension,
    tensile force as a fraction of the load); ``notes``: see ``Note``; ``discretization_error``: estimated
    relative error of V from the mesh (``simulate.discretization``), with ``ladder`` the levels
    solved for it (``Level``, the last one this result's). Built complete: ``simulate.converged`` adds
    the estimate to a level's result with ``dataclasses.replace``.
    """

    roughness: float
    roughness_stderr: float
    contact_fraction: float
    indentation_mm: float
    converged: bool
    iterations: int
    unresolved_nodes: int
    cycled: bool
    cg_iterations: int
    amg_setups: int
    nodes: int
    dofs: int
    seconds: float
    stage_seconds: dict[str, float]
    fluctuation: np.ndarray
    lambda3: np.ndarray
    grid_axis_mm: np.ndarray
    contact_history: list[int]
    notes: list[Note]
    config: SimConfig
    state: ContactResult | None = field(default=None, repr=False)
    discretization_error: float | None = None
    ladder: list[Level] = field(default_factory=list)
    contact_check: ContactCheck | None = None

    def __repr__(self) -> str:
        return short_repr(self, v_text(self.roughness, self.roughness_stderr), f"fem ({self.config.fidelity})",
                          "converged" if self.converged else "NOT converged", f"contact {self.contact_fraction:.2f}",
                          f"indentation {self.indentation_mm:.3g} mm", f"{self.nodes:,} nodes", f"{self.seconds:.2f} s",
                          f"{len(self.notes)} note(s)" if self.notes else "")

    def summary(self) -> dict:
        """The scalars, contact history, notes and main settings, as plain Python types (JSON-ready)."""
        keys = ("roughness", "roughness_stderr", "contact_fraction", "indentation_mm", "converged",
                "iterations", "cg_iterations", "amg_setups", "unresolved_nodes", "cycled", "nodes", "dofs",
                "seconds", "discretization_error")
        out = {k: getattr(self, k) for k in keys}
        notes = list(self.notes)
        ladder = [asdict(level) for level in self.ladder]
        if any(_undefined(x.get("discretization_error")) for x in [out, *ladder]):
            # relative to V = 0 (simulate.discretization.richardson): undefined, null rather than Infinity
            for x in (out, *ladder):
                x["discretization_error"] = None if _undefined(x["discretization_error"]) else x["discretization_error"]
            notes.append(Note("discretization_error_undefined", "V is 0 at a mesh but not at the next coarser one "
                              "(see ladder): its relative discretization error is undefined", unusual=False))
        out.update(stage_seconds={k: round(v, 4) for k, v in self.stage_seconds.items()},
                   contact_history=self.contact_history, notes=[asdict(n) for n in notes],
                   fidelity=self.config.fidelity, h_contact_mm=self.config.h_contact_mm,
                   force_n=self.config.force_n, poisson=self.config.poisson, contact=self.config.contact,
                   element=self.config.element, bone=self.config.bone, tolerance=self.config.tolerance,
                   ladder=ladder,
                   contact_check=None if self.contact_check is None else asdict(self.contact_check))
        if self.config.curvature_mm is not None:  # the curved base under the texture
            out.update(curvature_mm=self.config.curvature_mm, base=self.config.base,
                       curvature_axis=self.config.curvature_axis, texture_along=self.config.texture_along)
        return json.loads(canonical_json(out))  # numpy scalars and arrays become Python numbers and lists

    @property
    def unusual_notes(self) -> list[Note]:
        return [n for n in self.notes if n.unusual]


def _undefined(value: float | None) -> bool:
    return value is not None and not math.isfinite(value)

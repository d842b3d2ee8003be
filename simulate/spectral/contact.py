"""Contact of the layer's face with a rigid texture on the pixel grid, at a given mean pressure.

Unknowns are the face tractions on the skin (MPa per pixel): the normal pressure p >= 0 and, for
stick contact, the tangential tractions, which are free where the skin touches and zero where it
does not. The conditions, as in the FEM: no tension (p >= 0), no penetration (gap >= 0), gap = 0
where p > 0, and for stick no lateral displacement of the touching face. The mean of p is the
load. Full contact is tried first (the face takes the texture's shape: one linear response); if it
would need tension somewhere, partial contact is solved: frictionless by Polonsky & Keer's
constrained conjugate gradients (Wear 231, 1999), stick by an active set of touching pixels whose
every set is solved exactly, both preconditioned by the layer's stiffness.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .modes import EVEN, Modes

GAP_TOLERANCE = 1e-6  # relative to the texture's height range: largest penetration, mismatch and stick slip
TENSION_TOLERANCE = 1e-3  # relative to the mean pressure: largest tension of a touching pixel
SETTLE_TOLERANCE = 1e-4  # relative to the height range: the rounds' solves until the contact set holds
LOOSE_TENSION_TOLERANCE = 1e-2  # the FEM's (simulate/contact.py TENSION_TOL): taken if the contact set cycles
MAX_ITERATIONS = 500  # conjugate-gradient iterations per solve
MAX_ROUNDS = 50  # active-set rounds (stick)


@dataclass(frozen=True)
class ContactState:
    """The solved face: Fourier face displacements (3, ny, nx//2+1), real tractions (3, ny, nx) on
    the skin (MPa), and how well the contact conditions hold (like scipy.optimize results).

    ``offset_mm``: the face's rigid position, u_z - H on the contact set; ``max_penetration_mm`` and
    ``max_tension_mpa``: the largest violation of each condition; ``max_slip_mm``: the largest
    lateral displacement of a touching point under stick.
    """

    face: np.ndarray
    traction: np.ndarray
    in_contact: np.ndarray
    offset_mm: float
    success: bool
    message: str
    iterations: int
    max_penetration_mm: float
    max_tension_mpa: float
    max_slip_mm: float


def _uniform_face(modes: Modes, pressure_mpa: float) -> np.ndarray:
    """Fourier face displacements (3, ...) of the uniform load alone: the layer's uniform compression
    (the uniform mode's stiffness is diagonal, so the face does not slide, with friction or without)."""
    face = np.zeros((3,) + modes.stiffness.shape[:2], dtype=complex)
    face[2, 0, 0] = pressure_mpa * modes.uniform / modes.normal_stiffness[0, 0]
    return face


def full_contact(modes: Modes, heights: np.ndarray, pressure_mpa: float, frictionless: bool) -> ContactState:
    """The face in contact everywhere: it takes the shape of ``heights`` (mm)."""
    spectrum = modes.forward(heights[None], EVEN)[0]
    spectrum[0, 0] = 0.0
    face = modes.slid(spectrum) if frictionless else np.stack([np.zeros_like(spectrum)] * 2 + [spectrum])
    traction = modes.inverse(modes.traction(face))
    traction[2] += pressure_mpa
    face = face + _uniform_face(modes, pressure_mpa)
    offset = float(face[2, 0, 0].real / modes.uniform - heights.mean())
    tension = max(0.0, float(-traction[2].min()))
    holds = tension <= TENSION_TOLERANCE * pressure_mpa
    return ContactState(face, traction, np.ones(heights.shape, bool), offset, holds,
                        "full contact" if holds else "full contact would need tension", 0, 0.0, tension, 0.0)


def solve_contact(modes: Modes, heights: np.ndarray, pressure_mpa: float, frictionless: bool,
                  max_iterations: int = MAX_ITERATIONS) -> ContactState:
    """The face pressed onto ``heights`` (mm, the periodic domain) at mean pressure ``pressure_mpa``.

    Full contact if it needs no tension; else frictionless: Polonsky-Keer; stick: an active set of
    touching pixels, each set solved exactly (``_fixed_set``), pixels in tension released and
    penetrating ones added until the set holds (a set seen before ends the rounds, reported).
    """
    full = full_contact(modes, heights, pressure_mpa, frictionless)
    if full.success:
        return full
    load = pressure_mpa * heights.size
    relief = max(float(np.ptp(heights)), 1e-12)
    tolerance = GAP_TOLERANCE * relief
    if frictionless:
        traction, iterations = _polonsky_keer(modes, heights, full.traction, load, tolerance, max_iterations)
        return _checked(modes, heights, traction, traction[2] > 0, pressure_mpa, frictionless, iterations, tolerance)
    traction, mask = full.traction, full.traction[2] > 0
    seen, iterations, message, tension_tolerance = set(), 0, "", TENSION_TOLERANCE
    settling = SETTLE_TOLERANCE * relief
    precise = False  # rounds solve loosely until the set holds, then once to the full tolerance to confirm it
    for rounds in range(1, MAX_ROUNDS + 1):
        within = tolerance if precise else settling
        traction, gap, used = _fixed_set(modes, heights, mask, traction, load, within, max_iterations)
        iterations += used
        tensile = mask & (traction[2] < -tension_tolerance * pressure_mpa)
        penetrating = ~mask & (gap < -within)
        if not (tensile.any() or penetrating.any()):
            if precise:
                break
            precise = True
            continue
        seen.add(hash(mask.tobytes()))
        update = mask | penetrating if penetrating.any() else mask & ~tensile  # add first: release what holds no load
        if hash(update.tobytes()) in seen:  # edge pixels chatter between slight tension and slight penetration
            if tension_tolerance < LOOSE_TENSION_TOLERANCE:
                tension_tolerance = LOOSE_TENSION_TOLERANCE
                message = "the contact set cycled, so the FEM's tension tolerance (1% of the pressure) was taken"
                seen.clear()
                continue
            message = f"the contact set cycled after {rounds} rounds"
            break
        mask = update
    state = _checked(modes, heights, np.where(mask, traction, 0.0), mask, pressure_mpa, frictionless, iterations,
                     tolerance, tension_tolerance)
    return replace(state, message=f"{message}; {state.message}") if message else state


def _fixed_set(modes: Modes, heights: np.ndarray, mask: np.ndarray, traction: np.ndarray, load: float,
               tolerance: float, max_iterations: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Stick tractions on the contact set ``mask``: u_x = u_y = 0 and u_z - H constant there, the normal
    tractions summing to ``load``, zero elsewhere. Conjugate gradients preconditioned by the stiffness
    (exact for full contact), projected on the load constraint. Returns the tractions, the gap u_z - H
    less its mean on the set (mm) and the iterations."""
    m = mask.astype(float)
    count = m.sum()
    t = traction * m
    t[2] = t[2] + (load - t[2].sum()) / count * m
    direction, g_old = np.zeros_like(t), 0.0
    u = modes.stick_displacement(t)  # updated with each step, not recomputed
    for iteration in range(1, max_iterations + 1):
        residual = u.copy()
        residual[2] -= heights
        residual *= m
        residual[2] -= residual[2].sum() / count * m
        if np.abs(residual).max() <= tolerance:
            break
        precond = modes.stick_traction(residual) * m
        precond[2] -= precond[2].sum() / count * m
        norm = float(np.vdot(residual, precond))
        direction = precond + (norm / g_old if g_old else 0.0) * direction
        g_old = norm
        moved = modes.stick_displacement(direction)
        response = moved * m
        response[2] -= response[2].sum() / count * m
        step = float(np.vdot(residual, direction)) / float(np.vdot(response, direction))
        t = t - step * direction
        u -= step * moved
    gap = u[2] - heights
    return t, gap - gap[mask].mean(), iteration


def _polonsky_keer(modes: Modes, heights: np.ndarray, traction: np.ndarray, load: float, tolerance: float,
                   max_iterations: int) -> tuple[np.ndarray, int]:
    """Frictionless normal contact by Polonsky & Keer's constrained CG, preconditioned by the stiffness."""
    p = np.where(traction[2] > 0, traction[2], 0.0)
    p *= load / p.sum()
    direction, g_old, restart = np.zeros_like(p), 1.0, True

    def normal(field: np.ndarray) -> np.ndarray:
        spectrum = np.zeros((3,) + modes.stiffness.shape[:2], dtype=complex)
        spectrum[2] = modes.forward(field[None], EVEN)[0]
        return modes.inverse(modes.displacement(spectrum, True)[2:], EVEN)[0]

    for iteration in range(1, max_iterations + 1):
        mask = (p > 0).astype(float)
        count = mask.sum()
        gap = normal(p) - heights
        gap -= (gap * mask).sum() / count
        residual, outside = gap * mask, gap * (1 - mask)
        if max(float(np.abs(residual).max()), float(-outside.min())) <= tolerance:
            break
        precond = modes.inverse(modes.normal_stiffness * modes.forward(residual[None], EVEN), EVEN)[0] * mask
        precond -= precond.sum() / count * mask
        norm = float(np.vdot(residual, precond))
        direction = precond + (0.0 if restart else norm / g_old) * direction
        g_old = norm
        response = normal(direction) * mask
        response -= response.sum() / count * mask
        step = float(np.vdot(residual, direction)) / float(np.vdot(response, direction))
        p = p - step * direction
        p[p < 0] = 0.0
        entering = outside < 0
        p[entering] = -step * outside[entering]
        restart = bool(entering.any())
        p *= load / p.sum()
    out = np.zeros_like(traction)
    out[2] = p
    return out, iteration


def _checked(modes: Modes, heights: np.ndarray, traction: np.ndarray, touching: np.ndarray, pressure_mpa: float,
             frictionless: bool, iterations: int, tolerance: float,
             tension_tolerance: float = TENSION_TOLERANCE) -> ContactState:
    """The state for ``traction`` with the pixels ``touching``, each contact condition measured against
    ``tolerance`` (mm) and ``tension_tolerance`` (relative to the pressure)."""
    face = modes.displacement(modes.forward(traction), frictionless)
    u = modes.inverse(face)
    gap = u[2] - heights
    offset = float(gap[touching].mean())
    gap -= offset
    penetration = max(0.0, float(-gap[~touching].min())) if (~touching).any() else 0.0
    mismatch = float(np.abs(gap[touching]).max())
    slip = 0.0 if frictionless else float(np.abs(u[:2, touching]).max())
    tension = max(0.0, float(-traction[2].min()))
    worst = max(penetration, mismatch, slip)
    success = worst <= tolerance and tension <= tension_tolerance * pressure_mpa
    message = ("contact conditions hold" if success else
               f"contact conditions violated by up to {worst:.3g} mm after {iterations} iterations")
    return ContactState(face, traction, touching, offset, success, message, iterations,
                        max(penetration, mismatch), tension, slip)

"""Contact of the layer's face with a rigid texture on the pixel grid, at a given mean pressure.

Unknowns are the face tractions on the skin (MPa per pixel): the normal pressure p >= 0 and, for
stick contact, the tangential tractions, which are free where the skin touches and zero where it
does not. The conditions, as in the FEM: no tension (p >= 0), no penetration (gap >= 0), gap = 0
where p > 0, and for stick no lateral displacement of the touching face. The mean of p is the
load. Full contact is tried first (the face takes the texture's shape: one linear response); if it
would need tension somewhere, a constrained conjugate-gradient method of the Polonsky-Keer kind
(Polonsky & Keer 1999, Wear 231) solves the partial contact, with the stick tractions as extra
unconstrained unknowns on the contact set.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .modes import Modes

GAP_TOLERANCE = 1e-6  # relative to the texture's height range: contact conditions hold within this
STEP_TOLERANCE = 1e-10  # relative change of the tractions between iterations that ends the iteration
MAX_ITERATIONS = 2000


@dataclass
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


def _fft(fields: np.ndarray) -> np.ndarray:
    return np.fft.rfft2(fields)


def _ifft(spectra: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    return np.fft.irfft2(spectra, s=shape)


def _uniform_face(modes: Modes, pressure_mpa: float, frictionless: bool) -> np.ndarray:
    """Fourier face displacements (3, ...) of the uniform load alone."""
    traction = np.zeros((3,) + modes.stiffness.shape[:2], dtype=complex)
    traction[2, 0, 0] = pressure_mpa * np.prod(modes.shape)
    return modes.displacement(traction, frictionless)


def full_contact(modes: Modes, heights: np.ndarray, pressure_mpa: float, frictionless: bool) -> ContactState:
    """The face in contact everywhere: it takes the shape of ``heights`` (mm)."""
    spectrum = _fft(heights)
    spectrum[0, 0] = 0.0
    face = modes.slid(spectrum) if frictionless else np.stack([np.zeros_like(spectrum)] * 2 + [spectrum])
    traction = _ifft(modes.traction(face), modes.shape)
    traction[2] += pressure_mpa
    face = face + _uniform_face(modes, pressure_mpa, frictionless)
    offset = float(face[2, 0, 0].real / heights.size - heights.mean())
    tension = max(0.0, float(-traction[2].min()))
    return ContactState(face, traction, np.ones(heights.shape, bool), offset, tension == 0.0,
                        "full contact" if tension == 0.0 else "full contact would need tension",
                        0, 0.0, tension, 0.0)


def solve_contact(modes: Modes, heights: np.ndarray, pressure_mpa: float, frictionless: bool,
                  max_iterations: int = MAX_ITERATIONS) -> ContactState:
    """The face pressed onto ``heights`` (mm, the periodic domain) at mean pressure ``pressure_mpa``."""
    full = full_contact(modes, heights, pressure_mpa, frictionless)
    if full.success:
        return full
    shape, n = heights.shape, heights.size
    load = pressure_mpa * n
    tolerance = GAP_TOLERANCE * max(float(np.ptp(heights)), 1e-12)
    active = slice(2, 3) if frictionless else slice(0, 3)
    t = full.traction.copy()
    t *= t[2] > 0
    t[2] *= load / t[2].sum()
    direction = np.zeros_like(t)
    restart, g_old = True, 1.0
    for iteration in range(1, max_iterations + 1):
        u = _ifft(modes.displacement(_fft(t), frictionless), shape)
        touching = t[2] > 0
        mask = touching.astype(float)
        count = mask.sum()
        residual = u * mask if not frictionless else np.zeros_like(t)
        gap = u[2] - heights
        residual[2] = (gap - (gap * mask).sum() / count) * mask
        outside = (gap - (gap * mask).sum() / count) * (1 - mask)
        violation = max(float(np.abs(residual).max()), float(-outside.min()))
        if violation <= tolerance:
            break
        precond = _ifft(modes.traction(_fft(residual)), shape) * mask  # the stiffness: exact at full contact
        precond[2] -= (precond[2].sum() / count) * mask
        if frictionless:
            precond[:2] = 0.0
        norm = float(np.vdot(residual, precond))
        direction = precond + (0.0 if restart else norm / g_old) * direction
        g_old = norm
        response = _ifft(modes.displacement(_fft(direction), frictionless), shape) * mask
        response[2] -= (response[2].sum() / count) * mask
        curvature = float(np.vdot(response, direction))
        if curvature <= 0:
            break
        step = float(np.vdot(residual, direction)) / curvature
        previous = t
        t = t - step * direction
        t *= t[2] > 0
        entering = outside < 0
        t[2] -= step * outside * entering
        restart = bool(entering.any())
        t[2] *= load / t[2].sum()
        change = float(np.abs(t - previous).sum() / np.abs(t).sum())
        if change < STEP_TOLERANCE:
            break
    return _checked(modes, heights, t, frictionless, iteration)


def _checked(modes: Modes, heights: np.ndarray, traction: np.ndarray, frictionless: bool,
             iterations: int) -> ContactState:
    """The state for ``traction``, with each contact condition measured."""
    face = modes.displacement(_fft(traction), frictionless)
    u = _ifft(face, heights.shape)
    touching = traction[2] > 0
    gap = u[2] - heights
    offset = float(gap[touching].mean())
    gap -= offset
    scale = max(float(np.ptp(heights)), 1e-12)
    penetration = max(0.0, float(-gap[~touching].min())) if (~touching).any() else 0.0
    mismatch = float(np.abs(gap[touching]).max())
    slip = 0.0 if frictionless else float(np.abs(u[:2, touching]).max())
    tension = max(0.0, float(-traction[2].min()))
    worst = max(penetration, mismatch, slip)
    success = worst <= GAP_TOLERANCE * scale and tension == 0.0
    message = ("contact conditions hold" if success else
               f"contact conditions violated by up to {worst:.3g} mm after {iterations} iterations")
    return ContactState(face, traction, touching, offset, success, message, iterations,
                        max(penetration, mismatch), tension, slip)

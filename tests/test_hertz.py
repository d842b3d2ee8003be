"""Analytic validation: a rigid sphere pressed into a thick skin block follows Hertz.

Hertz (frictionless, elastic half-space, rigid sphere of radius R, force F):
    contact radius   a = (3 F R / (4 E*))^(1/3),  E* = E / (1 - nu^2)
    approach         d = a^2 / R
The FEM block is finite (top held by the bone), so the rigid offset of its surface is not
the half-space's: we compare the approach measured relative to the surface at r = 2a,
d(0) - w(2a), with the half-space value a^2/R - w(2a), where outside the contact
    w(r) = [(2 a^2 - r^2) asin(a / r) + a sqrt(r^2 - a^2)] / (pi R).
Block 10 x 10 mm, 6 mm thick (a / thickness < 0.2), contact-face spacing 0.3 mm.
"""
from __future__ import annotations

import numpy as np
import pytest

from roughness.simulate.config import SimConfig
from roughness.simulate.model import Simulator
from roughness.surface.heightmap import Heightmap

E, NU, R = 0.042, 0.45, 5.0


def sphere(pixel_mm: float = 0.02, size_mm: float = 11.0) -> Heightmap:
    n = int(round(size_mm / pixel_mm))
    x = (np.arange(n) + 0.5) * pixel_mm - size_mm / 2
    r2 = x[None, :] ** 2 + x[:, None] ** 2
    return Heightmap(np.sqrt(np.clip(R**2 - r2, 0.0, None)), pixel_mm)


def outside_deflection(r: float, a: float) -> float:
    return ((2 * a * a - r * r) * np.arcsin(a / r) + a * np.sqrt(r * r - a * a)) / (np.pi * R)


@pytest.fixture(scope="module")
def block_sim():
    cfg = SimConfig(width_mm=10.0, tissue_mm=6.0, h_contact_mm=0.3, contact="frictionless", young_mpa=E, poisson=NU)
    return Simulator(cfg)


@pytest.mark.parametrize("force_n", [0.02, 0.04])
def test_sphere_contact_follows_hertz(block_sim, force_n):
    result = block_sim.run(sphere(), force_n=force_n)
    assert result.converged and result.unresolved_nodes == 0
    block = block_sim.block(result.config)
    a_fem = np.sqrt(block.area[result.state.in_contact].sum() / np.pi)
    a_hertz = (3 * force_n * R / (4 * E / (1 - NU**2))) ** (1 / 3)
    assert a_fem == pytest.approx(a_hertz, rel=0.05)

    uz = result.state.u.reshape(-1, 3)[block.problem.bottom, 2]
    r = np.hypot(*block.problem.bottom_xy.T)
    ring = np.abs(r - 2 * a_hertz) < 0.225
    d_fem = uz[np.argmin(r)] - uz[ring].mean()
    d_hertz = a_hertz**2 / R - outside_deflection(2 * a_hertz, a_hertz)
    assert d_fem == pytest.approx(d_hertz, rel=0.05)

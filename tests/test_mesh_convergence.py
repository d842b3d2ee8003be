"""Mesh convergence: V at ``default`` within 5% of ``fine`` (opt-in: pytest -m slow).

Full-resolution runs take minutes; the numbers are kept in
studies/results/mesh_convergence.md (python studies/mesh_convergence.py).
"""
from __future__ import annotations

import pytest

from roughness.dataset.fractal import fbm_surface
from roughness.dataset.textures import standard_texture
from roughness.simulate.config import SimConfig
from roughness.simulate.model import Simulator


@pytest.mark.slow
@pytest.mark.parametrize("make", [lambda: standard_texture(1.0, seed=0), lambda: fbm_surface(seed=0)],
                         ids=["standard-1.0", "fbm"])
def test_default_is_within_5_percent_of_fine(make):
    hm = make()
    default = Simulator(SimConfig(fidelity="default")).run(hm).roughness
    fine = Simulator(SimConfig(fidelity="fine")).run(hm).roughness
    assert default == pytest.approx(fine, rel=0.05)

"""Discretization-error estimate and the ``converged`` ladder, on a small block (seconds)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from roughness.core.errors import InputError
from roughness.simulate import converged
from roughness.simulate.config import SimConfig
from roughness.simulate.discretization import SAFETY, V_FLOOR, coarser_spacing, richardson, within
from roughness.simulate.model import Simulator
from roughness.surface.heightmap import Heightmap

# A 4 mm block (force scaled with its area) sampled in a 3 mm window: a sixth of the nodes.
SMALL = dict(width_mm=4.0, window_mm=3.0, pair_distance_mm=0.5, disk_radius_mm=0.5, pairs=2000, force_n=1.6)
LADDER = (0.6, 0.4, 0.27, 0.18)  # coarser than the real ladder: each level solves in about a second


def smooth_texture() -> Heightmap:
    """A 2 mm sine grating 0.2 mm high: smooth at every spacing of LADDER."""
    x = (np.arange(120) + 0.5) * 0.05
    return Heightmap(np.broadcast_to(0.1 * np.sin(2 * np.pi * x / 2.0), (120, 120)).copy(), 0.05)


@pytest.fixture(scope="module")
def sim():
    return Simulator(SimConfig(**SMALL), max_blocks=6)


def test_richardson_recovers_the_error_of_an_exact_power_law():
    exact, c, order = 0.1, 0.5, 2.0
    v = {h: exact + c * h**order for h in (0.3, 0.2)}
    estimate = richardson(v[0.2], v[0.3], 0.2, 0.3, order=order, safety=1.0)
    assert estimate == pytest.approx(abs(v[0.2] - exact) / v[0.2], rel=1e-12)
    assert richardson(v[0.2], v[0.3], 0.2, 0.3, order=order) == pytest.approx(SAFETY * estimate, rel=1e-12)
    assert richardson(0.0, 0.0, 0.2, 0.3) == 0.0 and math.isinf(richardson(0.0, 0.1, 0.2, 0.3))
    with pytest.raises(ValueError):
        richardson(0.1, 0.1, 0.3, 0.2)


def test_tolerance_is_relative_above_the_floor_and_absolute_below():
    assert within(0.1, 0.029, 0.03) and not within(0.1, 0.031, 0.03)
    small = V_FLOOR / 10  # a 20% error of a tiny V is 2% of the floor
    assert within(small, 0.2, 0.03) and not within(small, 0.4, 0.03)


def test_coarser_spacing_is_the_next_rung():
    assert coarser_spacing(0.2) == 0.3 and coarser_spacing(0.14) == 0.2 and coarser_spacing(0.1) == 0.14
    assert coarser_spacing(0.3) == pytest.approx(0.45)


def test_tolerance_is_checked():
    for bad in (0.0, 1.5, -0.1, math.nan):
        with pytest.raises(InputError) as err:
            SimConfig(tolerance=bad)
        assert err.value.parameter == "tolerance"


def test_every_result_carries_an_estimate_and_it_shrinks_under_refinement(sim):
    hm = smooth_texture()
    results = [sim.run(hm, h_contact_mm=h) for h in (0.6, 0.4, 0.27)]
    errors = [r.discretization_error for r in results]
    assert all(0 < e < math.inf for e in errors)
    assert errors[0] > errors[1] > errors[2]
    for r in results:
        assert [level.h_contact_mm for level in r.ladder] == [coarser_spacing(r.config.h_contact_mm),
                                                               r.config.h_contact_mm]
        assert r.summary()["discretization_error"] == r.discretization_error
    plain = sim.run(hm, h_contact_mm=0.4, estimate_error=False)
    assert plain.discretization_error is None and plain.ladder == []
    assert plain.roughness == pytest.approx(results[1].roughness, rel=1e-3)  # CG tolerance; contact start differs


@pytest.mark.parametrize("tolerance", [0.2, 0.05])
def test_converged_stops_at_the_first_level_below_tolerance(sim, monkeypatch, tolerance):
    monkeypatch.setattr(converged, "LADDER_MM", LADDER)
    r = sim.run(smooth_texture(), fidelity="converged", tolerance=tolerance)
    levels = r.ladder
    assert levels[0].discretization_error is None
    assert all(not within(lv.roughness, lv.discretization_error, tolerance) for lv in levels[1:-1])
    reached = levels[-1]
    assert within(reached.roughness, reached.discretization_error, tolerance) or len(levels) == len(LADDER)
    assert r.config.h_contact_mm == reached.h_contact_mm and r.roughness == reached.roughness
    summary = r.summary()
    assert summary["fidelity"] == "converged" and summary["h_contact_mm"] == reached.h_contact_mm
    assert summary["discretization_error"] == reached.discretization_error
    assert [lv["h_contact_mm"] for lv in summary["ladder"]] == list(LADDER[:len(levels)])
    met = within(r.roughness, r.discretization_error, tolerance)
    assert met != any(n.code == "tolerance_not_met" for n in r.notes)


def test_converged_reports_a_tolerance_it_cannot_meet(sim, monkeypatch):
    monkeypatch.setattr(converged, "LADDER_MM", LADDER[:2])
    r = sim.run(smooth_texture(), fidelity="converged", tolerance=1e-6)
    assert len(r.ladder) == 2 and r.config.h_contact_mm == LADDER[1]
    assert [n.code for n in r.notes if n.unusual] == ["tolerance_not_met"]


def test_contact_set_carries_over_as_a_superset(sim):
    hm = smooth_texture()
    coarse = sim.run(hm, h_contact_mm=0.4, estimate_error=False)
    carried = converged.contact_set_map(sim, coarse)
    coarse_xy = sim.block(coarse.config).problem.bottom_xy
    assert np.all(carried(coarse_xy)[coarse.state.in_contact])
    fine_xy = sim.block(sim.run(hm, h_contact_mm=0.27, estimate_error=False).config).problem.bottom_xy
    start = carried(fine_xy)
    assert start.shape == (len(fine_xy),) and start.dtype == bool
    assert start.mean() >= coarse.contact_fraction - 0.05  # the coarse set covers a fine node's area

"""The FEM's seams: block cache key, linear-solver and contact result objects, plain summaries, CLI outputs."""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from roughness.cli import main
from roughness.dataset.textures import standard_texture
from roughness.simulate.config import CHOICES, RUN_FIELDS, SimConfig
from roughness.simulate.elasticity import rigid_body_modes, stiffness
from roughness.simulate.mesh import MeshSpec, build
from roughness.simulate.model import Simulator

ROOT = Path(__file__).parents[1]
EXAMPLE = ROOT / "examples" / "standard-1.0mm.png"
SIMULATE = ["simulate", str(EXAMPLE), "--pixel-mm", "0.05", "--height-mm", "1", "--fidelity", "coarse"]


def _other_value(name: str, value: object) -> object:
    """A different valid value for a SimConfig field."""
    if name in CHOICES:
        return next(o for o in CHOICES[name] if o != value and o != "auto")
    if value is None:  # h_contact_mm (mm) and curvature_mm (a radius: at least the receptor depth)
        return 25.0 if name == "curvature_mm" else 0.25
    if isinstance(value, int):
        return value + 1
    return value * 0.9


@pytest.mark.parametrize("name", [f.name for f in dataclasses.fields(SimConfig)])
def test_every_config_field_is_in_the_block_spec_or_declared_run_level(name):
    """A new SimConfig field that shapes the block but is missing from block_spec() fails here."""
    shapes_block = False
    for base in (SimConfig(fidelity="coarse"), SimConfig(fidelity="coarse", bone="elastic")):
        changed = dataclasses.replace(base, **{name: _other_value(name, getattr(base, name))})
        shapes_block |= changed.resolved().block_spec() != base.resolved().block_spec()
    assert shapes_block != (name in RUN_FIELDS), name


@pytest.fixture(scope="module")
def small():
    m = build(MeshSpec(width_mm=4.0, tissue_mm=2.0, h_contact_mm=0.4, fine_depth_mm=1.0, h_max_mm=0.8))
    k = stiffness(m, np.full(len(m.tets), 0.042), np.full(len(m.tets), 0.45)).tocsr()
    return m, k


def test_constrain_returns_independent_systems_sharing_one_hierarchy(small):
    from roughness.simulate.linsolve import AMGCache, constrain

    m, k = small
    amg = AMGCache(rigid_body_modes(m.points))
    fixed = np.zeros(k.shape[0], dtype=bool)
    fixed[3 * m.top[:, None] + np.arange(3)] = True
    fixed[3 * m.bottom[:, None] + np.arange(3)] = True
    values = np.zeros(k.shape[0])
    values[3 * m.top + 2] = -0.02
    first = constrain(k, fixed, amg)
    assert amg.setups == 1
    a = first.solve(values)
    nearly = fixed.copy()
    nearly[3 * m.bottom[0] + 2] = False  # one DOF of thousands: within the drift allowance, reused
    second = constrain(k, nearly, amg)
    assert amg.setups == 1 and second.fixed is nearly and first.fixed is fixed
    b = second.solve(values)
    assert isinstance(a.iterations, int) and a.iterations > 0 and a.residual <= first.rtol
    assert b.residual <= second.rtol and not np.array_equal(a.u, b.u)
    again = first.solve(values)  # the first system is unchanged by the second, and so is the hierarchy
    assert amg.setups == 1 and np.array_equal(again.u, a.u)
    far = np.zeros_like(fixed)
    far[3 * m.top[:, None] + np.arange(3)] = True  # the bottom released: far beyond the drift allowance
    constrain(k, far, amg)
    assert amg.setups == 2


@pytest.fixture(scope="module")
def coarse():
    return Simulator(SimConfig(fidelity="coarse"))


def test_contact_reports_counts_and_calls_back_every_round(coarse):
    rounds = []
    r = coarse.run(standard_texture(1.0, seed=0), callback=rounds.append)
    assert [x.round for x in rounds] == list(range(1, r.iterations + 1))
    assert [x.in_contact for x in rounds] == r.contact_history
    assert sum(x.cg_iterations for x in rounds) == r.cg_iterations > 0
    assert sum(x.amg_setups for x in rounds) == r.amg_setups
    state = r.state
    assert state.success is True and state.message == "contact set settled"
    assert state.linear_solves == r.iterations  # one force-controlled solve per round (warm: no unit solve)


def _plain(value: object) -> bool:
    if isinstance(value, dict):
        return all(isinstance(k, str) and _plain(v) for k, v in value.items())
    if isinstance(value, list):
        return all(_plain(v) for v in value)
    return value is None or type(value) in (bool, int, float, str)


def test_summary_of_an_unsettled_contact_is_plain_json(coarse):
    r = coarse.run(standard_texture(1.0, seed=0), max_rounds=1)
    assert not r.converged and r.unresolved_nodes > 0
    assert not r.state.success and "after 1 rounds" in r.state.message
    assert [n.code for n in r.unusual_notes] == ["not_converged"]
    summary = r.summary()
    assert _plain(summary) and json.loads(json.dumps(summary)) == summary
    # numpy values anywhere (a cycled, unresolved state as numpy computes it) still give plain JSON
    numpyish = dataclasses.replace(r, cycled=np.bool_(True), converged=np.bool_(False),
                                   unresolved_nodes=np.int64(3), roughness=np.float64(r.roughness),
                                   contact_history=list(np.array(r.contact_history)))
    summary = numpyish.summary()
    assert _plain(summary) and summary["cycled"] is True and summary["unresolved_nodes"] == 3


def test_cli_defaults_come_from_simconfig_and_every_option_shows_its_default():
    from roughness.cli import build_parser

    parser = build_parser()
    args = parser.parse_args(["simulate", "x.png"])
    d = SimConfig()
    assert (args.force, args.poisson, args.contact, args.element, args.bone, args.seed, args.fidelity) == (
        d.force_n, d.poisson, d.contact, d.element, d.bone, d.seed, d.fidelity)
    assert args.flags["force_n"] == "--force" and args.flags["poisson"] == "--poisson"
    sub = next(a for a in parser._actions if isinstance(a, __import__("argparse")._SubParsersAction))
    own = ("--fidelity", "--force", "--poisson", "--contact", "--element", "--bone", "--seed", "--json",
           "--save-strain", "--save-vtu", "--overwrite")
    for action in sub.choices["simulate"]._actions:
        if action.option_strings and action.option_strings[-1] in own:
            assert "default" in (action.help or ""), action.option_strings


@pytest.mark.parametrize("flag", ["--save-strain", "--save-vtu"])
def test_existing_or_unwritable_outputs_are_refused_before_the_fem(tmp_path, capsys, monkeypatch, flag):
    def no_fem(*a, **k):
        raise AssertionError("the FEM ran before the output path was checked")

    monkeypatch.setattr(Simulator, "run", no_fem)
    out = tmp_path / "out.file"
    out.write_bytes(b"keep me")
    assert main([*SIMULATE, flag, str(out)]) == 2
    assert "already exists" in capsys.readouterr().err and out.read_bytes() == b"keep me"
    assert main([*SIMULATE, flag, str(tmp_path / "missing" / "x")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_ordinary_run_keeps_notes_in_json_and_quiet_stderr(tmp_path, capsys):
    png = tmp_path / "strain.png"
    png.write_bytes(b"old")
    assert main([*SIMULATE, "--json", "--save-strain", str(png), "--overwrite"]) == 0
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert "indentation" in [n["code"] for n in out["notes"]] and not any(n["unusual"] for n in out["notes"])
    assert "note:" not in captured.err  # the regime note is ordinary for this model: JSON only
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_meaningless_pixel_size_exits_2_naming_the_flag(capsys):
    """Refused by the unit check (a 1 m pixel is no touchable texture's), and confirmed, by the footprint."""
    command = ["simulate", str(EXAMPLE), "--pixel-mm", "1000", "--height-mm", "1", "--fidelity", "coarse"]
    assert main(command) == 2
    err = capsys.readouterr().err
    assert "--pixel-mm" in err and "implausible" in err and "--units-ok" in err and "Traceback" not in err
    assert main([*command, "--units-ok"]) == 2
    err = capsys.readouterr().err
    assert "--pixel-mm" in err and "spans only 0.01 pixels" in err and "Traceback" not in err

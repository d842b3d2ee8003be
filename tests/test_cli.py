"""The roughness command line: JSON output, files written, exit codes and messages."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from roughness.cli import main

EXAMPLE = Path(__file__).parents[1] / "examples" / "standard-1.0mm.png"
REQUIRED = {"roughness", "roughness_stderr", "contact_fraction", "indentation_mm", "converged", "iterations",
            "nodes", "seconds"}


def test_simulate_json_and_outputs(tmp_path, capsys):
    png, vtu = tmp_path / "strain.png", tmp_path / "mesh.vtu"
    code = main(["simulate", str(EXAMPLE), "--pixel-mm", "0.05", "--height-mm", "1", "--fidelity", "coarse",
                 "--json", "--quiet", "--save-strain", str(png), "--save-vtu", str(vtu)])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert REQUIRED <= out.keys()
    assert out["converged"] and 0 < out["roughness"] < 1 and 0.8 < out["contact_fraction"] <= 1
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import meshio

    mesh = meshio.read(vtu)
    assert "displacement" in mesh.point_data and "lambda3" in mesh.cell_data
    assert np.isfinite(mesh.point_data["displacement"]).all()


def test_human_readable_output(capsys):
    assert main(["simulate", str(EXAMPLE), "--pixel-mm", "0.05", "--height-mm", "1", "--fidelity", "coarse",
                 "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "roughness V" in out and "contact fraction" in out


@pytest.mark.parametrize(
    "args, message",
    [
        (["missing.npy", "--pixel-mm", "0.05"], "not found"),
        ([str(EXAMPLE), "--height-mm", "1"], "--pixel-mm"),
        ([str(EXAMPLE), "--pixel-mm", "0.05"], "--height-mm"),
        ([str(EXAMPLE), "--pixel-mm", "-1", "--height-mm", "1"], "pixel"),
        ([str(EXAMPLE), "--pixel-mm", "0.02", "--height-mm", "1"], "--tile"),
        ([str(EXAMPLE), "--pixel-mm", "0.05", "--height-mm", "1", "--poisson", "0.5"], "poisson"),
        ([str(EXAMPLE), "--pixel-mm", "0.05", "--height-mm", "1", "--force", "0"], "force"),
        ([str(EXAMPLE), "--pixel-mm", "0.05", "--height-mm", "1", "--save-vtu", "/no/such/dir/x.vtu"], "folder"),
    ],
)
def test_bad_input_exits_2_with_a_message(args, message, capsys):
    assert main(["simulate", *args, "--fidelity", "coarse"]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_nan_heightmap_is_refused(tmp_path, capsys):
    h = np.zeros((240, 240))
    h[3, 4] = np.nan
    np.save(tmp_path / "nan.npy", h)
    assert main(["simulate", str(tmp_path / "nan.npy"), "--pixel-mm", "0.05"]) == 2
    assert "NaN" in capsys.readouterr().err


def test_console_script_runs_as_a_module():
    proc = subprocess.run([sys.executable, "-m", "roughness.cli", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.startswith("roughness ")


def test_cold_run_prints_only_json_on_stdout(tmp_path):
    """Meshing (TetGen) must not write to stdout: --json output stays parseable."""
    import os

    env = {**os.environ, "ROUGHNESS_CACHE": str(tmp_path)}
    proc = subprocess.run([sys.executable, "-m", "roughness.cli", "simulate", str(EXAMPLE), "--pixel-mm", "0.05",
                           "--height-mm", "1", "--fidelity", "coarse", "--json"],
                          capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    assert REQUIRED <= json.loads(proc.stdout).keys()
    assert "preparing the skin block" in proc.stderr


@pytest.mark.parametrize("name, params", [("standard-0.75", []), ("flattop-0.3", []), ("grating", ["period_mm=1.5"]),
                                          ("bumps", ["lambda_mm=2.0", "top=flat", "top_diameter_mm=0.4"])])
def test_texture_make_writes_heightmaps_in_mm(tmp_path, capsys, name, params):
    from roughness.surface.io import load_heightmap

    out = tmp_path / "t.npy"
    args = ["texture", "make", name, "--out", str(out), "--seed", "2", "--pixel-mm", "0.04", "--size-mm", "11"]
    assert main(args + [a for p in params for a in ("--param", p)]) == 0
    hm = load_heightmap(out, pixel_mm=0.04)
    assert hm.shape == (275, 275) and hm.heights.min() >= 0.0 and 0 < hm.heights.max() <= 1.0
    recipe = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert recipe["name"] == name and recipe["seed"] == 2


@pytest.mark.parametrize("args, message", [(["nope"], "unknown texture"), (["grating", "--param", "period"], "key=value"),
                                           (["grating", "--param", "speed=3"], "unknown grating parameter"),
                                           (["standard-0.7"], "not on the standard scale")])
def test_texture_make_bad_input(tmp_path, capsys, args, message):
    assert main(["texture", "make", *args, "--out", str(tmp_path / "x.npy")]) == 2
    assert message in capsys.readouterr().err

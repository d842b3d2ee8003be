"""`roughness dataset` and `roughness texture` on bad input: a generated sweep of bad values, each
answered with exit code 2, a message naming the problem, no traceback, and no file created or changed."""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from roughness.cli import main
from roughness.dataset.recipe import Recipe
from roughness.dataset.writer import DatasetWriter

ROOT = Path(__file__).parents[1]
GOOD_RECIPE = json.loads(Recipe(name="sweep", families={"bumps": 1.0, "fbm": 1.0}).to_json())
# Bad values tried in every recipe field, except where one is valid there (FIELD_VALID).
WRONG_TYPES = {"a string": "abc", "null": None, "true": True, "a list": [1, 2], "an object": {"a": 1},
               "NaN": math.nan, "Infinity": math.inf, "-1": -1, "0": 0, "1e12": 1e12}
FIELD_VALID = {"name": {"a string"}, "ranges": {"an object"}, "holdout_family": {"null"},
               "perturb_probability": {"0"}, "max_perturb_steps": {"0"}, "seed": {"0"},
               "test_fraction": {"0"}}
OUT_OF_RANGE = {  # field -> bad values that have the right type
    "name": [""], "seed": [1.5], "families": [{}, {"bumps": 0.0}, {"velvet": 1.0}, {"bumps": -1.0}],
    "ranges": [{"bumps": 3}, {"bumps": {"lambda_mm": [2.0, 1.0]}}, {"fbm": {"hurst": [0.0, 5.0]}},
               {"fbm": {"speed": [1, 2]}}, {"bumps": {"top": ["dome"]}}, {"bumps": {"lambda_mm": [1.0]}}],
    "perturb_probability": [1.5, -0.1], "max_perturb_steps": [2.5], "size_mm": [1e7],
    "pixel_mm": [1e-9], "holdout_family": ["knit"], "test_fraction": [1.0, -0.5],
}


def recipe_cases() -> list[tuple[str, object, str]]:
    """(field, bad value, case id) for every field of Recipe."""
    cases = []
    for field in GOOD_RECIPE:
        for label, value in WRONG_TYPES.items():
            if label not in FIELD_VALID.get(field, set()):
                cases.append((field, value, f"{field}={label}"))
        cases += [(field, value, f"{field}={value!r}") for value in OUT_OF_RANGE.get(field, [])]
    return cases


RECIPE_CASES = recipe_cases()
BAD_FILES = {  # file content -> what the message must say
    "missing": (None, "not found"), "empty": (b"", "not valid JSON"),
    "truncated": (json.dumps(GOOD_RECIPE).encode()[:40], "not valid JSON"),
    "binary": (bytes(range(256)), "not a text"), "a list": (b"[1, 2]", "must be a JSON object"),
    "a number": (b"3", "must be a JSON object"), "null": (b"null", "must be a JSON object"),
    "unknown field": (json.dumps({**GOOD_RECIPE, "colour": "red"}).encode(), "unknown field(s) colour"),
}


def run(args: list[str], capsys) -> tuple[int, str]:
    """Exit code and stderr of the CLI run in-process (argparse errors exit through SystemExit)."""
    try:
        code = main(args)
    except SystemExit as stop:
        code = stop.code
    return code, capsys.readouterr().err


def snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def assert_refused(folder: Path, args: list[str], message: str, capsys) -> str:
    """Run the CLI: exit 2, ``message`` on stderr, no traceback, no file in ``folder`` created or changed."""
    before, names = snapshot(folder), sorted(os.listdir(folder))
    code, err = run(args, capsys)
    assert code == 2, err
    assert message in err and "Traceback" not in err, err
    assert snapshot(folder) == before and sorted(os.listdir(folder)) == names
    return err


@pytest.mark.parametrize("field, value", [c[:2] for c in RECIPE_CASES], ids=[c[2] for c in RECIPE_CASES])
def test_every_bad_recipe_field_is_refused_by_name(tmp_path, capsys, field, value):
    recipe = tmp_path / "recipe.json"
    recipe.write_text(json.dumps({**GOOD_RECIPE, field: value}))
    err = assert_refused(tmp_path, ["dataset", "build", "--recipe", str(recipe), "--n", "2", "--out",
                                    str(tmp_path / "d.h5"), "--quiet"], f"recipe {recipe}: ", capsys)
    assert field in err.split(f"recipe {recipe}: ")[1], err  # the message names the field


@pytest.mark.parametrize("kind", list(BAD_FILES))
def test_bad_recipe_files_are_refused(tmp_path, capsys, kind):
    content, message = BAD_FILES[kind]
    recipe = tmp_path / "recipe.json"
    if content is not None:
        recipe.write_bytes(content)
    assert_refused(tmp_path, ["dataset", "build", "--recipe", str(recipe), "--n", "2", "--out",
                              str(tmp_path / "d.h5")], message, capsys)


BUILD_FLAGS = [(["--n", "0"], "--n"), (["--n", "-3"], "--n"), (["--n", "abc"], "--n"), (["--workers", "0"], "--workers"),
               (["--seed", "-1"], "--seed"), (["--seed", "1.5"], "--seed"), (["--fidelity", "ultra"], "--fidelity")]


@pytest.mark.parametrize("flags, message", BUILD_FLAGS, ids=[" ".join(f) for f, _ in BUILD_FLAGS])
def test_bad_build_flags(tmp_path, capsys, flags, message):
    args = {"--n": "2", "--out": str(tmp_path / "d.h5")}
    args.update(dict(zip(flags[::2], flags[1::2])))
    assert_refused(tmp_path, ["dataset", "build", *[x for kv in args.items() for x in kv]], message, capsys)


def other_dataset(path: Path) -> None:
    config = {"simulation": {"fidelity": "fine"}, "recipe": {"name": "other"}}
    with DatasetWriter(path, config, "test") as writer:
        writer.write_failure({"family": "bumps", "seed": 1}, None, 0.05, "a failure")


@pytest.mark.parametrize("kind, message", [("text", "not an HDF5 file"), ("hdf5", "is not a roughness dataset"),
                                           ("other config", "another configuration"), ("folder", "not a file"),
                                           ("no folder", "No such file or directory")])
def test_build_out_must_be_a_dataset_of_the_same_configuration(tmp_path, capsys, kind, message):
    out = tmp_path / "d.h5"
    if kind == "text":
        out.write_text("notes")
    elif kind == "hdf5":
        with h5py.File(out, "w") as f:
            f["x"] = np.zeros(3)
    elif kind == "other config":
        other_dataset(out)
    elif kind == "folder":
        out.mkdir()
    else:
        out = tmp_path / "missing" / "d.h5"
    assert_refused(tmp_path, ["dataset", "build", "--n", "2", "--out", str(out)], message, capsys)


TEXTURE_CASES = [
    (["bumps", "--param", "lambda_mm=abc"], "--param: lambda_mm must be a positive finite number, got 'abc'"),
    (["bumps", "--param", "lambda_mm=nan"], "lambda_mm must be a positive finite number"),
    (["bumps", "--param", "lambda_mm=-1"], "lambda_mm must be a positive finite number"),
    (["bumps", "--param", "lambda_mm=1", "--param", "height_mm=abc"], "--param: height_mm"),
    (["bumps", "--param", "lambda_mm=1", "--param", "top=dome"], "--param: top must be one of"),
    (["bumps", "--param", "lambda"], "not of the form key=value"),
    (["bumps", "--param", "=1"], "not of the form key=value"),
    (["bumps"], "bumps needs lambda_mm"),
    (["grating", "--param", "period_mm=abc"], "grating parameter period_mm must be a finite number"),
    (["grating", "--param", "period_mm=99"], "grating parameter period_mm must be between"),
    (["grating", "--param", "speed=1"], "unknown grating parameter"),
    (["standard-1.0", "--param", "lambda_mm=1"], "takes no parameters"),
    (["nope"], "unknown texture"), (["standard-abc"], "unknown texture"), (["flattop-nan"], "top_diameter_mm"),
    (["standard-0.7"], "not on the standard scale"),
    (["flat", "--seed", "-1"], "argument --seed: expected an integer >= 0"),
    (["bumps", "--param", "lambda_mm=1", "--seed", "-1"], "--seed"),
    (["flat", "--seed", "abc"], "--seed"),
    (["grating", "--size-mm", "100000"], "argument --size-mm: expected a number > 0 and <= 1000 (MAX_LENGTH_MM)"),
    (["bumps", "--param", "lambda_mm=1", "--size-mm", "100000"], "--size-mm"),
    (["flat", "--pixel-mm", "1e-9"], "--size-mm"),
    (["flat", "--size-mm", "0"], "argument --size-mm: expected a number > 0"),
    (["flat", "--size-mm", "nan"], "--size-mm"), (["flat", "--size-mm", "inf"], "--size-mm"),
    (["flat", "--size-mm", "abc"], "--size-mm"), (["flat", "--pixel-mm", "-0.05"], "--pixel-mm"),
    (["flat", "--size-mm", "0.01"], "smaller than one pixel"),
    (["flat", "--height-mm", "1"], "--height-mm: applies only to PNG"),
]


@pytest.mark.parametrize("args, message", TEXTURE_CASES, ids=[" ".join(a) for a, _ in TEXTURE_CASES])
def test_bad_texture_input(tmp_path, capsys, args, message):
    assert_refused(tmp_path, ["texture", "make", *args, "--out", str(tmp_path / "t.npy")], message, capsys)


@pytest.mark.parametrize("out, message", [("t.npy", "already exists; pass --overwrite"), ("t.xyz", "unsupported format"),
                                          ("missing/t.npy", "does not exist"), (".", "is a folder"),
                                          ("t.png --height-mm -1", "--height-mm")])
def test_bad_texture_output(tmp_path, capsys, out, message):
    (tmp_path / "t.npy").write_bytes(b"an earlier result")
    path, *more = out.split()
    assert_refused(tmp_path, ["texture", "make", "flat", "--out", str(tmp_path / path), *more], message, capsys)


def test_texture_make_overwrites_only_when_asked(tmp_path, capsys):
    out = tmp_path / "t.npy"
    out.write_bytes(b"an earlier result")
    assert main(["texture", "make", "standard-1.0", "--out", str(out), "--overwrite", "--size-mm", "5"]) == 0
    assert np.load(out).shape == (100, 100) and os.listdir(tmp_path) == ["t.npy"]


@pytest.mark.parametrize("kind", ["missing", "text", "empty", "folder", "hdf5", "truncated"])
def test_info_and_verify_of_bad_files(tmp_path, capsys, kind):
    path = tmp_path / "d.h5"
    if kind == "text":
        path.write_text("notes")
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "folder":
        path.mkdir()
    elif kind == "hdf5":
        with h5py.File(path, "w") as f:
            f["x"] = np.zeros(3)
    elif kind == "truncated":
        other_dataset(tmp_path / "whole.h5")
        path.write_bytes((tmp_path / "whole.h5").read_bytes()[:1000])
    message = {"missing": "no dataset file", "folder": "not a file", "hdf5": "not a roughness dataset"}.get(
        kind, "not an HDF5 file")
    assert_refused(tmp_path, ["dataset", "info", str(path)], message, capsys)
    if kind == "hdf5":  # an HDF5 file that is not a dataset: verify lists the problems (exit 1)
        assert main(["dataset", "verify", str(path)]) == 1
        assert "root attribute 'schema' is missing" in capsys.readouterr().out
    else:
        assert_refused(tmp_path, ["dataset", "verify", str(path)], message, capsys)


@pytest.mark.parametrize("args", [["dataset", "info", "{path}"], ["dataset", "verify", "{path}"], ["texture", "list"]])
def test_a_closed_pipe_ends_output_quietly(tmp_path, args):
    """`roughness dataset info FILE | head`: the reader goes away before the output is written."""
    other_dataset(tmp_path / "d.h5")
    argv = [a.format(path=tmp_path / "d.h5") for a in args]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "roughness.cli", *argv], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=env)
    proc.stdout.close()  # before the command has started up
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 0 and err == ""


def test_help_shows_every_default():
    from roughness.cli import build_parser

    parser = build_parser()
    for path in (["dataset", "build"], ["dataset", "info"], ["dataset", "verify"], ["texture", "make"]):
        sub = parser
        for name in path:
            sub = next(a for a in sub._actions if a.dest.endswith("command")).choices[name]
        for action in sub._actions:
            if action.dest == "help":
                continue
            assert action.help, f"{path} {action.dest} has no help"
            if action.default not in (None, False, [], "==SUPPRESS=="):
                assert str(action.default).rstrip("0").rstrip(".") in action.help or "default" in action.help, \
                    f"{path} {action.dest}: the help does not show the default {action.default!r}"

"""Bad input never gives a traceback, a silent result or a changed file: a generated sweep over the CLI.

For every subcommand the matrix is generated from the parser itself: each numeric option's
declared domain (``common.Number.invalid``: every option has an upper bound, so the matrix holds a
value just above it), each input file broken in the usual ways (missing,
empty, truncated, a folder, the wrong kind of content), and each output that exists already or
cannot be written. Every case must exit with 2, name the problem on stderr, print no traceback,
and leave the working folder exactly as it was. Heavy computations are replaced by a tripwire,
so a bad value that slips through fails at once instead of running an FEM.
"""
from __future__ import annotations

import argparse
import hashlib
import math
import os
from pathlib import Path

import pytest

from roughness.cli import build_parser, main
from roughness.cli.common import Number

# A valid invocation per subcommand (paths relative to the case folder, made by ``_inputs``).
BASE: dict[tuple[str, ...], list[str]] = {
    ("simulate",): ["map.npy", "--pixel-mm", "0.05", "--fidelity", "coarse"],
    ("texture", "make"): ["standard-1.0", "--out", "new.npy"],
    ("texture", "list"): [],
    ("dataset", "build"): ["--out", "new.h5", "--n", "2"],
    ("dataset", "info"): ["data.h5"],
    ("dataset", "verify"): ["data.h5"],
    ("dataset", "labels"): ["data.h5", "--out", "new.jsonl.gz"],
    ("train",): ["data.h5", "--out", "run"],
    ("export",): ["checkpoint.pt", "--out", "new.onnx"],
    ("predict",): ["map.npy", "--pixel-mm", "0.05", "--engine", "surrogate"],
    ("compare",): ["maps", "--pixel-mm", "0.05", "--out", "report", "--engines", "ra", "--reference", "p90"],
    ("jnd",): ["map.npy", "map.npy", "--pixel-mm", "0.05", "--engine", "surrogate"],
    ("perception", "embed"): ["trials.csv", "--out", "emb", "--folds", "2", "--resamples", "2", "--workers", "1"],
    ("perception", "fit"): ["embedding.csv", "--stimuli", "stimuli.csv", "--out", "fit", "--engine", "fem:coarse"],
    ("perception", "design"): ["--stimuli", "stimuli.csv", "--trials", "10", "--out", "design.csv"],
    ("perception", "simulate"): ["--stimuli", "stimuli.csv", "--truth", "truth.csv", "--trials", "10", "--out", "sim"],
    ("homogeneity",): ["map.npy", "--pixel-mm", "0.05", "--n", "5"],
    ("tune",): ["map.npy", "--pixel-mm", "0.05", "--target-lambda", "1.0", "--out", "new.npz"],
    ("palette",): ["--k", "3", "--out", "pal"],
    ("tactile-image",): ["picture.png", "--out", "plate"],
    ("hidden-shapes",): ["--mask", "picture.png", "--out", "plate"],
    ("perception", "plan"): ["--stimuli", "stimuli.csv", "--truth", "truth.csv", "--trials", "10", "--experiments", "2",
                             "--out", "plan"],
    ("object", "feel"): ["mesh.stl", "--texture", "standard-1.0"],
    ("object", "tune"): ["mesh.stl", "--texture", "standard-1.0", "--target-lambda", "1.0", "--out", "new.npz"],
    ("object", "texture"): ["mesh.stl", "--texture", "standard-1.0", "--out", "new.stl"],
    ("ensemble",): ["checkpoint.pt", "checkpoint.pt", "--out", "new.onnx"],
    ("card",): ["run", "model.onnx", "--card", "new.md", "--plots", "."],
    ("model-version",): ["model.onnx", "--version", "2"],
    ("fuzzy-skin",): ["--engine", "surrogate", "--draws", "1"],
    ("studio",): ["--no-browser"],  # every case is refused by argparse before a server starts
}
# Input files per subcommand: (position in BASE or flag, suffix the broken file gets, extra arguments).
FILE_INPUTS: dict[tuple[str, ...], list[tuple[int | str, str, list[str]]]] = {
    ("simulate",): [(0, ".npy", [])],
    ("dataset", "build"): [("--recipe", ".json", []), ("--labels", ".gz", [])],
    ("dataset", "info"): [(0, ".h5", [])],
    ("dataset", "verify"): [(0, ".h5", [])],
    ("dataset", "labels"): [(0, ".h5", [])],
    ("train",): [(0, ".h5", [])],
    ("export",): [(0, ".pt", [])],
    ("predict",): [(0, ".npy", []), ("--model", ".onnx", [])],
    ("compare",): [(0, ".json", ["--n", "2"]), (0, ".h5", [])],
    ("jnd",): [(0, ".npy", []), (1, ".png", [])],
    ("perception", "embed"): [(0, ".csv", []), ("--stimuli", ".csv", [])],
    ("perception", "fit"): [(0, ".csv", []), ("--stimuli", ".csv", [])],
    ("perception", "design"): [("--stimuli", ".csv", [])],
    ("perception", "simulate"): [("--stimuli", ".csv", []), ("--truth", ".csv", [])],
    ("homogeneity",): [(0, ".npy", [])],
    ("tune",): [(0, ".npy", [])],
    ("tactile-image",): [(0, ".png", [])],
    ("hidden-shapes",): [("--mask", ".png", []), ("--texture", ".npy", ["--pixel-mm", "0.05"])],
    ("perception", "plan"): [("--stimuli", ".csv", []), ("--truth", ".csv", [])],
    ("object", "feel"): [(0, ".stl", []), ("--texture", ".npy", ["--pixel-mm", "0.05"])],
    ("object", "tune"): [(0, ".stl", []), ("--texture", ".npy", ["--pixel-mm", "0.05"])],
    ("object", "texture"): [(0, ".stl", []), ("--texture", ".npy", ["--pixel-mm", "0.05"])],
    ("ensemble",): [(0, ".pt", [])],
    ("card",): [(1, ".onnx", [])],
    ("model-version",): [(0, ".onnx", [])],
    ("fuzzy-skin",): [("--config", ".ini", []), ("--config", ".json", []), ("--config", ".3mf", [])],
}
# Outputs that must not be replaced without --overwrite, nor fail after the work is done.
FILE_OUTPUTS: dict[tuple[str, ...], list[str]] = {
    ("simulate",): ["--save-strain", "--save-vtu"],
    ("texture", "make"): ["--out"],
    ("dataset", "labels"): ["--out"],
    ("train",): ["--out"],
    ("export",): ["--out"],
    ("predict",): ["--map"],
    ("perception", "design"): ["--out"],
    ("homogeneity",): ["--map"],
    ("tune",): ["--out"],
    ("palette",): ["--out"],
    ("tactile-image",): ["--out"],
    ("hidden-shapes",): ["--out"],
    ("object", "feel"): ["--picture"],
    ("object", "tune"): ["--out", "--mesh-out"],
    ("object", "texture"): ["--out", "--preview"],
    ("ensemble",): ["--out", "--int8"],
    ("card",): ["--card"],
    ("fuzzy-skin",): ["--out", "--plot"],
}
OUTPUT_SUFFIX = {"--save-strain": ".png", "--save-vtu": ".vtu", "--map": ".npy", "--preview": ".png",
                 "--picture": ".png", "--mesh-out": ".stl", "--int8": ".onnx"}
OUTPUT_SUFFIX_OF = {("homogeneity",): {"--map": ".png"}, ("fuzzy-skin",): {"--out": ".npz", "--plot": ".png"}}


def _subcommands(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()):
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        yield path, parser
        return
    for name, sub in subs[0].choices.items():
        yield from _subcommands(sub, (*path, name))


PARSERS = dict(_subcommands(build_parser()))


def _domain(action: argparse.Action) -> Number | None:
    """The Number an option's values are parsed with: its type, or the ``kind`` of a list of numbers."""
    return action.type if isinstance(action.type, Number) else getattr(action.type, "kind", None)


# Option types that parse numbers without a Number, each bounded where its value is used: --centre by
# MAX_COORDINATE_MM (test_limits.py), --widths by MAX_CHANNELS, --detrend's cut-off by MAX_LENGTH_MM; --exclude
# holds names.
OTHER_TYPES = {"float_pair", "count_list", "_detrend_spec", "id_list"}


def _numeric_cases() -> list[tuple[tuple[str, ...], str, str]]:
    cases = []
    for path, parser in PARSERS.items():
        for action in parser._actions:
            if _domain(action) is not None:
                cases += [(path, action.option_strings[-1], value) for value in _domain(action).invalid]
    return cases


def _file_cases() -> list[tuple[tuple[str, ...], int | str, str, list[str], str]]:
    kinds = ("missing", "empty", "truncated", "folder", "garbage")
    return [(path, where, suffix, extra, kind) for path, inputs in FILE_INPUTS.items()
            for where, suffix, extra in inputs for kind in kinds]


def _output_cases() -> list[tuple[tuple[str, ...], str, str]]:
    return [(path, flag, kind) for path, flags in FILE_OUTPUTS.items() for flag in flags
            for kind in ("exists", "no-folder")]


def _snapshot(folder: Path) -> dict[str, str]:
    out = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs:
            out[os.path.relpath(os.path.join(root, name), folder) + "/"] = "dir"
        for name in files:
            p = os.path.join(root, name)
            out[os.path.relpath(p, folder)] = hashlib.sha1(Path(p).read_bytes()).hexdigest()
    return out


def _run(argv: list[str], capsys) -> tuple[int, str]:
    try:
        code = main(argv)
    except SystemExit as exit_:  # argparse
        code = exit_.code
    return code, capsys.readouterr().err


def _expect_refusal(argv: list[str], workdir: Path, capsys, names: tuple[str, ...]) -> None:
    before = _snapshot(workdir)
    code, err = _run(argv, capsys)
    assert code == 2, f"{argv}: exit {code}, stderr: {err[-500:]}"
    assert "Traceback" not in err, err
    assert any(n in err for n in names), f"{argv}: the message does not name {names}: {err[-500:]}"
    assert _snapshot(workdir) == before, f"{argv} changed files"


def test_every_numeric_option_declares_its_domain():
    loose = [(" ".join(path), a.option_strings[-1]) for path, parser in PARSERS.items() for a in parser._actions
             if a.type in (int, float)]
    assert not loose, f"options typed plain int/float (use common.Number with a domain): {loose}"


def test_every_numeric_option_declares_an_upper_bound():
    """Nothing touchable needs 1e300 of anything: each number has a stated largest value, and the sweep tries one
    just above it (an option without one once read --radius-mm 1e300 into garbage heights)."""
    unbounded, untested, others = [], [], set()
    for path, parser in PARSERS.items():
        for action in parser._actions:
            domain, where = _domain(action), (" ".join(path), action.option_strings[-1] if action.option_strings else "")
            if domain is None:
                if action.type is not None:
                    others.add(getattr(action.type, "__name__", repr(action.type)))
                continue
            if domain.high is None:
                unbounded.append(where)
            elif not any(_beyond(domain, v) for v in domain.invalid):
                untested.append(where)
    assert not unbounded, f"numeric options without an upper bound: {unbounded}"
    assert not untested, f"numeric options whose sweep has no value above the bound: {untested}"
    assert others == OTHER_TYPES, f"options parsed by a type that is not a common.Number: {others - OTHER_TYPES}"


def _beyond(domain: Number, text: str) -> bool:
    """True if ``text`` is a finite number of the domain's kind on or past its upper bound (past it if closed)."""
    try:
        value = domain.kind(text)
    except ValueError:
        return False
    return math.isfinite(value) and (value >= domain.high if domain.high_open else value > domain.high)


def test_every_option_has_help():
    missing = [(" ".join(path), a.option_strings[-1] if a.option_strings else a.dest)
               for path, parser in PARSERS.items() for a in parser._actions
               if not a.help and not isinstance(a, argparse._SubParsersAction)]
    assert not missing, f"options without help: {missing}"


def test_the_sweep_covers_every_subcommand():
    assert set(PARSERS) == set(BASE)


@pytest.mark.parametrize("path, flag, value", _numeric_cases(), ids=lambda v: str(v))
def test_numeric_option_out_of_domain(path, flag, value, workdir, capsys):
    _expect_refusal([*path, *BASE[path], flag, value], workdir, capsys, (flag,))


@pytest.mark.parametrize("value", ["8,0", "8,-16", "8,a", "", "8.5"])
def test_bad_channel_widths_are_refused(value, workdir, capsys):
    _expect_refusal(["train", *BASE[("train",)], "--widths", value], workdir, capsys, ("--widths",))


@pytest.mark.parametrize("path, where, suffix, extra, kind", _file_cases(), ids=lambda v: str(v))
def test_broken_input_file(path, where, suffix, extra, kind, workdir, capsys):
    name = f"broken{suffix}"
    target = workdir / name
    if kind == "empty":
        target.write_bytes(b"")
    elif kind == "truncated":
        target.write_bytes({".json": b'{"seed": 1', ".npy": b"\x93NUMPY\x01\x00v\x00{'descr'"}.get(suffix, b"\x89HDF\r"))
    elif kind == "folder":
        target.mkdir()
    elif kind == "garbage":
        target.write_bytes(bytes(range(256)) * 4)
    argv = [*BASE[path], *extra]
    if isinstance(where, int):
        argv[where] = name
    else:
        argv += [where, name]
    _expect_refusal([*path, *argv], workdir, capsys, (name,))


@pytest.mark.parametrize("path, flag, kind", _output_cases(), ids=lambda v: str(v))
def test_output_that_exists_or_cannot_be_written(path, flag, kind, workdir, capsys):
    argv = list(BASE[path])
    suffix = OUTPUT_SUFFIX_OF.get(path, {}).get(flag, OUTPUT_SUFFIX.get(flag, ""))
    if flag in argv:
        name = argv[argv.index(flag) + 1]
    else:
        name = f"out{suffix}"
        argv += [flag, name]
    if kind == "exists":
        target = workdir / name
        if suffix or Path(name).suffix:
            target.write_bytes(b"precious")
        else:
            target.mkdir()
            (target / "precious.txt").write_text("precious")
    else:
        argv[argv.index(flag) + 1] = str(Path("no-such-folder") / Path(name).name)
        name = "no-such-folder"
    _expect_refusal([*path, *argv], workdir, capsys, (name,))

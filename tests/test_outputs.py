"""Outputs never destroy data: not an input, not another output, not a concurrent writer's file, not
silently on a full disk, not one palette member over another (issue 26, root cause 3 and part of 8).

The collision cases extend the bad-input matrix of tests/test_bad_inputs.py: they are generated
from a table of every path option of every subcommand (kept complete by a test that reads the
parsers), and each must exit 2 with its reason and leave the case folder as it was.
"""
from __future__ import annotations

import argparse
import errno
import json
import os
import resource
import signal
import subprocess
import sys
import time
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest

from roughness.core.errors import InputError, OutputExists
from roughness.core.files import atomic_write, check_distinct
from test_bad_inputs import BASE, PARSERS, _expect_refusal, _run

# Every path option of every subcommand: (inputs it reads, outputs it writes). An input is a position
# in BASE's argv or a flag; a flag absent from BASE gets INPUT_VALUE's file.
PATHS: dict[tuple[str, ...], tuple[list[int | str], list[str]]] = {
    ("simulate",): ([0], ["--save-strain", "--save-vtu"]),
    ("texture", "make"): ([], ["--out"]),
    ("texture", "list"): ([], []),
    ("dataset", "build"): (["--recipe", "--labels", "--scheduler-file"], ["--out"]),
    ("dataset", "labels"): ([0], ["--out"]),
    ("dataset", "info"): ([0], []),
    ("dataset", "verify"): ([0], []),
    ("train",): ([0, "--extra-data"], ["--out"]),
    ("export",): ([0], ["--out", "--int8"]),
    ("predict",): ([0, "--model", "--printer", "--scheduler-file"], ["--map"]),
    ("compare",): ([0], ["--out"]),
    ("jnd",): ([0, 1, "--model", "--printer"], []),
    ("perception", "embed"): ([0, "--stimuli"], ["--out"]),
    ("perception", "fit"): ([0, "--stimuli"], ["--out"]),
    ("perception", "design"): (["--stimuli"], ["--out", "--plates"]),
    ("perception", "simulate"): (["--stimuli", "--truth"], ["--out"]),
    ("perception", "plan"): (["--stimuli", "--truth"], ["--out"]),
    ("homogeneity",): ([0, "--model", "--printer"], ["--map"]),
    ("tune",): ([0, "--like", "--model", "--printer"], ["--out"]),
    ("palette",): (["--from", "--model", "--printer"], ["--out"]),
    ("tactile-image",): ([0, "--palette", "--model", "--printer"], ["--out"]),
    ("hidden-shapes",): (["--mask", "--texture"], ["--out"]),
    ("object", "texture"): ([0, "--texture", "--printer"], ["--out", "--preview"]),
    ("object", "feel"): ([0, "--texture", "--printer"], ["--picture"]),
    ("object", "tune"): ([0, "--texture", "--printer"], ["--out", "--mesh-out"]),
    ("ensemble",): ([0, "--data"], ["--out", "--int8"]),
    ("card",): ([1, "--latency"], ["--card"]),
    ("model-version",): ([0], []),  # rewritten in place
    ("fuzzy-skin",): (["--config", "--printer"], ["--out", "--plot"]),
    ("studio",): ([], []),  # a server: files come by upload and go to a per-session temporary folder
}
# String options that are not files: names, lists of names, addresses; --cache is a folder of FEM
# results that a run reads and adds to (never replaces); card's RUN is a folder it reads two files from and
# --plots one it writes two into (they may be one folder): their files are checked by test_card_outputs_*.
# tactile-image's --background, --line-colour and --key-labels are colours (and text), --braille-table a liblouis
# table name, --assign a colour mapping (or @FILE, read only, as text).
NOT_PATHS = {"NAME", "--param", "--scheduler", "--holdout-family", "--engines", "--reference", "--roughest",
             "--family", "--cache", "--axis", "--region", "RUN", "--plots", "--background", "--line-colour",
             "--key-labels", "--braille-table", "--assign", "--host"}
INPUT_VALUE = {"--recipe": "recipe.json", "--labels": "labels.jsonl.gz", "--extra-data": "data.h5",
               "--model": "model.onnx", "--like": "map.npy", "--from": "maps", "--palette": "maps",
               "--stimuli": "stimuli.csv", "--printer": "printer.json", "--scheduler-file": "scheduler.json",
               "--data": "data.h5", "--latency": "latency.json", "--config": "fuzzy.ini", "--texture": "map.npy"}
EXCLUDES = {"--like": "--target-lambda"}  # an input flag and the BASE option it cannot go with


def _string_options(parser: argparse.ArgumentParser) -> set[int | str]:
    """The options (flags) and positionals (their index) that take a free string: the candidates for paths."""
    found: set[int | str] = set()
    positionals = [a for a in parser._actions if not a.option_strings and not isinstance(a, argparse._SubParsersAction)]
    for action in parser._actions:
        if action.type is not None or action.choices or action.nargs == 0 or action.dest == "help":
            continue
        if action.option_strings:
            found.add(action.option_strings[-1])
        else:
            found.add(action.metavar if action.metavar in NOT_PATHS else positionals.index(action))
    return found


def test_every_path_option_is_classified():
    assert set(PATHS) == set(PARSERS)
    for path, parser in PARSERS.items():
        inputs, outputs = PATHS[path]
        assert _string_options(parser) == {*inputs, *outputs, *(_string_options(parser) & NOT_PATHS)}, path


def _with(argv: list[str], where: int | str, value: str) -> list[str]:
    """``argv`` with the argument at ``where`` (a position or a flag) set to ``value``."""
    argv = list(argv)
    if where in EXCLUDES and EXCLUDES[where] in argv:
        del argv[argv.index(EXCLUDES[where]):argv.index(EXCLUDES[where]) + 2]
    if isinstance(where, int):
        argv[where] = value
    elif where in argv:
        argv[argv.index(where) + 1] = value
    else:
        argv += [where, value]
    return argv


def _value(argv: list[str], where: int | str) -> str:
    if isinstance(where, int):
        return argv[where]
    return argv[argv.index(where) + 1] if where in argv else INPUT_VALUE[where]


def _overwrite(path: tuple[str, ...]) -> list[str]:
    return ["--overwrite"] if any("--overwrite" in a.option_strings for a in PARSERS[path]._actions) else []


def _same_as_input_cases():
    return [(path, where, out) for path, (inputs, outputs) in PATHS.items() for where in inputs for out in outputs]


@pytest.mark.parametrize("path, where, out", _same_as_input_cases(), ids=lambda v: str(v))
def test_an_output_that_is_an_input_is_refused_even_with_overwrite(path, where, out, workdir, capsys):
    """`dataset labels D --out D`, `export C --out C`, `predict H --map H` ...: exit 2, the input intact."""
    for name in INPUT_VALUE.values():
        if not (workdir / name).exists():
            (workdir / name).write_bytes(b"precious")
    argv = _with(BASE[path], where, _value(BASE[path], where))
    argv = _with(argv, out, "./" + _value(argv, where))  # spelled differently: compared as files
    _expect_refusal([*path, *argv, *_overwrite(path)], workdir, capsys, ("is also an input",))


@pytest.mark.parametrize("path, input_flag, folder, name", [
    (("perception", "simulate"), "--truth", "sim", "truth.csv"),
    (("perception", "plan"), "--truth", "plan", "plan.csv"),
    (("perception", "embed"), 0, "emb", "embedding.csv"),
    (("perception", "fit"), 0, "fit", "fit.csv"),
], ids=str)
def test_an_output_folder_does_not_replace_an_input_inside_it(path, input_flag, folder, name, workdir, capsys):
    """`perception simulate --truth sim/truth.csv --out sim --overwrite` would write sim/truth.csv over its input."""
    (workdir / folder).mkdir()
    source = _value(BASE[path], input_flag)
    (workdir / folder / name).write_bytes((workdir / source).read_bytes())
    argv = _with(_with(BASE[path], input_flag, f"{folder}/{name}"), "--out", folder)
    _expect_refusal([*path, *argv, "--overwrite"], workdir, capsys, ("is also an input",))


@pytest.mark.parametrize("argv, reason", [
    (["--card", "run/history.csv"], "is also an input"),
    (["--card", "./surrogate_training.png"], "name the same file"),
    (["--latency", "surrogate_accuracy.png"], "is also an input"),
], ids=str)
def test_card_outputs_replace_no_input_and_no_other_output(argv, reason, workdir, capsys):
    """The card's folders: RUN's predictions.csv and history.csv are inputs, the plots in --plots outputs."""
    (workdir / "run").mkdir()
    for name in ("run/predictions.csv", "run/history.csv", "model.onnx", "surrogate_accuracy.png"):
        (workdir / name).write_bytes(b"precious")
    base = ["card", "run", "model.onnx", "--plots", ".", "--overwrite"]
    _expect_refusal([*base, *(["--card", "new.md"] if "--card" not in argv else []), *argv], workdir, capsys,
                    (reason,))

def _two_outputs_cases():
    return [(path, a, b) for path, (_, outputs) in PATHS.items() for a, b in combinations(outputs, 2)]


@pytest.mark.parametrize("path, first, second", _two_outputs_cases(), ids=lambda v: str(v))
def test_two_outputs_naming_one_file_are_refused(path, first, second, workdir, capsys):
    """`simulate --save-strain X --save-vtu X`: one would replace the other."""
    argv = _with(_with(BASE[path], first, "twice.out"), second, "twice.out")
    _expect_refusal([*path, *argv, *_overwrite(path)], workdir, capsys, ("name the same file",))


def test_same_file_through_a_link_or_another_spelling(tmp_path):
    (tmp_path / "a.npy").write_bytes(b"x")
    os.link(tmp_path / "a.npy", tmp_path / "hard.npy")
    os.symlink(tmp_path / "a.npy", tmp_path / "soft.npy")
    for other in ("hard.npy", "soft.npy", "sub/../a.npy"):
        with pytest.raises(InputError, match="is also an input"):
            check_distinct({"--out": tmp_path / other}, {"HEIGHTMAP": tmp_path / "a.npy"})
    check_distinct({"--out": tmp_path / "b.npy", "--map": tmp_path / "c.npy"}, {"HEIGHTMAP": tmp_path / "a.npy"})


# --- concurrent writers ---------------------------------------------------------------------------

# Each writer waits when its temporary file is written (the output checked absent, not yet published)
# until all have arrived: the check-then-rename race, lost by every writer but one, every time.
WRITER = """
import os, sys, time
from pathlib import Path
import numpy as np
save = np.save
def held(*args, **kwargs):
    save(*args, **kwargs)
    Path(f"ready-{os.getpid()}").touch()
    while not Path("go").exists():
        time.sleep(0.005)
np.save = held
from roughness.cli import main
sys.exit(main(["texture", "make", "standard-1.0", "--out", "same.npy", "--size-mm", "4"]))
"""


def test_concurrent_writers_without_overwrite_exactly_one_wins(tmp_path):
    n = 6
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    procs = [subprocess.Popen([sys.executable, "-c", WRITER], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(n)]
    deadline = time.monotonic() + 60
    while len(list(tmp_path.glob("ready-*"))) < n and time.monotonic() < deadline:
        if any(p.poll() is not None for p in procs):
            break
        time.sleep(0.01)
    assert len(list(tmp_path.glob("ready-*"))) == n, [p.communicate() for p in procs]
    (tmp_path / "go").touch()
    results = [(p.wait(30), p.stderr.read()) for p in procs]
    codes = sorted(code for code, _ in results)
    assert codes == [0] + [2] * (n - 1), results
    assert all("same.npy already exists; pass --overwrite" in err for code, err in results if code == 2)
    heights = np.load(tmp_path / "same.npy")
    assert heights.shape == (80, 80) and np.isfinite(heights).all() and heights.max() > 0
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith("ready-")) == ["go", "same.npy"]


def test_atomic_write_without_overwrite_never_replaces(tmp_path):
    path = tmp_path / "a.txt"
    atomic_write(path, lambda tmp: Path(tmp).write_text("first"), overwrite=False)
    with pytest.raises(OutputExists):
        atomic_write(path, lambda tmp: Path(tmp).write_text("second"), overwrite=False)
    assert path.read_text() == "first" and [p.name for p in tmp_path.iterdir()] == ["a.txt"]
    atomic_write(path, lambda tmp: Path(tmp).write_text("third"), overwrite=True)
    assert path.read_text() == "third"


# --- full disk ------------------------------------------------------------------------------------

def _no_space(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


def test_full_disk_during_texture_make(workdir, capsys, monkeypatch):
    monkeypatch.setattr(np, "save", _no_space)
    _expect_refusal(["texture", "make", "standard-1.0", "--out", "new.npy"], workdir, capsys,
                    ("cannot write new.npy: no space left on device",))


@pytest.mark.parametrize("free, reason", [(0, "no space left on device"), (10**9, "the write stopped short")])
def test_a_short_write_without_errno_is_explained(free, reason, tmp_path, monkeypatch):
    """numpy reports a full disk as "640000 requested and 262128 written" (no errno): told by the free space."""
    import shutil
    from types import SimpleNamespace

    def short(tmp):
        raise OSError("640000 requested and 262128 written")

    monkeypatch.setattr(shutil, "disk_usage", lambda folder: SimpleNamespace(free=free))
    with pytest.raises(InputError, match=f"cannot write .*a.npy: {reason}"):
        atomic_write(tmp_path / "a.npy", short)
    assert not list(tmp_path.iterdir())


def _file_size_limit(limit: int):
    def apply():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit then fails with EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return apply


def test_a_real_short_write_is_an_error_without_a_partial_file(tmp_path):
    """A file size limit makes a real short write (as a full disk does): exit 2, a message, no file left."""
    result = subprocess.run([sys.executable, "-m", "roughness.cli", "texture", "make", "standard-1.0", "--out",
                             "big.npy"], cwd=tmp_path, capture_output=True, text=True,
                            preexec_fn=_file_size_limit(100_000), env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert result.returncode == 2, result.stderr
    assert "roughness: error: cannot write big.npy: " in result.stderr and "Traceback" not in result.stderr
    assert not list(tmp_path.iterdir())


def test_full_disk_while_train_saves_a_checkpoint(tmp_path, monkeypatch):
    """train's checkpoints go through atomic_write as plain bytes (torch's own writer says "unexpected pos")."""
    torch = pytest.importorskip("torch")
    from roughness.surrogate.run_files import save_torch

    save_torch({"w": torch.ones(3)}, tmp_path / "ok.pt")
    assert torch.load(tmp_path / "ok.pt", weights_only=True)["w"].sum() == 3
    monkeypatch.setattr(Path, "write_bytes", _no_space)
    with pytest.raises(InputError, match="cannot write .*checkpoint.pt: no space left on device"):
        save_torch({"w": torch.ones(3)}, tmp_path / "checkpoint.pt")
    assert [p.name for p in tmp_path.iterdir()] == ["ok.pt"]


def test_full_disk_during_train_is_exit_2_and_leaves_no_run_folder(tmp_path, capsys, monkeypatch):
    """`roughness train` on a tiny store with a disk that fills at the first checkpoint: a message, exit 2."""
    pytest.importorskip("torch")
    from roughness.dataset.recipe import Recipe, realise, sample_record
    from roughness.dataset.writer import DatasetWriter
    from roughness.surrogate.patch import descriptors, footprint_patch
    from test_surrogate import CONFIG, fake_fields

    data = tmp_path / "small.h5"
    recipe = Recipe(name="tiny", seed=9, families={"bumps": 1, "fbm": 1, "grating": 1, "knurl": 1})
    with DatasetWriter(data, CONFIG, "test") as writer:
        for i in range(48):
            hm = realise(sample_record(recipe, i))
            writer.write_result(sample_record(recipe, i), hm.heights, hm.pixel_mm,
                                fake_fields(0.05 * descriptors(footprint_patch(hm))[2]), np.zeros((5, 5)))
    monkeypatch.setattr(Path, "write_bytes", _no_space)  # how train writes its checkpoints
    code, err = _run(["train", str(data), "--out", str(tmp_path / "run"), "--max-epochs", "1", "--batch-size", "8",
                      "--threads", "1", "--holdout-family", "knurl"], capsys)
    assert code == 2 and "Traceback" not in err, err
    assert "cannot write " in err and "resume.pt: no space left on device" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["small.h5"]


# --- palette members from files with one stem -----------------------------------------------------

def test_candidate_names_are_distinct(tmp_path):
    from roughness.design.palette import candidate_names

    files = [tmp_path / n for n in ("a.png", "tex.npy", "tex.npz", "z.h5")]
    assert candidate_names(files) == ["a", "tex.npy", "tex.npz", "z"]
    with pytest.raises(InputError, match=r"Tex\.npy and .*tex\.npy would both be the palette member"):
        candidate_names([tmp_path / "Tex.npy", tmp_path / "tex.npy"])


def test_palette_from_a_folder_with_one_stem_twice_keeps_both_textures(workdir, capsys, monkeypatch):
    """tex.npy and tex.npz were one member file: tactile-image then printed one texture in two regions."""
    from roughness.dataset.textures import standard_texture
    from roughness.design.evaluation import Evaluator, Verified
    from roughness.design.palette import load_palette

    def verify(self, hm, tile=False):  # the surrogate's answer as the "FEM" answer: no FEM in this test
        v = float(self.surrogate([hm], tile=tile)[0][0])
        return Verified(v, 0.0, self.lambda_of(v), True, 0.0)

    monkeypatch.setattr(Evaluator, "verify", verify)
    smooth, rough = standard_texture(0.625, seed=2), standard_texture(1.625, seed=2)
    (workdir / "cands").mkdir()
    np.save(workdir / "cands" / "tex.npy", smooth.heights)
    np.savez(workdir / "cands" / "tex.npz", heightmap=rough.heights, pixel_mm=rough.pixel_mm)
    code, err = _run(["palette", "--k", "2", "--min-jnd", "2", "--from", "cands", "--pixel-mm", str(smooth.pixel_mm),
                      "--out", "pal", "--quiet"], capsys)
    assert code == 0, err
    members = load_palette(workdir / "pal")
    assert [name for name, _, _ in members] == ["tex.npy", "tex.npz"]
    assert np.array_equal(members[0][1].heights, smooth.heights)
    assert np.array_equal(members[1][1].heights, rough.heights)
    from PIL import Image

    rgb = np.zeros((20, 40, 3), dtype=np.uint8)
    rgb[:, :20], rgb[:, 20:] = (250, 250, 250), (20, 20, 90)
    Image.fromarray(rgb).save(workdir / "two.png")
    code, err = _run(["tactile-image", "two.png", "--palette", "pal", "--out", "plate", "--size-mm", "40",
                      "--step-mm", "2", "--background", "none", "--json", "--quiet"], capsys)  # both textured
    assert code == 0, err
    regions = json.loads((workdir / "plate" / "plate.json").read_text())["regions"]
    assert [r["texture"] for r in regions] == ["tex.npy", "tex.npz"]
    assert regions[1]["plate_roughness"] > 2 * regions[0]["plate_roughness"]  # lambda 1.625 vs 0.625 mm: ~7x


def test_tactile_image_refuses_a_palette_with_one_member_file_twice(workdir, capsys):
    """A palette folder written before the fix lists one name twice: refused, not printed as two textures."""
    from roughness.dataset.textures import standard_texture
    from roughness.surface.io import save_heightmap

    (workdir / "old").mkdir()
    save_heightmap(standard_texture(1.0), workdir / "old" / "tex.npz")
    members = [{"name": "tex", "fem_roughness": v} for v in (0.05, 0.09)]
    (workdir / "old" / "palette.json").write_text(json.dumps({"members": members}))
    _expect_refusal(["tactile-image", "picture.png", "--palette", "old", "--out", "plate"], workdir, capsys,
                    ("lists two members named 'tex'",))

"""Clear messages (issue 26, root cause 9): errors name the option the value came from, pictures are read
as what they are, simulated trials embed with default options, a disconnected design is warned about."""
from __future__ import annotations

import argparse
import ast
import itertools
import json
import re
from importlib import import_module
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from PIL import Image

from conftest import source_modules
from roughness.cli import COMMANDS, build_parser, main
from roughness.cli.common import error_message
from roughness.core.errors import InputError
from roughness.design.tactile_image import flat_colours, read_image
from roughness.design.tune import Target, tune
from roughness.perception.trials import parse_trials
from roughness.simulate.config import SimConfig
from roughness.simulate.curved import FLAT
from roughness.simulate.model import _require_small_strain_regime
from roughness.surface.heightmap import Heightmap

REPO = Path(__file__).resolve().parents[1]


def _leaves(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()):
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        yield path, parser
    for sub in subs:
        for name, child in sub.choices.items():
            yield from _leaves(child, path + (name,))


def _names(parser: argparse.ArgumentParser) -> set[str]:
    """The Python names a subcommand's errors may use: its flags' dests, their aliases, its positionals."""
    return set(parser.get_default("flags") or {}) | {a.dest for a in parser._actions if not a.option_strings}


def _flags(command: str) -> dict[str, str]:
    parser = dict(_leaves(build_parser()))[tuple(command.split())]
    return parser.get_default("flags")


def _cli(argv: list[str], capsys) -> tuple[int, str]:
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


# --- every parameter= names a flag (or is documented as library-only) ----------------------------------------

# Names InputErrors carry that no subcommand has as an option: the library's own argument or field names, for
# Python callers (the CLI never passes a bad value there, or the CLI names its option on the way).
LIBRARY_ONLY = {
    "factor": "design.tune.scaled(factor): the CLI scales within --min-factor..--max-factor",
    "lambdas": "perception.crossval.cross_validate(lambdas): the CLI takes one --lambda or cross-validates",
    "textures": "design.tactile_image.tactile_image(textures): the CLI checks --k / --palette first",
    "pairs": "SimConfig field (not an option)", "max_rounds": "SimConfig field", "h_contact_mm": "SimConfig field",
    "depth_mm": "SimConfig field", "pair_distance_mm": "SimConfig field",
    "cutoff_mm": "simulate.detrend.Detrend field (--detrend lowpass:MM is checked as it is parsed); fbm parameter",
    "footprint width": "Heightmap.covers / max_in_footprint: the skin footprint width of a checked SimConfig/model",
    # fields of a recipe file (load_recipe names the file and drops the parameter) or of --param KEY=VALUE
    "families": "recipe field", "ranges": "recipe field", "perturb_probability": "recipe field",
    "print_probability": "recipe field", "printers": "recipe field",
    "reach_mm": "objects.sampling.sample_heightmap(reach_mm): a library function the CLI does not call",
    "max_perturb_steps": "recipe field", "test_fraction": "recipe field", "max_steps": "perturbation (recipe)",
    "hurst": "texture parameter (--param)", "rms_mm": "texture parameter (--param)",
    "lambda_mm": "texture parameter (--param)", "base_diameter_mm": "texture parameter (--param)",
    "top": "texture parameter (--param)", "top_diameter_mm": "texture parameter (--param)",
    "flat_state": "SpectralSimulator(flat_state): studies compare the flat states; the CLI uses the default",
    "pressure": "SpectralSimulator(pressure): a study parameter; the CLI uses the flat state's pressure",
    "client": "dataset.build.build(client): a dask.distributed.Client; the CLI takes --scheduler(-file)",
    "picture": "roughness.tactile_image(picture): an RGB or grey array from Python; the CLI reads a PICTURE file",
    "heights": "Heightmap(heights): an array from Python; a file's heights are checked as it is read, naming it",
    "options": "roughness.predict(options=PredictOptions(...)): the CLI has a flag per field",
    "config": "Simulator(config) / fem_roughness(config=SimConfig(...)): the CLI builds it from its flags",
    "simulator": "fem_roughness(simulator=Simulator(...)): a prepared simulator from Python",
    "max_blocks": "Simulator(max_blocks): blocks kept per process; the CLI keeps the default",
    "factor_range": "roughness.tune(factor_range=(lo, hi)): the CLI has --min-factor and --max-factor",
    "path": "load_scale(path): another scale table from Python; the CLI uses the shipped one",
    "span": "design.shapes.builtin_mask(span): the CLI draws the built-in shapes at the default span",
    "region_b": "design.look.compare(region_a, region_b): masks from Python; hidden-shapes makes them from the shape",
    "elevation_deg": "design.look.render(elevation_deg): the CLI renders under the standard light",
    "azimuths": "design.look.render(azimuths): the CLI renders under the standard light",
    **{name: "printer profile field (a JSON profile's; load_profile reports it under --printer)"
       for name in ("nozzle_mm", "layer_mm", "line_width_mm", "closing_radius_mm")},
    "max_runs": "fuzzy_tune.tune_fuzzy_skin(max_runs): the CLI uses the default number of verifications",
    "grid": "fuzzy_tune.tune_fuzzy_skin(grid): a KnobScan fuzzy_palette shares among its members",
}
CHECK_HELPERS = {"real": 0, "positive": 0, "non_negative": 0, "in_range": 0, "integer": 0,
                 "check_output": 2, "check_output_folder": 2}  # function -> position of its parameter-name argument


def _parameter_names(path: Path) -> list[tuple[int, str]]:
    """(line, name) of every literal parameter name in a file: InputError(..., parameter=...) or its second
    positional argument, and the name argument of the checks in src/roughness/core (checks.py, files.py)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.Call):
            continue
        fn = node.func.id if isinstance(node.func, ast.Name) else getattr(node.func, "attr", None)
        if fn in ("InputError", "OutputExists"):
            given = [k.value for k in node.keywords if k.arg == "parameter"] + node.args[1:2]
        elif fn in CHECK_HELPERS:
            given = node.args[CHECK_HELPERS[fn]:CHECK_HELPERS[fn] + 1]
        else:
            continue
        out += [(node.lineno, v.value) for v in given if isinstance(v, ast.Constant) and isinstance(v.value, str)]
    return out


def _sources() -> list[Path]:
    return sorted(source_modules().values())


def test_every_parameter_name_is_a_flag_or_library_only():
    known = set().union(*(_names(p) for _, p in _leaves(build_parser())))
    found = [(path, line, name) for path in _sources() for line, name in _parameter_names(path)]
    assert len(found) > 100  # the scan sees the raises (a broken scan would pass vacuously)
    unknown = [f"{p.relative_to(REPO)}:{line} {name!r}" for p, line, name in found
               if name not in known and name not in LIBRARY_ONLY]
    assert not unknown, f"parameter names that are no option of any subcommand (name the real one): {unknown}"
    stale = set(LIBRARY_ONLY) - {name for _, _, name in found}
    assert not stale, f"LIBRARY_ONLY lists names no longer raised: {stale}"


def test_cli_modules_name_their_own_options():
    """A parameter raised in src/roughness/cli/X.py (or in a module of one of X's actions) names an option or
    positional of X's own subcommands."""
    for module in sorted(set(COMMANDS.values())):
        parser = argparse.ArgumentParser()
        command = import_module(f"roughness.cli.{module}")
        command.add_parser(parser.add_subparsers())
        own = set().union(*(_names(p) for _, p in _leaves(parser)))
        for source in (module, *getattr(command, "ACTIONS", {}).values()):
            names = _parameter_names(source_modules()[f"roughness.cli.{source}"])
            wrong = [(line, name) for line, name in names if name not in own]
            assert not wrong, f"src/roughness/cli/{source}.py raises parameters it has no option for: {wrong}"


# --- curved bases: the radius, not the force -----------------------------------------------------------------

@pytest.mark.parametrize("radius", ["1e-9", "-1e-9", "0.5"])
def test_a_radius_far_below_the_footprint_names_curvature_not_force(radius, tmp_path, capsys):
    np.save(tmp_path / "map.npy", np.random.default_rng(0).random((240, 240)) * 0.05)
    code, err = _cli(["simulate", tmp_path / "map.npy", "--pixel-mm", "0.05", f"--curvature-mm={radius}"], capsys)
    assert code == 2
    assert "--curvature-mm" in err and "--force" not in err
    assert "at least 0.75 mm" in err and "not a curved surface" in err


def test_a_base_too_sharp_for_the_force_is_blamed_on_the_base():
    config = SimConfig(curvature_mm=1.0)
    deep = SimpleNamespace(indentation_mm=5 * config.tissue_mm)  # 5 tissue thicknesses: beyond the limit of 4
    with pytest.raises(InputError, match="before any texture: the base is too sharp") as err:
        _require_small_strain_regime(config, deep, config.base_shape(), base_indentation_mm=4.5 * config.tissue_mm)
    assert err.value.parameter == "curvature_mm" and "convex cylinder along x of radius 1 mm" in str(err.value)
    # the base alone within the limit: the texture pushed the skin that far, the force is to blame
    with pytest.raises(InputError, match="far too large for this texture") as err:
        _require_small_strain_regime(config, deep, config.base_shape(), base_indentation_mm=1.0)
    assert err.value.parameter == "force_n"
    with pytest.raises(InputError) as err:
        _require_small_strain_regime(SimConfig(), deep, FLAT, base_indentation_mm=4.5 * config.tissue_mm)
    assert err.value.parameter == "force_n"


# --- tune: the target's own option ---------------------------------------------------------------------------

class _FlatSurrogate:
    """An evaluator whose surrogate answers V = 0.01 for every texture (lambda 0.1 mm)."""

    footprint_mm = 10.0

    def surrogate(self, maps, tile=False):
        return np.full(len(maps), 0.01), np.zeros(len(maps))

    def lambda_of(self, v):
        return 0.1


@pytest.mark.parametrize("given_as, flag", [("like ref.npy", "--like"), ("roughness", "--target-v"),
                                            ("lambda", "--target-lambda")])
def test_an_out_of_reach_target_names_the_option_it_came_from(given_as, flag, monkeypatch):
    import roughness.design.tune

    flat = lambda factors: np.full(len(factors), 0.01)  # noqa: E731  (the spectral search, flat too)
    monkeypatch.setattr(roughness.design.tune, "_spectral_search", lambda *args: flat)
    hm = Heightmap(np.random.default_rng(0).random((40, 40)) * 0.1, 0.25)
    with pytest.raises(InputError, match="out of reach") as err:
        tune(hm, Target(0.5, 2.0, given_as), "height", _FlatSurrogate(), tile=True)
    message = error_message(err.value, _flags("tune"))
    assert message.startswith(f"{flag}: ")
    assert all(other not in message for other in ("--like", "--target-v", "--target-lambda") if other != flag)


# --- tactile-image: what the picture is ----------------------------------------------------------------------

def _grey16(levels: list[int]) -> np.ndarray:
    """A 60 x 60 16-bit greyscale picture in vertical stripes of the given levels."""
    a = np.zeros((60, 60), dtype=np.uint16)
    for i, level in enumerate(levels):
        a[:, i * 60 // len(levels):] = level
    return a


@pytest.mark.parametrize("suffix", [".png", ".tif"])
def test_16_bit_greyscale_levels_are_distinct_flat_colours(suffix, tmp_path):
    path = tmp_path / f"grey16{suffix}"
    Image.fromarray(_grey16([0, 20000, 40000])).save(path)  # Pillow's own RGB conversion clips both to white
    with Image.open(path) as image:
        assert image.mode.startswith("I")
    colours, labels = flat_colours(read_image(path))
    assert len(colours) == 3
    assert [tuple(c) for c in colours] == [(156,) * 3, (78,) * 3, (0,) * 3]  # v / 257, lightest first
    assert labels[0, 0] == 2 and labels[0, 30] == 1 and labels[0, 59] == 0


@pytest.mark.parametrize("ink", [(0, 0, 0), (255, 255, 255), (200, 30, 30)])
def test_a_logo_on_a_transparent_background_has_two_colours(ink, tmp_path):
    rgba = np.zeros((60, 60, 4), dtype=np.uint8)
    rgba[..., :3] = ink  # the same colour everywhere: the shape is in the alpha channel only
    rgba[15:45, 15:45, 3] = 255
    rgba[14, 15:25, 3] = 96  # anti-aliased edge pixels (under 0.5% of the picture) join the nearest colour
    Image.fromarray(rgba).save(tmp_path / "logo.png")
    colours, labels = flat_colours(read_image(tmp_path / "logo.png"))
    assert len(colours) == 2
    inside, outside = labels[30, 30], labels[0, 0]
    assert inside != outside and np.all(labels[15:45, 15:45] == inside) and (labels == inside).sum() == 30 * 30
    assert tuple(colours[inside]) == ink  # the logo keeps its colour; the background contrasts with it


def test_a_one_colour_picture_says_what_it_is_and_what_to_give(tmp_path, capsys):
    Image.fromarray(_grey16([30000])).save(tmp_path / "one.png")
    code, err = _cli(["tactile-image", tmp_path / "one.png", "--out", tmp_path / "plate"], capsys)
    assert code == 2 and "Traceback" not in err
    for part in ("16-bit greyscale", "mode I;16", "1 distinct colour", "#757575", "2 or more flat colours"):
        assert part in err, (part, err)
    assert not (tmp_path / "plate").exists()


def test_too_few_textures_name_the_option_given(tmp_path, capsys):
    Image.fromarray(_grey16([0, 20000, 40000])).save(tmp_path / "three.png")
    code, err = _cli(["tactile-image", tmp_path / "three.png", "--out", tmp_path / "plate", "--k", "2",
                      "--background", "none"], capsys)  # every colour textured (default: the background flat)
    assert code == 2 and "--k: the picture has 3 flat colours" in err and "--palette" not in err


# --- perception: repeated trials and disconnected designs ----------------------------------------------------

STIMULI = ["standard-0.625", "standard-1.0", "standard-1.625", "flattop-0.1"]


def _stimuli_and_truth(folder: Path) -> tuple[Path, Path]:
    table, truth = folder / "stimuli.csv", folder / "truth.csv"
    table.write_text("stimulus,texture,seed\n" + "".join(f"{s},{s},0\n" for s in STIMULI))
    truth.write_text("stimulus,roughness\n" + "".join(f"{s},{v}\n" for s, v in zip(STIMULI, [0.03, 0.06, 0.11, 0.09])))
    return table, truth


def test_perception_simulate_output_embeds_with_default_options(tmp_path, capsys):
    pytest.importorskip("cvxpy")
    table, truth = _stimuli_and_truth(tmp_path)
    code, err = _cli(["perception", "simulate", "--stimuli", table, "--truth", truth, "--trials", "60",
                      "--sigma", "0.3", "--out", tmp_path / "sim", "--quiet"], capsys)
    assert code == 0, err
    text = (tmp_path / "sim" / "trials.csv").read_text()
    with pytest.raises(InputError, match="contradictory duplicates"):  # a noisy observer answers repeats both ways
        parse_trials(text, repeats="error")
    code, err = _cli(["perception", "embed", tmp_path / "sim" / "trials.csv", "--out", tmp_path / "emb",
                      "--folds", "2", "--resamples", "2", "--workers", "1", "--quiet"], capsys)
    assert code == 0, err
    assert "warning" not in err  # every stimulus compared with every other
    summary = json.loads((tmp_path / "emb" / "embedding.json").read_text())
    assert summary["trials"] == 60 and summary["disconnected_groups"] is None and summary["warnings"] == []
    code, err = _cli(["perception", "embed", tmp_path / "sim" / "trials.csv", "--out", tmp_path / "emb2",
                      "--repeats", "error"], capsys)
    assert code == 2 and "contradictory duplicates" in err and "--repeats error" in err


def _two_groups_text() -> str:
    rows = ["subject,reference,left,right,answer"]
    for group in (("a", "b", "c"), ("d", "e", "f", "g")):
        for i, (r, left, right) in enumerate(itertools.permutations(group, 3)):
            rows.append(f"s1,{r},{left},{right},{('left', 'right')[i % 2]}")
    return "\n".join(rows) + "\n"


def test_groups_of_a_design():
    assert parse_trials(_two_groups_text()).groups() == (("d", "e", "f", "g"), ("a", "b", "c"))
    bridged = _two_groups_text() + "s2,c,d,a,left\n"  # one trial comparing across the groups connects them
    assert parse_trials(bridged).groups() == (("a", "b", "c", "d", "e", "f", "g"),)


def test_a_disconnected_design_is_warned_about(tmp_path, capsys):
    pytest.importorskip("cvxpy")
    (tmp_path / "trials.csv").write_text(_two_groups_text())
    code, err = _cli(["perception", "embed", tmp_path / "trials.csv", "--out", tmp_path / "emb", "--lambda", "0.1",
                      "--resamples", "0", "--workers", "1", "--quiet"], capsys)
    assert code == 0, err
    assert "warning" in err and "2 groups of stimuli never compared with each other (d, e, f, g | a, b, c)" in err
    summary = json.loads((tmp_path / "emb" / "embedding.json").read_text())
    assert summary["disconnected_groups"] == [["d", "e", "f", "g"], ["a", "b", "c"]]
    assert len(summary["warnings"]) == 1 and "never compared" in summary["warnings"][0]


def test_a_stimulus_without_roughness_is_named(tmp_path, capsys):
    table, truth = _stimuli_and_truth(tmp_path)
    truth.write_text(truth.read_text().replace("standard-1.0,0.06", "standard-1.0,0"))  # e.g. a flat texture's V
    code, err = _cli(["perception", "simulate", "--stimuli", table, "--truth", truth, "--trials", "20",
                      "--out", tmp_path / "sim"], capsys)
    assert code == 2 and "not so for: standard-1.0 (V = 0)" in err


# --- a flag parsed into several fields names the flag, never a field ---------------------------------------------

@pytest.mark.parametrize("text", ["cone:0,0,1,1e300", "cone:0,0,1,-1", "cone:0,0,0,10", "cone:nan,0,1,10",
                                  "box:0,0,0,nan,1,1", "box:1,1,1,0,0,0", "colour:300,0,0", "colour:1,2,3,300",
                                  "colour:1,2,3,-1", "cone:1,2", "foo:1"])
def test_region_errors_name_the_region_in_words(text):
    """--region is parsed into Region fields (axis, half_angle_deg, low, high, tolerance): an error in any of them is
    the --region flag's, worded as parts of the region, so the CLI never shows a Python field name."""
    from roughness.objects.regions import parse_region

    with pytest.raises(InputError) as caught:
        parse_region(text)
    assert caught.value.parameter == "region"
    assert not re.search(r"(^|[^' \w])(axis|low|high|tolerance)\b|half_angle_deg", str(caught.value)), str(caught.value)


# --- an optional dependency missing: the extra that installs it, never a traceback --------------------------------

BLOCK_AND_RUN = """
import importlib.abc, sys
class Missing(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.partition(".")[0] == sys.argv[1]:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, Missing())
from roughness.cli import main
sys.exit(main(sys.argv[2:]))
"""


@pytest.mark.parametrize("module, extra, argv", [
    ("trimesh", "objects", ["object", "texture", "mesh.stl", "--texture", "standard-1.0", "--out", "new.stl"]),
    ("trimesh", "objects", ["object", "feel", "mesh.stl", "--texture", "standard-1.0"]),
    ("trimesh", "objects", ["object", "tune", "mesh.stl", "--texture", "standard-1.0", "--target-lambda", "1",
                            "--out", "new.npz"]),
    ("cvxpy", "perception", ["perception", "embed", "trials.csv", "--out", "emb", "--folds", "2", "--resamples", "2",
                             "--workers", "1"]),
])
def test_a_missing_optional_dependency_names_its_extra(module, extra, argv, workdir):
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", BLOCK_AND_RUN, module, *argv], cwd=workdir, capture_output=True,
                         text=True)
    assert out.returncode == 2, out.stderr
    assert module in out.stderr and f"roughness[{extra}]" in out.stderr and "Traceback" not in out.stderr


def test_a_physics_answer_is_never_called_out_of_domain():
    """``in_domain`` is the surrogate's domain: where auto climbed to a physics engine, the line says why the
    surrogate did not answer and which engine did, not that the answer is OUT OF DOMAIN."""
    from roughness.prediction import domain_words

    notes = ["feature size 0.1 mm below the training range"]
    for engine in ("spectral", "fem"):
        words = domain_words(SimpleNamespace(in_domain=False, engine=engine, domain_notes=notes))
        assert words == f"outside the surrogate's domain ({notes[0]}); the {engine} engine answered"
    assert domain_words(SimpleNamespace(in_domain=False, engine="surrogate", domain_notes=notes)) == \
        f"OUT OF DOMAIN: {notes[0]}"
    assert domain_words(SimpleNamespace(in_domain=True, engine="spectral", domain_notes=[])) == "in domain"


def test_auto_and_the_spectral_engine_give_one_answer_one_verdict():
    """Issue 41: auto called a spectral answer outside the surrogate's domain that --engine spectral called "in
    domain" (it never checked: True unchecked). Both now judge the surrogate's domain: a texture just above its
    relief range (1.16 mm, 2 mm period) and one inside it get the same verdict, words and V from either."""
    import numpy as np

    from roughness.prediction import domain_words, predict
    from roughness.surface.heightmap import Heightmap

    y, x = np.mgrid[0:240, 0:240] * 0.05
    tall = Heightmap(0.6 * np.sin(2 * np.pi * x / 2.0) * np.sin(2 * np.pi * y / 2.0), 0.05)
    [auto], [spectral] = predict(tall, engine="auto"), predict(tall, engine="spectral")
    assert auto.engine == spectral.engine == "spectral" and auto.roughness == spectral.roughness
    assert not auto.in_domain and not spectral.in_domain and auto.domain_notes == spectral.domain_notes
    assert domain_words(auto) == domain_words(spectral) and "relief_mm 1.16 outside" in domain_words(spectral)
    [inside] = predict(Heightmap(0.1 * np.sin(2 * np.pi * x / 1.0), 0.05), engine="spectral")
    assert inside.in_domain and domain_words(inside) == "in domain"


def test_the_python_repr_says_whose_domain_too():
    """The repr of a physics answer that auto climbed to names the surrogate's domain, as the command line does."""
    from roughness.prediction import domain_words

    physics = SimpleNamespace(in_domain=False, engine="spectral", domain_notes=["a note"])
    assert domain_words(physics, notes=False) == "outside the surrogate's domain; the spectral engine answered"
    assert domain_words(SimpleNamespace(in_domain=False, engine="surrogate", domain_notes=["a note"]),
                        notes=False) == "out of domain"

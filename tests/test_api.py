"""The public Python API as notebook users meet it: dir(), help(), type checking of the documented examples,
NumPy arrays wherever a heightmap is taken, short reprs, and plots that return Figures and leave the backend."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest
from matplotlib.figure import Figure

import roughness
from conftest import package_view, source_modules
from roughness.core.errors import InputError
from test_packaging import doc_python_blocks

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("torch", "scipy", "matplotlib", "roughness.simulate.model", "roughness.design", "onnxruntime")


def _fresh(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_fresh_interpreter_dir_and_help_show_the_public_api():
    out = _fresh(f"""
import sys, pydoc, json
import roughness
heavy = sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r} or m in {HEAVY!r})
names = dir(roughness)
text = pydoc.render_doc(roughness, renderer=pydoc.plaintext)
print(json.dumps({{"heavy": heavy, "dir": names, "all": roughness.__all__, "help": text}}))
""")
    import json

    got = json.loads(out)
    assert got["heavy"] == [], "import roughness alone must stay light"
    assert set(got["all"]) <= set(got["dir"])
    for name in ("predict", "Heightmap", "load_heightmap", "tune", "homogeneity", "embed_trials", "design",
                 "perception", "simulate"):
        assert name in got["dir"], name
    assert not {"Path", "annotations", "import_module", "TYPE_CHECKING"} & set(got["dir"])
    help_text = got["help"]
    for name in got["all"]:
        if name != "__version__":
            assert re.search(rf"\b{name}\b", help_text), f"help(roughness) does not show {name}"
    assert "predict(inputs" in help_text  # the function's signature, not just its name
    assert "class Heightmap" in help_text


def _doc_examples() -> list[str]:
    """The Python examples of the README and the manual: their ```python blocks that start with ``import roughness``."""
    return [b for b in doc_python_blocks().values() if b.startswith("import roughness")]


def test_mypy_passes_on_the_documented_python_examples_and_sees_real_types(tmp_path):
    examples = _doc_examples()
    assert len(examples) >= 3 and any("pixel_mm=" in e and "roughness.tune(" in e for e in examples)
    # each example in a function of its own, so names do not clash between them
    (tmp_path / "doc_examples.py").write_text("\n".join(
        f"def example_{i}() -> None:\n" + "".join(f"    {line}\n" for line in block.splitlines())
        for i, block in enumerate(examples)))
    # the control: mypy must find these wrong, so the public names are typed, not Any
    (tmp_path / "control.py").write_text("import roughness\n"
                                         "[p] = roughness.predict(roughness.standard_texture(1.0), engine=3)\n"
                                         "p.roughness.upper()\n"
                                         "roughness.homogeneity(roughness.standard_texture(1.0)).verdict + 1\n")
    out = subprocess.run([sys.executable, "-m", "mypy", "--follow-imports=silent", "--ignore-missing-imports",
                          "--cache-dir", str(tmp_path / "cache"), "--no-error-summary", "doc_examples.py",
                          "control.py"], capture_output=True, text=True, cwd=tmp_path,
                         env={"MYPYPATH": str(package_view(tmp_path / "view")), "PATH": "/usr/bin:/bin"})
    assert out.returncode == 1, out.stdout + out.stderr  # mypy is in the test extra: missing, this fails
    errors = out.stdout.splitlines()
    assert [e for e in errors if e.startswith("doc_examples.py")] == []
    control = "\n".join(e for e in errors if e.startswith("control.py"))
    assert 'Argument "engine" to "predict" has incompatible type "int"' in control
    assert '"float" has no attribute "upper"' in control
    assert 'Unsupported operand types for + ("str" and "int")' in control
    assert len(errors) == 3, out.stdout


@pytest.fixture(scope="module")
def texture():
    return roughness.standard_texture(1.25, seed=1)


def test_predict_takes_an_array_with_its_pixel_size(texture):
    [from_array] = roughness.predict(texture.heights, pixel_mm=texture.pixel_mm, engine="surrogate")
    [from_map] = roughness.predict(texture, engine="surrogate")
    assert from_array.roughness == from_map.roughness
    several = roughness.predict([texture.heights, texture], pixel_mm=texture.pixel_mm, engine="surrogate")
    assert [p.roughness for p in several] == [from_map.roughness] * 2
    [spectral] = roughness.predict(texture.heights, pixel_mm=texture.pixel_mm, engine="spectral")
    assert spectral.engine == "spectral"


def test_predict_names_its_answers_after_named_inputs_and_takes_options(texture):
    """A mapping or (name, heightmap) pairs name the answers; PredictOptions carries the footprint's placement."""
    by_mapping = roughness.predict({"left": texture, "right": texture.heights}, pixel_mm=texture.pixel_mm,
                                   engine="surrogate")
    by_pairs = roughness.predict([("left", texture), ("right", texture)], engine="surrogate")
    assert [p.source for p in by_mapping] == [p.source for p in by_pairs] == ["left", "right"]
    assert [p.source for p in roughness.predict([texture, texture], engine="surrogate")] == ["heightmap 0",
                                                                                            "heightmap 1"]
    tiled = roughness.PredictOptions(tile=True, centre_mm=(1.0, 2.0))
    [moved] = roughness.predict(texture, engine="surrogate", options=tiled)
    assert moved.roughness != by_pairs[0].roughness  # another footprint of the texture
    with pytest.raises(InputError) as err:
        roughness.predict(texture, engine="spectral", options=roughness.PredictOptions(fidelity="fine"))
    assert err.value.parameter == "fidelity"


@pytest.mark.parametrize("heights, kwargs, parameter, message", [
    ("array", {}, "pixel_mm", "without a pixel size: pass pixel_mm="),
    ("3d", {"pixel_mm": 0.05}, "inputs", "must be 2-D"),
    ("nan", {"pixel_mm": 0.05}, "inputs", "NaN/Inf pixel(s); first at row 0, column 0: NaN and masked points are "
                                          "missing data"),
    ("inf", {"pixel_mm": 0.05}, "inputs", "infinite height"),
    ("text", {"pixel_mm": 0.05}, "inputs", "must be a Heightmap, a 2-D array"),
    ("number", {"pixel_mm": 0.05}, "inputs", "must be a Heightmap, a 2-D array"),
    ("map", {"pixel_mm": 0.1}, "pixel_mm", "contradicts the heightmap's own pixel"),
    ("array", {"pixel_mm": float("nan")}, "pixel_mm", "pixel_mm"),
])
def test_predict_refuses_bad_arrays_with_input_errors(texture, heights, kwargs, parameter, message):
    a = np.zeros((40, 40))
    value = {"array": a, "3d": np.zeros((3, 40, 40)), "nan": np.where(np.eye(40) > 0, np.nan, 0.0),
             "inf": np.where(np.eye(40) > 0, np.inf, 0.0), "text": "heights.png", "number": 3.0,
             "map": texture}[heights]
    with pytest.raises(InputError, match=re.escape(message)) as err:
        roughness.predict(value, engine="surrogate", **kwargs)
    assert err.value.parameter == parameter


def test_design_tools_take_arrays_and_plain_arguments(texture):
    h = roughness.homogeneity(texture.heights, pixel_mm=texture.pixel_mm, n=8)
    assert h.verdict == "homogeneous" and len(h.roughness) == 8
    tuned = roughness.tune(texture.heights, pixel_mm=texture.pixel_mm, target_lambda_mm=1.0, verify="spectral")
    assert tuned.reached and tuned.factor < 1  # smoother than the 1.25 mm standard: lower bumps
    assert abs(tuned.achieved.equivalent_lambda_mm - 1.0) < 0.1
    smooth, rough = roughness.standard_texture(0.75, seed=1), roughness.standard_texture(1.5, seed=1)
    chosen = roughness.palette(2, candidates={"a": smooth.heights, "b": rough, "c": texture},
                               pixel_mm=0.05, min_jnd=2.0, verify="spectral")
    assert [m.name for m in chosen.members] == ["a", "b"] and chosen.verified
    picture = np.zeros((30, 40, 3), np.uint8)
    picture[:, 20:] = 255
    plate = roughness.tactile_image(picture, [smooth.heights, rough.heights], texture_pixel_mm=0.05, size_mm=30)
    assert len(plate.regions) == 2 and plate.heightmap.size_mm[0] == pytest.approx(30, abs=0.1)
    for call, parameter in ((lambda: roughness.homogeneity(texture.heights), "pixel_mm"),
                            (lambda: roughness.tune(texture.heights, target_v=0.1), "pixel_mm"),
                            (lambda: roughness.tactile_image(np.zeros((5, 5, 4)), []), "picture"),
                            (lambda: roughness.tactile_image(np.full((5, 5), 2.0), []), "picture"),
                            (lambda: roughness.palette(2, candidates=[texture]), "candidates")):
        with pytest.raises(InputError) as err:
            call()
        assert err.value.parameter == parameter


def test_perception_analysis_from_its_files():
    folder = ROOT / "examples" / "perception"
    fit = roughness.fit_embedding(folder / "embedding" / "embedding.csv", folder / "stimuli.csv",
                                  exclude=["standard-1.625"])
    assert len(fit.stimuli) == 26 and fit.included.sum() == 25
    assert fit.correlations()["V"]["all"]["pearson"] > 0.9  # the worked example's surrogate V follows the scale
    with pytest.raises(InputError) as err:
        roughness.fit_embedding(folder / "embedding" / "embedding.csv", folder / "stimuli.csv", exclude=["nope"])
    assert err.value.parameter == "exclude"


def test_reprs_are_a_line_or_two(texture):
    from roughness.engines import SpectralEngine
    from roughness.simulate.footprints import RoughnessMap

    [p] = roughness.predict(texture, engine="surrogate")
    rmap = RoughnessMap(np.arange(50.0), np.arange(40.0), np.full((40, 50), 0.1), np.ones((40, 50), bool))
    spectral = SpectralEngine.of().simulate(texture)
    h = roughness.homogeneity(texture, n=8)
    shown = {"Heightmap": (texture, "240 x 240 px, pixel 0.05 mm"), "Prediction": (p, "V = 0.1"),
             "RoughnessMap": (rmap, "40 x 50 positions, step 1 mm"), "SpectralResult": (spectral, "V = 0.1"),
             "Homogeneity": (h, "homogeneous, 8 windows")}
    for name, (value, part) in shown.items():
        text = repr(value)
        assert text.startswith(name + "(") and part in text, text
        assert len(text) < 300 and "\n" not in text and "array(" not in text, text


def test_fem_result_repr_is_short():
    from roughness.simulate.config import SimConfig
    from roughness.simulate.result import Result

    n = 400
    result = Result(0.05, 0.001, 0.9, 2.5, True, 3, 0, False, 10, 1, 1000, 3000, 1.5, {}, np.zeros((n, n)),
                    np.zeros((n, n)), np.zeros(n), [10], [], SimConfig(fidelity="coarse"))
    text = repr(result)
    assert text.startswith("Result(V = 0.05 ± 0.001, fem (coarse), converged") and len(text) < 200, text


def _plot_inputs():
    """Small synthetic inputs for every library plot function."""
    from roughness.design.evaluation import Verified
    from roughness.design.homogeneity import Homogeneity
    from roughness.design.palette import Member, Palette
    from roughness.design.tactile_image import Region, TactilePlate
    from roughness.perception.analysis import EmbeddingAnalysis
    from roughness.perception.crossval import CrossValidation
    from roughness.perception.embed import EmbedResult
    from roughness.perception.fit import Fit, SamplingFit
    from roughness.perception.values import StimulusValue
    from roughness.report import EngineScore
    from roughness.simulate.footprints import RoughnessMap

    hm = roughness.standard_texture(1.0, seed=0)
    x = np.linspace(0.5, 4.5, 5)
    n = 5
    coordinate = np.linspace(-1, 1, n)
    analysis = EmbeddingAnalysis(tuple(f"s{i}" for i in range(n)), coordinate, coordinate - 0.1, coordinate + 0.1,
                                 EmbedResult(np.outer(coordinate, coordinate), True, "ok", "", 1, 0.1, 0.0, 1.0),
                                 CrossValidation(np.array([0.1, 1.0]), np.full((2, 3), 0.1), np.full((2, 3), 0.2), 0),
                                 None, "", {})
    values = [StimulusValue(f"s{i}", 0.05 + 0.01 * i, 0.001, "fem") for i in range(n)]
    fit = Fit(analysis.stimuli, coordinate, coordinate - 0.1, coordinate + 0.1, values, np.ones(n, bool),
              sampling=SamplingFit(np.array([1.0, 2.0]), np.array([0.5, 1.0]), np.full((2, 2), 0.9),
                                   np.full((2, 2), 0.9)), forces={5.0: np.arange(n) * 0.01, 10.0: np.arange(n) * 0.02})
    verified = Verified(0.1, 0.001, 1.0, True, 1.0)
    palette = Palette((Member("a", hm, verified, 0.1, {}), Member("b", hm, verified, 0.1, {})), 2.0,
                      np.zeros((2, 2)), "test")
    labels = np.zeros(hm.shape, int)
    labels[:, 120:] = 1
    plate = TactilePlate(hm, labels, (Region((0, 0, 0), "a", 100, None, None, 0.1, 1.0, 3),
                                      Region((255, 255, 255), "b", 100, None, None, 0.2, 1.5, 3)),
                         x, x, np.full((5, 5), 0.1), np.zeros((5, 5), int), None, np.zeros((20, 20)), (0, 12, 12, 0))
    homogeneity = Homogeneity(10.0, x, x, np.linspace(0.1, 0.2, 5), np.ones(5), np.ones(5, bool), "surrogate",
                              1e-3, 0.1, 0.2, 0.15)
    score = EngineScore("surrogate", "surrogate", ["t1", "t2", "t3"], np.array([0.1, 0.2, 0.3]),
                        np.array([0.11, 0.19, 0.3]), np.array([0.11, 0.19, 0.3]), np.array([0.01, 0.01, 0.01]), 0,
                        False)
    rows = [{"engine": "surrogate", "kind": "surrogate", "median_s": 0.01, "median_rel_err": 0.05},
            {"engine": "fem:coarse", "kind": "fem", "median_s": 1.0, "median_rel_err": 0.01}]
    strain = SimpleNamespace(grid_axis_mm=np.linspace(-3, 3, 20), lambda3=np.zeros((20, 20)),
                             fluctuation=np.zeros((20, 20)), roughness=0.1, roughness_stderr=0.001,
                             contact_fraction=0.9, config=roughness.SimConfig(fidelity="coarse"))
    card_rows = [{"split": split, "family": "bumps", "V_fem": "0.1", "V_predicted": "0.11"} for split in ("test", "ood")]
    history = [{"epoch": "1", "train_loss": "0.1", "val_loss": "0.2"}, {"epoch": "2", "train_loss": "0.05",
                                                                        "val_loss": "0.1"}]
    rmap = RoughnessMap(x, x, np.full((5, 5), 0.1), np.eye(5) > 0, np.full((5, 5), 0.01))
    return hm, analysis, fit, palette, plate, homogeneity, score, rows, strain, card_rows, history, rmap


def test_plot_functions_return_figures_and_leave_the_backend(tmp_path):
    import matplotlib.pyplot as plt

    from roughness.design.homogeneity import save_map as homogeneity_map
    from roughness.design.palette import save_preview
    from roughness.design.tactile_image import figures, save_figures
    from roughness.perception import plots
    from roughness.report import plot_family_errors, plot_pareto, plot_scatter
    from roughness.simulate.output import save_strain_png
    from roughness.surrogate.card import plot_accuracy, plot_history
    from roughness.surrogate.roughness_map import map_figure, save_map

    hm, analysis, fit, palette, plate, homogeneity, score, rows, strain, card_rows, history, rmap = _plot_inputs()
    calls = {
        "plot_pareto": lambda: plot_pareto(rows, "fem:fine"),
        "plot_scatter": lambda: plot_scatter([score], "fem:fine"),
        "plot_family_errors": lambda: plot_family_errors({"surrogate": {"bumps": 0.05, "grating": 0.1}}),
        "homogeneity save_map": lambda: homogeneity_map(homogeneity, hm),
        "save_preview": lambda: save_preview(palette),
        "plot_embedding": lambda: plots.plot_embedding(analysis),
        "plot_cross_validation": lambda: plots.plot_cross_validation(analysis),
        "plot_fit": lambda: plots.plot_fit(fit),
        "plot_sampling": lambda: plots.plot_sampling(fit),
        "save_strain_png": lambda: save_strain_png(strain),
        "plot_accuracy": lambda: plot_accuracy(card_rows, "bumps", "default"),
        "plot_history": lambda: plot_history(history),
        "map_figure": lambda: map_figure(rmap),
        "roughness map save_map": lambda: save_map(rmap, tmp_path / "map.png"),
        **{f"tactile {name}": (lambda name=name: figures(plate)[name]) for name in ("relief.png", "roughness_map.png",
                                                                                    "strain.png")},
    }
    before = matplotlib.get_backend()
    try:
        matplotlib.use("svg")  # a backend no library code would pick: any change shows
        for name, call in calls.items():
            fig = call()
            assert isinstance(fig, Figure), name
            assert matplotlib.get_backend() == "svg", f"{name} changed the backend"
            assert plt.get_fignums() == [], f"{name} left a pyplot figure open"
    finally:
        matplotlib.use(before)
    written = save_figures(plate, tmp_path)
    assert sorted(written) == ["relief.png", "roughness_map.png", "strain.png"]
    assert all((tmp_path / name).stat().st_size > 1000 for name in written)
    assert (tmp_path / "map.png").stat().st_size > 1000


def test_library_code_never_selects_a_backend_or_uses_pyplot():
    offenders = [f"{path.relative_to(ROOT)}:{i}" for path in source_modules().values()
                 for i, line in enumerate(path.read_text().splitlines(), 1)
                 if re.search(r"matplotlib\.use\(|import matplotlib\.pyplot|from matplotlib import pyplot", line)]
    assert offenders == []


def test_wheel_ships_the_py_typed_marker(installed):  # noqa: F811 (the fixture imported above)
    from test_packaging import _purelib

    assert (_purelib(installed) / "roughness" / "py.typed").is_file()


def test_fem_takes_an_array_with_its_pixel_size(texture, monkeypatch):
    from roughness.simulate.model import Simulator

    seen = []
    monkeypatch.setattr(Simulator, "solve", lambda self, hm, *args, **kwargs: seen.append(hm) or "solved")
    simulator = Simulator(roughness.SimConfig(fidelity="coarse"))
    assert roughness.fem_roughness(texture.heights, pixel_mm=0.05, simulator=simulator, estimate_error=False) == "solved"
    [hm] = seen  # the array became the same Heightmap
    assert np.array_equal(hm.heights, texture.heights) and hm.pixel_mm == texture.pixel_mm
    for heights, kwargs, parameter in ((texture.heights, {}, "pixel_mm"), (np.zeros((2, 40, 40)), {"pixel_mm": 0.05},
                                                                          "heightmap")):
        with pytest.raises(InputError) as err:
            roughness.fem_roughness(heights, simulator=simulator, **kwargs)
        assert err.value.parameter == parameter


def test_the_package_docstring_example_runs():
    """The example at the top of ``help(roughness)`` uses what exists and runs as written."""
    doc = roughness.__doc__
    block = doc[doc.index("::\n") + 3:].split("\n\n", 2)
    code = "\n".join(line[4:] for line in "\n\n".join(block[:2]).splitlines())
    namespace: dict = {}
    exec(compile(code, "roughness.__doc__", "exec"), namespace)  # noqa: S102 (our own docstring)
    assert namespace["p"].roughness > 0 and [n.source for n in namespace["named"]] == ["fine", "coarse"]
    assert namespace["q"].roughness == namespace["p"].roughness or namespace["p"].engine != "surrogate"
    assert namespace["r"].roughness > 0 and np.isfinite(namespace["m"].map.roughness).all()

"""`roughness compare` and its report on a tiny set: tables, numbers consistent with the cached
results, plots, resuming, failures; the classical measures and the Pareto / break-even arithmetic."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from roughness import classical
from roughness.cli import main
from roughness.compare import SETUP_KEY
from roughness.core.errors import InputError
from roughness.dataset.recipe import Recipe, realise, sample_record
from roughness.dataset.writer import DatasetWriter
from roughness.engines import make_engine
from roughness.report import break_even, pareto_front
from roughness.simulate.config import SimConfig
from roughness.surface.heightmap import Heightmap

PNG = b"\x89PNG\r\n\x1a\n"
ENGINES = ["surrogate", "ra", "p90", "glcm_sum_of_squares", "glcm_sum_variance"]


def fields(v: float) -> dict:
    return {"roughness": v, "roughness_stderr": 1e-4, "contact_fraction": 0.9, "indentation_mm": 3.4,
            "converged": True, "iterations": 3, "unresolved_nodes": 0, "cycled": False, "seconds": 1.0 + v,
            "contact_history": [10, 12], "grid_axis_mm": np.linspace(-4, 4, 5),
            "discretization_error": None, "ladder": []}


@pytest.fixture(scope="module")
def tiny_set(tmp_path_factory):
    """Twelve textures of four families with stored `coarse` labels (V = 0.4 Ra, synthetic)."""
    path = tmp_path_factory.mktemp("compare") / "tiny.h5"
    recipe = Recipe(name="tiny", seed=8, families={"bumps": 1, "fbm": 1, "woven": 1, "grating": 1})
    config = {"recipe": {"name": "tiny"}, "simulation": SimConfig(fidelity="coarse").as_dict()}
    with DatasetWriter(path, config, "test") as writer:
        for i in range(12):
            record = sample_record(recipe, i)
            hm = realise(record)
            v = 0.4 * classical.ra(classical.footprint(hm))
            writer.write_result(record, hm.heights, hm.pixel_mm, fields(v), np.zeros((5, 5)))
    return path


def read_table(folder: Path) -> dict[str, dict]:
    with open(folder / "table.csv", newline="") as f:
        return {row["engine"]: row for row in csv.DictReader(f)}


def test_report_tables_plots_and_numbers(tiny_set, tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["compare", str(tiny_set), "--out", str(out), "--reference", "fem:coarse", "--engines", *ENGINES,
                 "--quiet"]) == 0
    table = read_table(out)
    assert list(table) == ["fem:coarse", *ENGINES]
    ref = table["fem:coarse"]
    assert int(ref["n"]) == 12 and float(ref["median_rel_err"]) == 0 and float(ref["spearman"]) == 1
    # stored labels come with their stored times (1 + V s): the reference's median time is theirs
    results = [r for r in map(json.loads, (out / "results.jsonl").read_text().splitlines()) if r["key"] != SETUP_KEY]
    stored = {r["key"]: r for r in results if r["engine"] == "fem:coarse"}
    assert float(ref["median_s"]) == pytest.approx(np.median([r["seconds"] for r in stored.values()]))
    assert "| fem:coarse | fem | 12 | 0 |" in (out / "table.md").read_text().replace("†", "")
    assert [line for line in (out / "table.md").read_text().splitlines() if "†" in line] == [
        line for line in (out / "table.md").read_text().splitlines() if line.startswith("| fem:coarse")]
    # each result keeps its error bars, absolute (V units) and relative named apart; none for classical measures
    assert {r["stderr_abs"] for r in stored.values()} == {1e-4}
    assert {r["discretization_rel"] for r in stored.values()} == {None}
    from roughness.dataset.reader import open_dataset
    from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel

    model = SurrogateModel(DEFAULT_MODEL)
    with open_dataset(tiny_set) as data:
        for r in (r for r in results if r["engine"] == "surrogate"):
            spread = model.evaluate(model.patch(data.heightmap(r["texture"]), None, False)[None]).roughness_std[0]
            assert r["ensemble_std_abs"] == pytest.approx(float(spread), rel=1e-6) and r["ensemble_std_abs"] > 0
            assert r["stderr_abs"] is None and r["discretization_rel"] is None
    assert all(r["stderr_abs"] is r["ensemble_std_abs"] is r["discretization_rel"] is None
               for r in results if r["engine"] == "ra")
    # the surrogate's numbers follow from the cached results
    mine = {r["key"]: r["value"] for r in results if r["engine"] == "surrogate"}
    rel = [abs(mine[k] - stored[k]["value"]) / stored[k]["value"] for k in mine]
    assert float(table["surrogate"]["median_rel_err"]) == pytest.approx(np.median(rel))
    # the labels are 0.4 Ra exactly: a power law fits Ra perfectly
    assert float(table["ra"]["median_rel_err"]) < 1e-6 and float(table["ra"]["spearman"]) == pytest.approx(1)
    for name in ("pareto.png", "predicted_vs_reference.png", "error_by_family.png"):
        assert (out / name).read_bytes()[:8] == PNG
    report = (out / "report.md").read_text()
    assert "Textures that disagree most" in report and "| engine |" in report
    assert "fem:coarse" in capsys.readouterr().out


def test_compare_resumes_from_its_cache(tiny_set, tmp_path, capsys):
    out = tmp_path / "report"
    args = ["compare", str(tiny_set), "--out", str(out), "--reference", "fem:coarse", "--engines", "ra", "p90"]
    assert main(args) == 0
    first = (out / "table.csv").read_text()
    lines = (out / "results.jsonl").read_text().splitlines()
    (out / "results.jsonl").write_text("\n".join(lines[:-1]) + "\n" + lines[-1][:10])  # torn last line
    capsys.readouterr()
    assert main(args) == 0
    assert "1 results to compute" in capsys.readouterr().err
    assert main(args) == 0
    assert "0 results to compute" in capsys.readouterr().err
    rows = lambda text: [r.split(",")[:4] for r in text.splitlines()]  # noqa: E731 (times differ per run)
    assert rows((out / "table.csv").read_text()) == rows(first)


def test_fem_results_are_computed_once(tmp_path, capsys, monkeypatch):
    recipe = tmp_path / "r.json"
    recipe.write_text(json.dumps({"name": "r", "seed": 3, "families": {"bumps": 1}}))
    args = ["compare", str(recipe), "--n", "2", "--out", str(tmp_path / "o"), "--reference", "fem:coarse",
            "--engines", "ra", "--quiet"]
    assert main(args) == 0
    from roughness import engines

    monkeypatch.setattr(engines.FemEngine, "measure", lambda *a: pytest.fail("FEM ran again"))
    assert main(args) == 0
    table = read_table(tmp_path / "o")
    assert int(table["fem:coarse"]["n"]) == 2 and float(table["fem:coarse"]["median_s"]) > 0


def maps_folder(tmp_path: Path, n: int = 4) -> Path:
    folder = tmp_path / "maps"
    folder.mkdir()
    rng = np.random.default_rng(0)
    for i in range(n):
        np.save(folder / f"ok{i}.npy", 0.3 * rng.random((240, 240)))
    return folder


def test_input_errors_are_reported_never_cached(tmp_path, capsys):
    folder = maps_folder(tmp_path)
    np.save(folder / "small.npy", np.zeros((20, 20)))
    (folder / "broken.npy").write_bytes(b"not numpy")
    out = tmp_path / "o"
    args = ["compare", str(folder), "--pixel-mm", "0.05", "--out", str(out), "--reference", "ra", "--engines", "p90"]
    assert main(args) == 2  # the report of the readable ones is written, the others are listed
    err = capsys.readouterr().err
    assert "small.npy" in err and "broken.npy" in err and "Traceback" not in err
    table = read_table(out)
    assert table["p90"]["failures"] == "0" and table["p90"]["n"] == "4"
    entries = [json.loads(x) for x in (out / "results.jsonl").read_text().splitlines()]
    assert {e.get("texture") for e in entries} == {f"ok{i}.npy" for i in range(4)}
    report = (out / "report.md").read_text()
    assert "Inputs not compared (2)" in report and "`small.npy`" in report and "`broken.npy`" in report


def test_folder_without_pixel_size_is_an_input_error(tmp_path, capsys):
    folder = maps_folder(tmp_path)
    out = tmp_path / "o"
    assert main(["compare", str(folder), "--out", str(out), "--reference", "ra", "--engines", "p90"]) == 2
    err = capsys.readouterr().err
    assert "pixel" in err and "none of the 4 textures" in err and "Traceback" not in err
    assert not out.exists()


def test_results_follow_the_content_not_the_file_name(tmp_path, capsys):
    folder = maps_folder(tmp_path, 3)
    out = tmp_path / "o"
    args = ["compare", str(folder), "--pixel-mm", "0.05", "--out", str(out), "--reference", "ra", "--engines", "p90"]
    assert main(args) == 0
    np.save(folder / "ok1.npy", 0.6 * np.random.default_rng(5).random((240, 240)))  # same name, new heights
    capsys.readouterr()
    assert main(args) == 0
    assert "2 results to compute, 4 cached" in capsys.readouterr().err
    values = {(e["engine"], e["texture"]): e["value"] for e in map(json.loads, (out / "results.jsonl").open())
              if e["key"] != SETUP_KEY}
    assert values[("ra", "ok1.npy")] == pytest.approx(classical.ra(classical.footprint(
        Heightmap(np.load(folder / "ok1.npy"), 0.05))))
    assert main([*args[:2], "--pixel-mm", "0.06", *args[4:]]) == 0  # another pixel size: other textures
    assert "6 results to compute, 0 cached" in capsys.readouterr().err


def test_another_comparison_in_the_same_folder_is_refused(tmp_path, capsys):
    folder = maps_folder(tmp_path, 3)
    out = tmp_path / "o"
    args = ["compare", str(folder), "--pixel-mm", "0.05", "--out", str(out), "--reference", "ra", "--engines"]
    assert main([*args, "p90", "--quiet"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main([*args, "glcm_sum_variance", "--quiet"]) == 2
    assert "already exists; pass --overwrite" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    assert main([*args[:5], str(tmp_path / "other"), *args[6:], "p90", "--quiet"]) == 2
    assert main([*args, "glcm_sum_variance", "--quiet", "--overwrite"]) == 0
    assert "glcm_sum_variance" in read_table(out)


def test_progress_is_plain_lines_without_a_terminal(tmp_path, capsys):
    folder = maps_folder(tmp_path, 3)
    assert main(["compare", str(folder), "--pixel-mm", "0.05", "--out", str(tmp_path / "o"), "--reference", "ra",
                 "--engines", "p90"]) == 0
    err = capsys.readouterr().err
    assert "\r" not in err and "6/6 results" in err


def test_eta_comes_from_each_engines_time_per_texture():
    from roughness.compare import Progress

    progress = Progress({"fem:coarse": 3, "ra": 3}, quiet=True)
    assert progress.eta_minutes() is None  # nothing timed yet
    progress.step("fem:coarse", 60.0, "a")
    assert progress.eta_minutes() is None  # ra untimed
    progress.step("ra", 0.5, "a")
    assert progress.eta_minutes() == pytest.approx((2 * 60.0 + 2 * 0.5) / 60)


def test_bad_compare_arguments_exit_2(tmp_path, capsys):
    assert main(["compare", str(tmp_path / "nothing.h5"), "--out", str(tmp_path / "o")]) == 2
    assert main(["compare", "recipes/validation.json", "--out", str(tmp_path / "o")]) == 2
    assert main(["compare", "recipes/validation.json", "--n", "2", "--engines", "fem:huge",
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "not found" in err and "needs --n" in err and "unknown engine 'fem:huge'" in err
    assert "Traceback" not in err


def test_classical_measures():
    x = (np.arange(200) + 0.5) * 0.05
    sine = np.tile(0.1 * np.sin(2 * np.pi * x / 1.0), (200, 1))
    assert classical.ra(sine) == pytest.approx(0.1 * 2 / np.pi, rel=0.01)  # 20 samples per period
    assert classical.p90(sine) == pytest.approx(0.1 + 0.1 * np.sin(0.4 * np.pi), rel=0.05)  # P(sin <= s) = 0.9
    flat = np.zeros((200, 200))
    assert classical.glcm_sum_of_squares(flat) == 0 and classical.glcm_sum_variance(flat) == 0
    noise = np.random.default_rng(0).random((200, 200))
    # independent uniform levels: variance of one level (32^2 - 1) / 12, of a sum of two twice that
    assert classical.glcm_sum_of_squares(noise) == pytest.approx((32**2 - 1) / 12, rel=0.03)
    assert classical.glcm_sum_variance(noise) == pytest.approx(2 * (32**2 - 1) / 12, rel=0.03)
    hm = Heightmap(np.zeros((240, 240)), 0.05)
    assert make_engine("ra").measure(hm).value == 0
    with pytest.raises(InputError, match="valid"):
        make_engine("glcm")


def test_pareto_front_and_break_even():
    points = [(10.0, 0.0), (1.0, 0.05), (3.0, 0.02), (2.0, 0.1), (0.001, 0.04), (0.01, 0.5)]
    assert pareto_front(points) == [4, 2, 0]
    rows = [{"engine": "fem:default", "kind": "fem", "median_s": 3.0}, {"engine": "surrogate", "kind": "surrogate",
                                                                       "median_s": 0.002}]
    [even] = break_even(rows, {"data_fem": 3600.0, "training": 1800.0})
    assert even["predictions"] == int(np.ceil(5400 / 2.998)) and even["fixed_core_hours"] == 1.5
    assert break_even(rows, None) == []


def test_cached_results_follow_the_engine_identity(tiny_set, tmp_path, capsys):
    import shutil

    import onnx

    from roughness.surrogate.predictor import DEFAULT_MODEL

    model = tmp_path / "m.onnx"
    shutil.copy(DEFAULT_MODEL, model)
    args = ["compare", str(tiny_set), "--out", str(tmp_path / "o"), "--reference", "fem:coarse",
            "--engines", f"surrogate:{model}", "ra"]
    assert main(args) == 0
    capsys.readouterr()
    assert main(args) == 0
    assert "0 results to compute" in capsys.readouterr().err
    graph = onnx.load(model)
    graph.doc_string = "retrained"  # another model file: its results are not the old model's
    onnx.save(graph, model)
    assert main(args) == 0
    assert "12 results to compute" in capsys.readouterr().err


def test_a_dataset_sample_has_the_content_key_of_its_texture(tiny_set):
    from roughness.dataset.reader import open_dataset
    from roughness.dataset.schema import sample_id
    from roughness.result_cache import content_key

    recipe = Recipe(name="tiny", seed=8, families={"bumps": 1, "fbm": 1, "woven": 1, "grating": 1})
    with open_dataset(tiny_set) as data:
        for i in range(3):
            record = sample_record(recipe, i)
            hm = realise(record)
            assert content_key(data.heightmap(sample_id(record))) == content_key(hm)
            assert content_key(Heightmap(hm.heights, hm.pixel_mm * 1.01)) != content_key(hm)
            assert content_key(Heightmap(hm.heights * 1.001, hm.pixel_mm)) != content_key(hm)


@pytest.mark.parametrize("tolerance, spec", [(0.01, "fem:converged@0.01"), (0.03, "fem:converged")])
def test_stored_converged_labels_serve_the_engine_of_their_tolerance(tolerance, spec, tmp_path):
    """A build converged to 1% is the reference ``fem:converged@0.01``, never the default-tolerance engine."""
    from roughness.compare import dataset_textures

    path = tmp_path / "converged.h5"
    recipe = Recipe(name="tiny", seed=8, families={"bumps": 1})
    config = {"recipe": {"name": "tiny"}, "simulation": SimConfig(fidelity="converged", tolerance=tolerance).as_dict()}
    with DatasetWriter(path, config, "test") as writer:
        record = sample_record(recipe, 0)
        hm = realise(record)
        writer.write_result(record, hm.heights, hm.pixel_mm, fields(0.05), np.zeros((5, 5)))
    _, stored = dataset_textures(path)
    assert list(stored) == [spec]
    engine = make_engine(spec)
    assert engine.spec == spec and engine.config.tolerance == tolerance
    assert engine.identity == make_engine("fem:converged").identity if tolerance == 0.03 else \
        engine.identity != make_engine("fem:converged").identity


@pytest.mark.parametrize("spec, message", [("fem:converged@x", "must be a number"),
                                           ("fem:converged@0", "positive"), ("fem:converged@1.5", "between 0 and 1")])
def test_bad_converged_tolerance_specs_are_refused(spec, message):
    with pytest.raises(InputError, match=message):
        make_engine(spec)

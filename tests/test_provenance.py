"""Provenance on every result (issue 31): one record under the JSON key ``provenance`` in every command's
JSON, on ``Prediction`` and in dataset files; model versions in the ONNX metadata; LICENSE and CITATION.cff."""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import h5py
import numpy as np
import onnx
import pytest
import tomllib
import yaml

import roughness
from roughness.cli import main
from roughness.core.provenance import Provenance, combined, model_id
from roughness.core.version import RELEASE
from roughness.engines import FemEngine, SpectralEngine
from roughness.models import MODELS_DIR
from roughness.prediction import predict
from roughness.surface.heightmap import Heightmap
from roughness.surface.io import save_heightmap
from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel
from roughness.surrogate.versioning import SHIPPED_MODEL_VERSION, stamp

ROOT = Path(__file__).resolve().parents[1]
FIELDS = {"tool_version", "engine", "fidelity", "config_digest", "model_id", "model_version"}
SHIPPED = SurrogateModel()


def _standard(tmp_path: Path, name: str = "standard.npz") -> Path:
    from roughness.dataset.catalogue import make_texture

    path = tmp_path / name
    save_heightmap(make_texture("standard-1.0", seed=0)[0], path)
    return path


def _json(argv: list[str], capsys) -> dict:
    code = main(argv)
    out = capsys.readouterr().out
    assert code == 0, out
    return json.loads(out.strip().splitlines()[-1])


def _surrogate_record(record: dict) -> None:
    assert set(record) == FIELDS
    assert record["tool_version"] == RELEASE
    assert record["model_id"] == SHIPPED.model_id and record["model_version"] == SHIPPED_MODEL_VERSION


def test_the_shipped_models_are_versioned_and_their_id_is_their_content_hash():
    for name in ("roughness-cnn.onnx", "roughness-cnn-int8.onnx"):
        assert onnx.load(str(MODELS_DIR / name), load_external_data=False).model_version == SHIPPED_MODEL_VERSION
        model = SurrogateModel(MODELS_DIR / name)
        assert model.model_version == SHIPPED_MODEL_VERSION
        assert model.model_id == model_id((MODELS_DIR / name).read_bytes()) and model.model_id.startswith("sha256:")
    card = (MODELS_DIR / "MODEL_CARD.md").read_text()
    assert f"model version {SHIPPED_MODEL_VERSION}" in card and SHIPPED.model_id in card


def test_stamping_the_version_keeps_the_readme_answer_bit_for_bit(tmp_path, capsys):
    """The README's main job (its committed output, read from the README) through a copy restamped with another
    version: the same V to the last bit, another model id and version in the provenance."""
    argv = ["predict", str(ROOT / "examples" / "standard-1.0mm.png"), "--pixel-mm", "0.05", "--height-mm", "1"]
    main(argv)
    committed = re.search(r"V = \S+ ± \S+ \(ensemble spread\)", (ROOT / "README.md").read_text())
    assert committed and committed.group(0) in capsys.readouterr().out
    before = _json([*argv, "--json"], capsys)
    copy = tmp_path / "model.onnx"
    shutil.copyfile(DEFAULT_MODEL, copy)
    assert main(["model-version", str(copy), "--version", "7"]) == 0
    after = _json([*argv, "--json", "--model", str(copy)], capsys)
    assert after["roughness"] == before["roughness"] and after["roughness_std"] == before["roughness_std"]
    assert after["provenance"]["model_version"] == 7 and before["provenance"]["model_version"] == SHIPPED_MODEL_VERSION
    assert after["provenance"]["model_id"] != before["provenance"]["model_id"]
    assert after["provenance"]["model_id"] == model_id(copy.read_bytes())
    empty = tmp_path / "empty.onnx"  # an empty file parses as an empty ONNX model: not stamped
    empty.write_bytes(b"")
    with pytest.raises(roughness.InputError, match="without roughness metadata"):
        stamp(empty, 2)
    assert empty.read_bytes() == b""


def test_an_unversioned_model_reads_as_version_0(tmp_path):
    graph = onnx.load(str(DEFAULT_MODEL))
    graph.ClearField("model_version")
    onnx.save(graph, tmp_path / "old.onnx")
    assert SurrogateModel(tmp_path / "old.onnx").model_version == 0


def test_predictions_carry_provenance_with_the_cache_digest():
    hm = Heightmap(np.random.default_rng(0).random((240, 240)) * 0.3, 0.05)
    [p] = predict(hm, engine="surrogate")
    assert isinstance(p.provenance, Provenance)
    _surrogate_record(p.as_dict()["provenance"])
    assert p.provenance.engine == "surrogate" and p.provenance.fidelity == SHIPPED.fidelity
    assert p.provenance.config_digest == FemEngine.of(SHIPPED.fidelity, SHIPPED.meta.simulation).identity
    [s] = predict(hm, engine="spectral")
    assert s.provenance.engine == "spectral" and s.provenance.model_id is None
    assert s.provenance.config_digest == SpectralEngine.of().identity


def test_combined_records_say_where_results_differ():
    a = Provenance("1", "surrogate", "fine", "fem-1", "sha256:a", 2)
    b = Provenance("1", "spectral", "spectral", "spectral-2", None, None)
    assert combined([a, a]) == a
    both = combined([a, b])
    assert both.engine == "surrogate+spectral" and both.model_id == "sha256:a" and both.model_version is None


def test_every_command_json_has_provenance(tmp_path, capsys):
    path = _standard(tmp_path)
    base = [str(path), "--quiet"]
    _surrogate_record(_json(["predict", *base, "--engine", "surrogate", "--json"], capsys)["provenance"])
    assert _json(["predict", *base, "--engine", "spectral", "--json"], capsys)["provenance"]["engine"] == "spectral"
    mapped = _json(["predict", *base, "--engine", "surrogate", "--json", "--map", str(tmp_path / "m.npy"),
                    "--step-mm", "4"], capsys)
    _surrogate_record(mapped["provenance"])
    _surrogate_record(_json(["jnd", str(path), str(path), "--engine", "surrogate", "--json"], capsys)["provenance"])
    homogeneity = _json(["homogeneity", *base, "--tile", "--n", "5", "--json"], capsys)
    _surrogate_record(homogeneity["provenance"])
    tune = _json(["tune", *base, "--jnd", "+1", "--out", str(tmp_path / "t.npz"), "--verify", "spectral", "--json"],
                 capsys)
    assert tune["provenance"]["engine"] == "spectral" and tune["provenance"]["model_id"] == SHIPPED.model_id
    assert tune["provenance"]["config_digest"] == SpectralEngine.of(SHIPPED.meta.simulation).identity


def test_design_files_record_their_verifier_and_searching_model(tmp_path, capsys):
    """palette.json and plate.json (and their --json) name the spectral verifier and the shipped surrogate."""
    from PIL import Image

    spectral = SpectralEngine.of(SHIPPED.meta.simulation).identity
    pal = tmp_path / "pal"
    printed = _json(["palette", "--k", "2", "--min-jnd", "1", "--verify", "spectral", "--out", str(pal), "--quiet",
                     "--json"], capsys)
    written = json.loads((pal / "palette.json").read_text())
    assert printed["provenance"] == written["provenance"]
    _surrogate_record(written["provenance"])
    assert written["provenance"]["engine"] == "spectral" and written["provenance"]["config_digest"] == spectral
    rgb = np.zeros((24, 40, 3), dtype=np.uint8)
    rgb[:, :20], rgb[:, 20:] = (250, 240, 200), (20, 20, 90)
    Image.fromarray(rgb).save(tmp_path / "picture.png")
    plate = tmp_path / "plate"
    _json(["tactile-image", str(tmp_path / "picture.png"), "--palette", str(pal), "--out", str(plate), "--size-mm",
           "40", "--step-mm", "4", "--verify", "spectral", "--json", "--quiet"], capsys)
    record = json.loads((plate / "plate.json").read_text())["provenance"]
    _surrogate_record(record)
    assert record["engine"] == "spectral" and record["config_digest"] == spectral


def test_compare_files_record_each_engines_provenance(tmp_path, capsys):
    folder = tmp_path / "maps"
    folder.mkdir()
    _standard(folder, "a.npz")
    out = tmp_path / "report"
    assert main(["compare", str(folder), "--out", str(out), "--engines", "ra", "surrogate", "--reference", "p90",
                 "--quiet"]) == 0
    capsys.readouterr()
    manifest = json.loads((out / "compare.json").read_text())
    _surrogate_record(manifest["provenance"]["surrogate"])
    assert manifest["provenance"]["ra"]["engine"] == "ra"
    lines = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert lines and all(set(line["provenance"]) == FIELDS for line in lines)
    # the provenance in the manifest does not make a rerun of the same comparison a different one
    assert main(["compare", str(folder), "--out", str(out), "--engines", "ra", "surrogate", "--reference", "p90",
                 "--quiet"]) == 0


def test_simulate_json_names_the_fem_configuration(tmp_path, capsys, monkeypatch):
    """The FEM itself is stubbed (seconds); the record is what the command builds from its configuration."""
    from roughness.simulate import prepared

    class Result:
        converged, unusual_notes = True, []

        def summary(self) -> dict:
            return {"roughness": 0.1}

    monkeypatch.setattr(prepared, "simulate", lambda config, hm, centre_mm=None, tile=False: Result())
    record = _json(["simulate", str(_standard(tmp_path)), "--fidelity", "coarse", "--json", "--quiet"],
                   capsys)["provenance"]
    assert record["engine"] == "fem" and record["fidelity"] == "coarse" and record["model_id"] is None
    assert record["config_digest"] == FemEngine.of("coarse").identity


def test_dataset_files_store_the_builds_provenance(tmp_path, capsys):
    from roughness.dataset.build import BUILD_CONFIG

    out = tmp_path / "d.h5"
    printed = _json(["dataset", "build", "--out", str(out), "--n", "1", "--engine", "spectral", "--workers", "1",
                     "--quiet"], capsys)
    with h5py.File(out) as h5:
        record = json.loads(h5.attrs["provenance"])
    assert record == printed["provenance"] and set(record) == FIELDS and record["engine"] == "spectral"
    assert record["config_digest"] == SpectralEngine("spectral", BUILD_CONFIG).identity


def test_citation_and_licence():
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert {"cff-version", "title", "authors", "message", "preferred-citation"} <= set(citation)
    paper = citation["preferred-citation"]
    assert paper["journal"] == "ACM Transactions on Graphics" and paper["volume"] == 37 and paper["issue"] == 5
    assert [a["family-names"] for a in paper["authors"]] == ["Tymms", "Gardner", "Zorin"]
    assert citation["version"] == RELEASE == roughness.__version__
    assert RELEASE == tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    licence = (ROOT / "LICENSE").read_text()
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["project"]["license"]["text"] in licence.splitlines()[0] == "BSD-3-Clause License"
    assert "LICENSE" in pyproject["tool"]["setuptools"]["license-files"]
    assert "include LICENSE CITATION.cff CHANGELOG.md" in (ROOT / "MANIFEST.in").read_text()
    assert (ROOT / "CHANGELOG.md").read_text().startswith("# Changelog")


def test_training_records_provenance_and_export_writes_the_model_version(tmp_path):
    """A 1-epoch run on synthetic labels (test_surrogate's tiny set): metrics.json names the labels'
    configuration; the export carries the version asked for, which the loaded model reports."""
    import torch

    from roughness.core.hashing import digest
    from roughness.surrogate.export import check_patches, export
    from roughness.surrogate.train import TrainConfig, train
    from test_surrogate import write_tiny_dataset

    data = tmp_path / "tiny.h5"
    write_tiny_dataset(data)
    torch.manual_seed(0)
    checkpoint = train(TrainConfig(data=str(data), out=str(tmp_path / "run"), max_epochs=1, batch_size=8,
                                   val_fraction=0.2))
    record = json.loads((tmp_path / "run" / "metrics.json").read_text())["provenance"]
    assert set(record) == FIELDS and record["engine"] == "surrogate" and record["fidelity"] == "coarse"
    with h5py.File(data) as h5:
        simulation = json.loads(h5.attrs["config"])["simulation"]
    assert record["config_digest"] == "fem-" + digest(simulation) and record["model_id"] is None
    report = export(checkpoint, tmp_path / "model.onnx", patches=check_patches(2), model_version=3)
    model = SurrogateModel(tmp_path / "model.onnx")
    assert report["model_version"] == 3 == model.model_version
    with pytest.raises(roughness.InputError, match="model_version"):
        export(checkpoint, tmp_path / "zero.onnx", patches=check_patches(2), model_version=0)
    assert not (tmp_path / "zero.onnx").exists()

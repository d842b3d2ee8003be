"""Files are checked for what they claim (issue 46): a model card only from the model's own run, a mesh's size as a
touchable object, an .x3p's checksum, a scheduler file's address, a model version ONNX can hold, one value per unit
key; damage is reported as damage, naming the file (meshes, scans, datasets, the result cache, FIFOs), never as a
traceback or as another defect. (A resume file's fields: tests/test_train_resume.py.)"""
from __future__ import annotations

import hashlib
import os
import struct
import zipfile
from pathlib import Path

import numpy as np
import onnx
import pytest
import trimesh

from roughness.cli import main
from roughness.cluster import ClusterChoice
from roughness.core.errors import InputError
from roughness.dataset.inspection import verify
from roughness.dataset.reader import open_dataset
from roughness.dataset.writer import DatasetWriter
from roughness.objects.meshes import MAX_OBJECT_MM, MIN_OBJECT_MM, read_mesh
from roughness.surface.heightmap import Heightmap
from roughness.surface.io import read_heightmap
from roughness.surface.units import split_input
from roughness.surrogate.card import write_card
from roughness.surrogate.train import TrainConfig, train
from roughness.surrogate.versioning import MAX_MODEL_VERSION, set_version
from test_surrogate import CONFIG, fake_fields, tiny  # noqa: F401 (a fixture: a short real training and its export)

# --- A: a card only from the model's own run ---------------------------------------------------------------------

def test_a_card_refuses_a_run_that_did_not_make_the_model(tiny, tmp_path):  # noqa: F811
    other = train(TrainConfig(data=str(tiny.data), out=str(tmp_path / "other"), max_epochs=2, batch_size=8,
                              val_fraction=0.2, seed=4, threads=1)).parent
    card = tmp_path / "CARD.md"
    with pytest.raises(InputError) as refused:
        write_card(other, tiny.model, card, tmp_path)
    message = str(refused.value)
    assert refused.value.parameter == "run_dir"
    assert f"{tiny.model} was not made by the training run {other}" in message
    assert "epochs 3 vs 2" in message and "seed 0 vs 4" in message
    assert not card.exists() and not (tmp_path / "surrogate_accuracy.png").exists()
    (other / "metrics.json").unlink()
    with pytest.raises(InputError, match="metrics.json not found: not the folder of a training run"):
        write_card(other, tiny.model, card, tmp_path)
    write_card(tiny.root / "run", tiny.model, card, tmp_path)  # its own run: written
    assert "best validation epoch" in card.read_text()


# --- B: a mesh's size and its defects ----------------------------------------------------------------------------

@pytest.mark.parametrize("side, likely", [(0.03, "metres or inches"), (1.2, "metres or inches"),
                                          (30_000.0, "micrometres")])
def test_a_mesh_of_an_implausible_size_is_refused_unless_confirmed(side, likely, tmp_path):
    trimesh.creation.box((side, side, side)).export(tmp_path / "box.stl")
    with pytest.raises(InputError, match=likely) as refused:
        read_mesh(tmp_path / "box.stl")
    assert refused.value.parameter == "units_ok" and "no units stated" in str(refused.value)
    assert f"{MIN_OBJECT_MM:g} mm" in str(refused.value) or f"{MAX_OBJECT_MM:g} mm" in str(refused.value)
    assert read_mesh(tmp_path / "box.stl", units_ok=True).mesh.extents.max() == pytest.approx(side)


def test_a_mesh_that_states_its_units_is_sized_in_them(tmp_path):
    trimesh.creation.box((0.03, 0.03, 0.03)).export(tmp_path / "mm.3mf")
    with zipfile.ZipFile(tmp_path / "mm.3mf") as mm, zipfile.ZipFile(tmp_path / "m.3mf", "w") as m:
        for name in mm.namelist():
            data = mm.read(name)
            m.writestr(name, data.replace(b'unit="millimeter"', b'unit="meter"') if name.endswith(".model") else data)
    with pytest.raises(InputError, match="its units 'millimeter'"):
        read_mesh(tmp_path / "mm.3mf")
    read = read_mesh(tmp_path / "m.3mf")
    assert read.mesh.extents.max() == pytest.approx(30.0) and any("scaled by 1000" in n for n in read.notes)


def test_object_commands_confirm_a_mesh_size_with_units_ok(tmp_path, monkeypatch, capsys):
    trimesh.creation.box((1.2, 1.2, 1.2)).export(tmp_path / "inches.stl")
    monkeypatch.chdir(tmp_path)
    argv = ["object", "texture", "inches.stl", "--texture", "standard-1.0", "--out", "t.stl", "--edge-mm", "0.5",
            "--min-face-mm", "0.1"]  # a 1.2 mm cube's faces are narrower than the default 2 mm left untextured
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "largest extent is 1.2 mm" in err and "--units-ok" in err and not os.path.exists("t.stl")
    assert main([*argv, "--units-ok"]) == 0 and os.path.exists("t.stl")


def _stl_bytes(tmp_path) -> bytearray:
    trimesh.creation.box((10, 10, 10)).export(tmp_path / "box.stl")
    return bytearray((tmp_path / "box.stl").read_bytes())


def test_mesh_defects_are_reported_as_what_they_are(tmp_path):
    data = _stl_bytes(tmp_path)
    data[84 + 12:84 + 16] = struct.pack("<f", float("nan"))  # a corner of the first triangle
    (tmp_path / "nan.stl").write_bytes(data)
    with pytest.raises(InputError, match="1 of its 36 vertices have coordinates that are not finite"):
        read_mesh(tmp_path / "nan.stl")
    for declared in (0, 5, 500):
        data = _stl_bytes(tmp_path)
        data[80:84] = struct.pack("<I", declared)
        (tmp_path / "lying.stl").write_bytes(data)
        with pytest.raises(InputError, match=f"declares {declared} triangles .* but the file has 684 bytes "
                                             r"\(12 triangles\): it is truncated or its triangle count is wrong"):
            read_mesh(tmp_path / "lying.stl")
    (tmp_path / "short.stl").write_bytes(_stl_bytes(tmp_path)[:-7])
    with pytest.raises(InputError, match="not a whole number of 50-byte records"):
        read_mesh(tmp_path / "short.stl")
    box = trimesh.creation.box((10, 10, 10))
    vertices = "".join(f"v {x} {y} {z}\n" for x, y, z in box.vertices)
    (tmp_path / "zero.obj").write_text(vertices + "".join(f"f {a} {b} {c}\n" for a, b, c in box.faces))
    with pytest.raises(InputError, match=r"zero.obj, line 9: a face names vertex 0, but OBJ numbers vertices from 1"):
        read_mesh(tmp_path / "zero.obj")
    (tmp_path / "one.obj").write_text(vertices + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in box.faces))
    assert read_mesh(tmp_path / "one.obj").mesh.volume == pytest.approx(1000)


# --- C: an .x3p's checksum ---------------------------------------------------------------------------------------

def _tampered(path: Path, out: Path) -> Path:
    """``path`` with one byte of its point data changed (the zip's own CRCs rewritten to match)."""
    with zipfile.ZipFile(path) as source, zipfile.ZipFile(out, "w") as target:
        for name in source.namelist():
            data = source.read(name)
            target.writestr(name, bytes([data[0] ^ 1]) + data[1:] if name.endswith("data.bin") else data)
    return out


def test_an_x3p_whose_data_do_not_match_its_md5_is_refused(tmp_path):
    from SurfaceTopography import Topography

    path = tmp_path / "scan.x3p"
    Topography(np.arange(35.0).reshape(7, 5) * 1e-3, (7e-3, 5e-3), unit="mm").to_x3p(str(path))
    assert read_heightmap(path).kind.endswith("(X3P)")
    with zipfile.ZipFile(path) as z:
        stated = hashlib.md5(z.read("bindata/data.bin")).hexdigest().upper()
        assert f"<MD5ChecksumPointData>{stated}</MD5ChecksumPointData>" in z.read("main.xml").decode()
    with pytest.raises(InputError, match=f"its point data \\(bindata/data.bin\\) do not match the MD5 checksum its "
                                         f"main.xml states \\({stated}; the data's is "):
        read_heightmap(_tampered(path, tmp_path / "tampered.x3p"))


# --- E: scheduler files, model versions, unit keys ---------------------------------------------------------------

@pytest.mark.parametrize("text, message", [('{"address": 12}', 'whose "address" is the scheduler'),
                                           ("[1]", 'whose "address" is'), ('{"address": " "}', 'whose "address"'),
                                           ("xx", "cannot read"), ("", "cannot read")])
def test_a_scheduler_file_without_an_address_is_refused_by_name(text, message, tmp_path):
    path = tmp_path / "scheduler.json"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as refused:
        ClusterChoice.of(None, str(path), None)
    assert refused.value.parameter == "scheduler_file" and str(path) in str(refused.value)


def test_model_versions_fit_onnx_and_a_link_is_stamped_through(tiny, tmp_path, capsys):  # noqa: F811
    model = tmp_path / "model.onnx"
    model.write_bytes(tiny.model.read_bytes())
    before = model.read_bytes()
    assert main(["model-version", str(model), "--version", str(2**63)]) == 2
    err = capsys.readouterr().err
    assert "--version" in err and "Traceback" not in err and model.read_bytes() == before
    graph = onnx.load(str(model))
    with pytest.raises(InputError, match="at most 9223372036854775806"):
        set_version(graph, MAX_MODEL_VERSION + 1)
    link = tmp_path / "current.onnx"
    link.symlink_to(model.name)
    assert main(["model-version", str(link), "--version", str(MAX_MODEL_VERSION)]) == 0
    assert link.is_symlink() and os.readlink(link) == model.name
    assert onnx.load(str(model)).model_version == MAX_MODEL_VERSION


def test_a_unit_key_given_twice_is_refused():
    assert split_input("a.npy:pixel-mm=0.1,height-mm=2")[1].pixel_mm == 0.1
    with pytest.raises(InputError, match="pixel-mm is given twice"):
        split_input("a.npy:pixel-mm=0.1,pixel-mm=0.2")


# --- F: damage and odd files named as such -----------------------------------------------------------------------

def test_a_gwy_without_a_height_channel_says_so(tmp_path):
    from SurfaceTopography.IO.GWY import _gwy_write_object

    unit = lambda text: ("o", ("GwySIUnit", {"unitstr": ("s", text)}))  # noqa: E731
    field = {"xres": ("i", 4), "yres": ("i", 3), "xreal": ("d", 1e-3), "yreal": ("d", 1e-3), "si_unit_xy": unit("m"),
             "si_unit_z": unit("V"), "data": ("D", np.zeros(12))}
    with open(tmp_path / "volts.gwy", "wb") as f:
        f.write(b"GWYP")
        _gwy_write_object(f, "GwyContainer", {"/0/data": ("o", ("GwyDataField", field))})
    with pytest.raises(InputError, match="volts.gwy holds no height map: none of its channels"):
        read_heightmap(tmp_path / "volts.gwy")


def test_a_damaged_dataset_chunk_names_the_file_and_verify_reports_it(tmp_path, capsys):
    import h5py

    from roughness.dataset.recipe import Recipe, realise, sample_record

    path = tmp_path / "d.h5"
    recipe = Recipe(name="tiny", seed=5, families={"bumps": 1})
    with DatasetWriter(path, CONFIG, "test") as writer:
        for i in range(2):
            record = sample_record(recipe, i)
            hm = realise(record)
            writer.write_result(record, hm.heights, hm.pixel_mm, fake_fields(0.1), np.zeros((5, 5)))
    with h5py.File(path, "r") as f:
        sid = sorted(f["samples"])[0]
        chunk = f["samples"][sid]["heightmap"].id.get_chunk_info(0)
    data = bytearray(path.read_bytes())
    data[chunk.byte_offset + 100:chunk.byte_offset + 1100] = b"\xff" * 1000
    path.write_bytes(data)
    with open_dataset(path) as ds, pytest.raises(InputError, match=f"{path}: sample {sid} cannot be read"):
        ds.heightmap(sid)
    assert main(["dataset", "verify", str(path)]) == 1
    out = capsys.readouterr().out
    assert f"problem: samples/{sid}: {path}: sample {sid} cannot be read" in out and "1 problem(s)" in out
    assert len(verify(path)) == 1


def test_a_damaged_part_file_is_named(tmp_path):
    path = tmp_path / "d.h5"
    with DatasetWriter(path, CONFIG, "test") as writer:
        writer.write_failure({"family": "bumps", "seed": 1}, None, 0.05, "a failure")
    parts = path.with_name(path.name + ".parts")
    parts.mkdir(exist_ok=True)
    (parts / "0123456789abcdef.npz").write_bytes(b"PK\x03\x04 not a zip")
    with pytest.raises(InputError, match="0123456789abcdef.npz: a finished sample's part file that cannot be read"):
        open_dataset(path)
    assert any("0123456789abcdef.npz: unreadable" in p for p in verify(path))


def test_a_fifo_is_refused_unopened_as_model_and_heightmap(tmp_path, capsys):
    os.mkfifo(tmp_path / "model.onnx")
    os.mkfifo(tmp_path / "map.npy")
    example = Path(__file__).parents[1] / "examples" / "standard-1.0mm.png"
    assert main(["predict", str(example), "--model", str(tmp_path / "model.onnx")]) == 2
    assert "model.onnx is not a regular file (a FIFO, socket or device)" in capsys.readouterr().err
    with pytest.raises(InputError, match="map.npy is not a regular file"):
        read_heightmap(tmp_path / "map.npy", pixel_mm=0.05)


# --- G: old cases ------------------------------------------------------------------------------------------------

def test_an_empty_integer_npy_is_refused_as_empty(tmp_path):
    np.save(tmp_path / "empty.npy", np.zeros((0, 5), dtype=np.int16))
    with pytest.raises(InputError, match=r"empty.npy holds no heights: an empty array \(0 x 5 values of int16\)"):
        read_heightmap(tmp_path / "empty.npy", pixel_mm=0.05)


def test_a_damaged_fem_cache_entry_is_named_and_computed_again(tmp_path, monkeypatch):
    from roughness.engines import FemEngine
    from roughness.perception.values import stimulus_values
    from test_perception import _FakeResult

    calls = []

    def fake(engine, hm):
        calls.append(hm)
        return _FakeResult(hm.heights, engine.config.force_n)

    monkeypatch.setattr(FemEngine, "simulate", fake)
    hm = Heightmap(np.random.default_rng(0).uniform(0, 1, (20, 20)), 0.5)
    first = stimulus_values(["a"], [hm], "fem:coarse", tmp_path)
    (arrays,) = tmp_path.glob("arrays/*.npz")
    arrays.write_bytes(b"PK\x03\x04 damaged")
    lines = []
    again = stimulus_values(["a"], [hm], "fem:coarse", tmp_path, progress=lines.append)
    assert len(calls) == 2 and again[0].roughness == first[0].roughness
    assert any(f"{arrays}: a damaged entry of the result cache {tmp_path}" in line and "computed again" in line
               for line in lines), lines
    stimulus_values(["a"], [hm], "fem:coarse", tmp_path)
    assert len(calls) == 2  # the entry was replaced: from the cache again
    with (tmp_path / "results.jsonl").open("a") as f:
        f.write("[1, 2]\n")
    with pytest.raises(InputError, match="results.jsonl line 3 is not a result"):
        stimulus_values(["a"], [hm], "fem:coarse", tmp_path)

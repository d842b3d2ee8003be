"""Files are data: nothing read from a user's file runs code, model files are checked whole when
loaded, and ids that a spreadsheet could run as formulas never reach a CSV the tools write.

- A checkpoint carrying a Python object (a pickle ``__reduce__``) is refused by ``roughness export``
  and the object is never built; a real checkpoint of ``roughness train`` still exports.
- Broken ``--model`` files (wrong graph signature, missing outputs, NaN answers, metadata of the wrong
  type or out of its domain) are refused by every command that takes a model, naming ``--model``.
- Stimulus ids starting with ``=``, ``+``, ``-``, ``@`` (other than plain numbers) are refused on read;
  ``write_csv`` writes such text cells as text.
"""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import onnx
import pytest
import torch
from onnx import TensorProto, helper

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.core.files import write_csv
from roughness.surrogate.metadata import METADATA_KEY, onnx_metadata
from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel
from test_bad_inputs import BASE, PARSERS, _expect_refusal, _run, _snapshot
from test_surrogate import tiny  # noqa: F401 (a fixture: a short real training and its export)

SHIPPED = onnx_metadata(DEFAULT_MODEL).to_dict()  # valid metadata (patch 100 px, embedding of 64)


# ---------------------------------------------------------------- checkpoints: plain data only

class _Payload:
    """Unpickling it creates the file ``marker``: stands for any code a crafted checkpoint would run."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def test_malicious_checkpoint_is_refused_and_not_run(tmp_path, capsys):
    marker = tmp_path / "marker"
    checkpoint = tmp_path / "crafted.pt"
    torch.save({"state_dict": {}, "widths": [8], "note": _Payload(marker)}, checkpoint)
    code, err = _run(["export", str(checkpoint), "--out", str(tmp_path / "m.onnx")], capsys)
    assert code == 2 and "Traceback" not in err, err
    assert "crafted.pt is not a plain checkpoint" in err and "could run code" in err, err
    assert "weights_only" not in err  # torch's advice to load it unsafely is not passed on
    assert not marker.exists() and not (tmp_path / "m.onnx").exists()


def test_a_real_training_checkpoint_is_plain_and_exports(tiny, tmp_path, capsys):  # noqa: F811
    torch.load(tiny.checkpoint, weights_only=True)  # what train writes loads as plain data
    out = tmp_path / "again.onnx"
    assert main(["export", str(tiny.checkpoint), "--out", str(out)]) == 0, capsys.readouterr().err
    assert onnx_metadata(out) == onnx_metadata(tiny.model)


# ---------------------------------------------------------------- model files: checked whole on load

def _graph(input_name: str = "heights", size: int = 100, embedding: int = 64,
           outputs: tuple[str, ...] = ("log_roughness", "embedding"), nan: bool = False,
           spread: float | None = None) -> onnx.ModelProto:
    """A tiny stand-in network: embedding = mean height x ones(E), log V = mean of the embedding - 3
    (divided by zero with ``nan``: 0 / 0 on a flat patch); with ``spread``, an ensemble's output
    log_roughness_std = mean of the embedding + spread."""
    x = helper.make_tensor_value_info(input_name, TensorProto.FLOAT, ["batch", 1, size, size])
    nodes = [helper.make_node("ReduceMean", [input_name], ["m"], axes=[2, 3], keepdims=0),
             helper.make_node("Mul", ["m", "ones"], ["embedding"]),
             helper.make_node("ReduceMean", ["embedding"], ["mean"], axes=[1], keepdims=0),
             helper.make_node("Div" if nan else "Add", ["mean", "k"], ["log_roughness"])]
    init = [helper.make_tensor("ones", TensorProto.FLOAT, [1, embedding], [1.0] * embedding),
            helper.make_tensor("k", TensorProto.FLOAT, [], [0.0 if nan else -3.0])]
    shapes = {"log_roughness": ["batch"], "embedding": ["batch", embedding], "log_roughness_std": ["batch"]}
    if spread is not None:
        nodes.append(helper.make_node("Add", ["mean", "s"], ["log_roughness_std"]))
        init.append(helper.make_tensor("s", TensorProto.FLOAT, [], [spread]))
        outputs = (*outputs, "log_roughness_std")
    graph = helper.make_graph(nodes, "stand-in", [x], [helper.make_tensor_value_info(o, TensorProto.FLOAT, shapes[o])
                                                       for o in outputs], init)
    return helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)], ir_version=8)


def _save(model: onnx.ModelProto, path: Path, metadata: dict | str | None = None) -> Path:
    text = metadata if isinstance(metadata, str) else json.dumps(SHIPPED if metadata is None else metadata)
    model.metadata_props.add(key=METADATA_KEY, value=text)
    onnx.save(model, path)
    return path


def _without(key: str) -> dict:
    return {k: v for k, v in SHIPPED.items() if k != key}


BROKEN: dict[str, tuple[dict, str]] = {  # name: (how, what the message must say)
    "wrong-input": ({"graph": {"input_name": "x"}}, "not one input 'heights'"),
    "no-embedding": ({"graph": {"outputs": ("log_roughness",)}}, "lacks the output(s) embedding"),
    "nan-answer": ({"graph": {"nan": True}}, "not 2 finite numbers"),
    "negative-spread": ({"graph": {"spread": -0.1}}, "not 2 finite numbers >= 0"),
    "other-size": ({"graph": {"size": 64}}, "P = 100"),
    "other-embedding": ({"graph": {"embedding": 32}}, "E = 64"),
    "footprint-0": ({"meta": SHIPPED | {"footprint_mm": 0}}, "footprint_mm must be a positive finite number"),
    "pixel-text": ({"meta": SHIPPED | {"patch_pixel_mm": "0.1"}}, "patch_pixel_mm must be a positive finite"),
    "offset-neg": ({"meta": SHIPPED | {"log_offset": -1e-3}}, "log_offset must be a positive finite number"),
    "widths-neg": ({"meta": SHIPPED | {"widths": [-1]}}, "widths must be"),
    "odd-pixels": ({"meta": SHIPPED | {"patch_pixel_mm": 0.3}}, "whole number of pixels"),
    "no-domain": ({"meta": _without("domain")}, "missing keys: domain"),
    "bad-domain": ({"meta": SHIPPED | {"domain": {**SHIPPED["domain"], "threshold": None}}}, "domain threshold"),
    "not-json": ({"meta": "{widths: [8]"}, "metadata is not JSON"),
    "bogus-fidelity": ({"meta": SHIPPED | {"label_fidelity": "bogus"}}, "label_fidelity must be one of"),
    "bad-simulation": ({"meta": SHIPPED | {"simulation": {**SHIPPED["simulation"], "force_n": -1}}}, "force_n"),
}
# Every command that takes --model (from the parser), with its valid invocation from the bad-input sweep.
COMMANDS = {" ".join(path): [*path, *BASE[path], "--model"] for path, parser in PARSERS.items()
            if any("--model" in action.option_strings for action in parser._actions)}


def test_the_model_sweep_covers_the_model_commands():
    assert {"predict", "jnd", "tune", "homogeneity", "palette", "tactile-image"} <= set(COMMANDS)


def _broken(folder: Path, name: str) -> Path:
    how, _ = BROKEN[name]
    return _save(_graph(**how.get("graph", {})), folder / f"{name}.onnx", how.get("meta"))


def test_the_stand_in_network_is_a_usable_model(tmp_path):
    """The control: the unbroken stand-in loads and answers, so each broken one fails for its one fault."""
    model = SurrogateModel(_save(_graph(), tmp_path / "ok.onnx"))
    v, _ = model.run(np.zeros((3, 100, 100), np.float32))
    np.testing.assert_allclose(v, np.exp(-3.0) - SHIPPED["log_offset"], rtol=1e-6)
    ensemble = SurrogateModel(_save(_graph(spread=0.1), tmp_path / "ensemble.onnx"))
    estimate = ensemble.evaluate(np.zeros((3, 100, 100), np.float32))
    assert ensemble.has_std and np.allclose(estimate.relative_std, 0.1)


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("name", BROKEN)
def test_broken_model_is_refused_by_every_command(name, command, workdir, capsys):  # noqa: F811
    path = _broken(workdir, name)
    argv = [*COMMANDS[command], path.name]
    before = _snapshot(workdir)
    code, err = _run(argv, capsys)
    assert code == 2 and "Traceback" not in err, f"{argv}: exit {code}: {err[-600:]}"
    assert f"--model: {path.name}" in err and BROKEN[name][1] in err, err
    assert "--fidelity" not in err, err  # bad metadata blames the model, not a flag the user never gave
    assert _snapshot(workdir) == before


@pytest.mark.parametrize("name", ["nan-answer", "bogus-fidelity", "wrong-input"])
def test_broken_model_as_a_compare_engine(name, workdir, capsys):  # noqa: F811
    path = _broken(workdir, name)
    argv = ["compare", "maps", "--pixel-mm", "0.05", "--out", "report", "--engines", f"surrogate:{path.name}",
            "--reference", "ra"]
    _expect_refusal(argv, workdir, capsys, (path.name,))


def test_non_finite_answers_on_real_inputs_are_refused(tmp_path):
    """A model that is finite on a flat patch but not on others: no silent NaN either."""
    model = SurrogateModel(_save(_graph(), tmp_path / "ok.onnx"))  # log V = mean height - 3: -inf for these
    patches = np.full((2, 100, 100), -np.finfo(np.float32).max, np.float32)
    patches[:, 0, 0] = 0
    with pytest.raises(InputError, match="non-finite V .* for 2 of 2 patches") as caught:
        model.run(patches)
    assert caught.value.parameter == "model"


# ---------------------------------------------------------------- spreadsheet formulas in CSVs

FORMULAS = ["=HYPERLINK(\"http://x\")", "+1+2", "-2+cmd|' /C calc'!A0", "@SUM(A1:A2)"]


@pytest.mark.parametrize("ident", FORMULAS)
def test_formula_ids_are_refused_in_every_table(ident, workdir, capsys):  # noqa: F811
    quoted = ident.replace('"', '""')
    (workdir / "stimuli.csv").write_text(f'stimulus,texture\n"{quoted}",standard-1.0\nb,standard-1.25\n'
                                         "c,flattop-0.3\n")
    _expect_refusal(["perception", "design", "--stimuli", "stimuli.csv", "--trials", "10", "--out", "design.csv"],
                    workdir, capsys, (repr(ident),))
    (workdir / "stimuli.csv").write_text("stimulus,texture\na,standard-1.0\nb,standard-1.25\nc,flattop-0.3\n")
    (workdir / "trials.csv").write_text(f'subject,reference,left,right,answer\ns1,a,b,"{quoted}",left\n')
    _expect_refusal(["perception", "embed", "trials.csv", "--out", "emb"], workdir, capsys, (repr(ident),))
    (workdir / "embedding.csv").write_text(f'stimulus,coordinate,low,high\na,-1,-1.2,-0.8\n"{quoted}",0.1,0,0.2\n'
                                           "c,0.9,0.8,1\n")
    _expect_refusal(["perception", "fit", "embedding.csv", "--stimuli", "stimuli.csv", "--out", "fit"],
                    workdir, capsys, (repr(ident),))


def test_ids_that_are_plain_numbers_are_kept(workdir, capsys):  # noqa: F811
    (workdir / "stimuli.csv").write_text("stimulus,texture\n-1,standard-1.0\n+2,standard-1.25\n3,flattop-0.3\n")
    code, err = _run(["perception", "design", "--stimuli", "stimuli.csv", "--trials", "12", "--out", "design.csv"],
                     capsys)
    assert code == 0, err
    with open(workdir / "design.csv", newline="") as f:
        used = {row[c] for row in csv.DictReader(f) for c in ("reference", "left", "right")}
    assert used == {"-1", "+2", "3"}


def test_write_csv_writes_formula_text_as_text_and_numbers_as_numbers(tmp_path):
    path = write_csv(tmp_path / "t.csv", ["=head", "b"], [["=1+2", -0.5], ["-0.5", "+1e-3"], ["@x", "\tx"],
                                                          ["-x", "a=b"]])
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    assert rows == [["'=head", "b"], ["'=1+2", "-0.5"], ["-0.5", "+1e-3"], ["'@x", "'\tx"], ["'-x", "a=b"]]

"""Export a training checkpoint to one self-contained ONNX file and check it against PyTorch.

    roughness export runs/cnn/checkpoint.pt --out runs/cnn/model.onnx

The graph takes ``heights`` (batch, 1, P, P) float32 with a dynamic batch axis and returns
``log_roughness`` (batch,) and ``embedding`` (batch, E). Everything prediction needs besides the
weights (pixel size, log offset, input domain, label fidelity, metrics, data checksum) is stored
as JSON under the model's metadata key ``roughness``. The file is written only if onnxruntime
agrees with PyTorch on real textures (relative difference of V below ``RTOL``) for batch sizes
1 and 16, and the batch axis is really dynamic.
"""
from __future__ import annotations

import pickle
import re
import warnings
from pathlib import Path

import numpy as np
import onnx
import onnxruntime as ort
import torch

from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.files import atomic_write, check_output

from .metadata import METADATA_KEY, ModelMetadata, read_metadata
from .network import RoughnessNet
from .patch import footprint_patch
from .predictor import INPUT
from .target import roughness_from_log
from .versioning import set_version

RTOL = 1e-4
OUTPUTS = ("log_roughness", "embedding")


class ExportError(RuntimeError):
    """The exported graph disagrees with PyTorch or lacks a dynamic batch axis."""


def write_graph(model: torch.nn.Module, patches: np.ndarray, outputs: list[str], meta: ModelMetadata,
                model_version: int, path: str) -> None:
    """``model`` as an ONNX graph at ``path``: a dynamic batch axis, ``outputs`` named, the model's metadata and
    version in the file (traced on two of ``patches``)."""
    batch = torch.export.Dim("batch", min=1)
    torch.onnx.export(model, (torch.from_numpy(patches[:2]),), path, input_names=[INPUT], output_names=outputs,
                      dynamic_shapes=({0: batch},), external_data=False, dynamo=True)
    graph = onnx.load(path)
    graph.metadata_props.add(key=METADATA_KEY, value=meta.to_json())
    set_version(graph, model_version)
    onnx.save(graph, path)


def load_checkpoint(path: str | Path) -> tuple[RoughnessNet, ModelMetadata]:
    """The network (eval mode) and the checkpoint's metadata; InputError if it is not a training checkpoint.

    Only plain data is loaded (``weights_only``: tensors, dicts, lists, numbers, strings), so a file
    that carries other Python objects is refused without running anything in it.
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # torch's notes on pickle protocols: the error below says what matters
            checkpoint = torch.load(path, map_location="cpu", weights_only=True)
    except FileNotFoundError:
        raise InputError(f"checkpoint not found: {path}", parameter="checkpoint") from None
    except pickle.UnpicklingError as err:  # torch's text advises loading it unsafely: not passed on
        named = re.search(r"GLOBAL (\S+)", str(err))
        if named is None:
            raise InputError(f"{path} is not a roughness training checkpoint: not a plain PyTorch file of tensors, "
                             "dicts, lists, numbers and strings", parameter="checkpoint") from None
        raise InputError(f"{path} is not a plain checkpoint: it holds Python objects other than tensors, dicts, "
                         f"lists, numbers and strings ({named.group(1)}); they are not loaded, since loading them "
                         "could run code (`roughness train` writes plain checkpoints)",
                         parameter="checkpoint") from None
    except Exception as err:
        raise InputError(f"{path} is not a roughness training checkpoint: {err}", parameter="checkpoint") from None
    state = checkpoint.get("state_dict") if isinstance(checkpoint, dict) else None
    if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
        raise InputError(f"{path} is not a roughness training checkpoint (no state_dict of tensors)",
                         parameter="checkpoint")
    meta = ModelMetadata.from_dict({k: v for k, v in checkpoint.items() if k != "state_dict"}, str(path),
                                   parameter="checkpoint")
    with torch.device("meta"):  # no memory until the weights are assigned: metadata cannot claim a huge network
        model = RoughnessNet(meta.widths, meta.hidden, meta.query_h_mm, meta.engine_input)
    try:
        model.load_state_dict(state, assign=True)
    except RuntimeError as err:
        detail = " ".join(str(err).split())
        raise InputError(f"{path}: the weights do not fit the network its metadata describes ("
                         f"{detail[:300]}{'...' if len(detail) > 300 else ''})", parameter="checkpoint") from None
    return model.eval(), meta


def check_patches(n: int = 16) -> np.ndarray:
    """Footprint patches of ``n`` textures, every family drawn alike (bumps, natural and engineered)."""
    from roughness.dataset.families import FAMILIES
    from roughness.dataset.recipe import Recipe, realise, sample_record

    recipe = Recipe(name="export-check", seed=7, families={f: 1.0 for f in ("bumps", *FAMILIES)})
    return np.stack([footprint_patch(realise(sample_record(recipe, i))) for i in range(n)])[:, None]


def export(checkpoint_path: str | Path, out: str | Path, patches: np.ndarray | None = None,
           overwrite: bool = False, model_version: int = 1) -> dict:
    """Write the ONNX model to ``out`` after checking it; returns the check's numbers.

    ``model_version`` (a whole number >= 1) goes into the ONNX ``model_version`` field (surrogate/versioning.py).

    ``out`` must not exist unless ``overwrite``; it is written whole or not at all.
    """
    out = check_output(out, overwrite, "out")
    integer("model_version", model_version, minimum=1)
    model, meta = load_checkpoint(checkpoint_path)
    patches = check_patches() if patches is None else patches.astype(np.float32)
    report: dict = {}

    def write(tmp: str) -> None:
        write_graph(model, patches, list(OUTPUTS), meta, model_version, tmp)
        report.update(verify(model, tmp, patches))

    atomic_write(out, write, overwrite)
    return report | {"path": str(out), "bytes": out.stat().st_size, "model_version": model_version}


def verify(model: RoughnessNet, onnx_path: str, patches: np.ndarray) -> dict:
    """Dynamic batch axis present, and onnxruntime matches PyTorch at batch 1 and the full batch."""
    graph = onnx.load(onnx_path)
    dim = graph.graph.input[0].type.tensor_type.shape.dim[0]
    if not dim.dim_param:
        raise ExportError(f"the exported batch axis is fixed at {dim.dim_value}, not dynamic")
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    session = ort.InferenceSession(onnx_path, options, providers=["CPUExecutionProvider"])
    offset = read_metadata({p.key: p.value for p in graph.metadata_props}, onnx_path).log_offset
    with torch.no_grad():
        ref_log, ref_emb = (t.numpy() for t in model(torch.from_numpy(patches)))
    got_log = np.concatenate([session.run(list(OUTPUTS), {INPUT: patches[i:i + 1]})[0] for i in range(len(patches))])
    batch_log, batch_emb = session.run(list(OUTPUTS), {INPUT: patches})
    ref_v = roughness_from_log(ref_log, offset)
    worst = max(float(np.max(np.abs(roughness_from_log(got, offset) - ref_v) / np.maximum(ref_v, 1e-6)))
                for got in (got_log, batch_log))
    emb_diff = float(np.max(np.abs(batch_emb - ref_emb)) / max(np.max(np.abs(ref_emb)), 1e-12))
    if not worst < RTOL or not emb_diff < RTOL:
        raise ExportError(f"onnxruntime differs from PyTorch: relative difference {worst:.2e} in V and "
                          f"{emb_diff:.2e} in the embedding (limit {RTOL:.0e})")
    return {"max_rel_diff_V": worst, "max_rel_diff_embedding": emb_diff, "checked_inputs": len(patches),
            "batch_axis": dim.dim_param}

"""Model versions: the ONNX ``model_version`` of a surrogate file, set when it is exported and read with it.

    roughness model-version MODEL.onnx --version N

stamps an existing file with version N, rewriting only that field (the weights, graph and metadata stay
byte for byte, so its answers stay bit-identical; its content hash, the model id, changes). The shipped
model (``models/roughness-cnn.onnx`` and its int8 graph) has ``SHIPPED_MODEL_VERSION``; the v2 model
kept beside it for comparison (``roughness-cnn-v2.onnx``) has version 2.
A new model gets the next whole number; 0 is ONNX's "unversioned".
"""
from __future__ import annotations

from pathlib import Path

from roughness.core.checks import integer
from roughness.core.files import atomic_write

from .metadata import load_onnx, read_metadata

SHIPPED_MODEL_VERSION = 4


def set_version(graph, version: int) -> None:
    """Set the ONNX ``model_version`` of a loaded ``onnx.ModelProto`` (a whole number >= 1)."""
    graph.model_version = integer("model_version", version, minimum=1)


def stamp(path: str | Path, version: int) -> None:
    """Rewrite the surrogate file at ``path`` with ``model_version`` = ``version``, nothing else changed;
    InputError for ``model`` unless it is an ONNX file with roughness metadata."""
    import onnx

    path = Path(path)
    graph = load_onnx(path)
    read_metadata({p.key: p.value for p in graph.metadata_props}, path)
    before = [t.SerializeToString() for t in graph.graph.initializer]
    set_version(graph, version)
    if [t.SerializeToString() for t in graph.graph.initializer] != before:  # cannot happen; guards the promise
        raise RuntimeError("stamping the version changed the weights")
    atomic_write(path, lambda tmp: onnx.save(graph, tmp), overwrite=True)


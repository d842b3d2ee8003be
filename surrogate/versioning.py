"""Model versions: the ONNX ``model_version`` of a surrogate file, set when it is exported and read with it.

    roughness model-version MODEL.onnx --version N

stamps an existing file with version N, rewriting only that field (the weights, graph and metadata stay
byte for byte, so its answers stay bit-identical; its content hash, the model id, changes). The shipped
model (``models/roughness-cnn.onnx`` and its int8 graph) has ``SHIPPED_MODEL_VERSION``; the v2 model
kept beside it for comparison (``roughness-cnn-v2.onnx``) has version 2.
A new model gets the next whole number; 0 is ONNX's "unversioned".
"""
from __future__ import annotations

import os
from pathlib import Path

from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.files import atomic_write

from .metadata import load_onnx, read_metadata

SHIPPED_MODEL_VERSION = 4
MAX_MODEL_VERSION = 2**63 - 2
"""The largest version: ONNX stores an int64, and onnxruntime reads 2**63 - 1 as "unset"."""


def set_version(graph, version: int) -> None:
    """Set the ONNX ``model_version`` of a loaded ``onnx.ModelProto`` (a whole number in 1..MAX_MODEL_VERSION)."""
    version = integer("model_version", version, minimum=1)
    if version > MAX_MODEL_VERSION:
        raise InputError(f"model_version must be at most {MAX_MODEL_VERSION} (2**63 - 2: ONNX stores a 64-bit "
                         f"integer), got {version}", parameter="model_version")
    graph.model_version = version


def stamp(path: str | Path, version: int) -> None:
    """Rewrite the surrogate file at ``path`` with ``model_version`` = ``version``, nothing else changed;
    InputError for ``model`` unless it is an ONNX file with roughness metadata. A symbolic link is followed:
    the file it points to is stamped and the link kept."""
    import onnx

    path = Path(os.path.realpath(path))
    graph = load_onnx(path)
    read_metadata({p.key: p.value for p in graph.metadata_props}, path)
    before = [t.SerializeToString() for t in graph.graph.initializer]
    set_version(graph, version)
    if [t.SerializeToString() for t in graph.graph.initializer] != before:  # cannot happen; guards the promise
        raise RuntimeError("stamping the version changed the weights")
    atomic_write(path, lambda tmp: onnx.save(graph, tmp), overwrite=True)


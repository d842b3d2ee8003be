"""Model versions: the ONNX ``model_version`` of a surrogate file, set when it is exported and read with it.

    python -m roughness.surrogate.versioning MODEL.onnx --version N

stamps an existing file with version N, rewriting only that field (the weights, graph and metadata stay
byte for byte, so its answers stay bit-identical; its content hash, the model id, changes). The shipped
models are surrogate v2 (``models/roughness-cnn.onnx`` and its int8 graph): ``SHIPPED_MODEL_VERSION``.
A new model gets the next whole number; 0 is ONNX's "unversioned".
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.files import atomic_write

SHIPPED_MODEL_VERSION = 2


def set_version(graph, version: int) -> None:
    """Set the ONNX ``model_version`` of a loaded ``onnx.ModelProto`` (a whole number >= 1)."""
    graph.model_version = integer("model_version", version, minimum=1)


def stamp(path: str | Path, version: int) -> None:
    """Rewrite the ONNX file at ``path`` with ``model_version`` = ``version``, nothing else changed."""
    import onnx

    path = Path(path)
    if not path.is_file():
        raise InputError(f"model not found: {path}", parameter="model")
    graph = onnx.load(str(path), load_external_data=False)
    before = [t.SerializeToString() for t in graph.graph.initializer]
    set_version(graph, version)
    if [t.SerializeToString() for t in graph.graph.initializer] != before:  # cannot happen; guards the promise
        raise RuntimeError("stamping the version changed the weights")
    atomic_write(path, lambda tmp: onnx.save(graph, tmp), overwrite=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+", metavar="MODEL", help="ONNX files to stamp (rewritten in place)")
    parser.add_argument("--version", type=int, required=True, help="model version, a whole number >= 1")
    args = parser.parse_args(argv)
    try:
        for path in args.models:
            stamp(path, args.version)
    except InputError as err:
        print(f"roughness: error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

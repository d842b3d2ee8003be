"""`roughness model-version MODEL... --version N`: stamp exported surrogates with a model version in place
(surrogate/versioning.py)."""
from __future__ import annotations

import argparse

from .common import COUNT, finish


def add_parser(sub) -> None:
    p = sub.add_parser("model-version", help="set the model version (ONNX model_version) of exported surrogate files "
                                             "in place: weights, graph and metadata stay byte for byte, so their "
                                             "answers stay bit-identical (the model id changes)")
    p.add_argument("models", nargs="+", metavar="MODEL", help="ONNX surrogate files to stamp (rewritten in place)")
    p.add_argument("--version", type=COUNT, required=True,
                   help="model version, a whole number >= 1: the next after the model it replaces (the shipped "
                        "models are 2)")
    finish(p, run, model="MODEL", model_version="--version")


def run(args: argparse.Namespace) -> int:
    from roughness.surrogate.versioning import stamp

    for path in args.models:
        stamp(path, args.version)
    return 0

"""`roughness model-version MODEL... --version N`: stamp exported surrogates with a model version in place
(surrogate/versioning.py)."""
from __future__ import annotations

import argparse

from .common import Number, finish


def add_parser(sub) -> None:
    p = sub.add_parser("model-version", help="set the model version (ONNX model_version) of exported surrogate files "
                                             "in place: weights, graph and metadata stay byte for byte, so their "
                                             "answers stay bit-identical (the model id changes)")
    p.add_argument("models", nargs="+", metavar="MODEL", help="ONNX surrogate files to stamp (rewritten in place; a "
                                                             "symbolic link's target is stamped, the link kept)")
    from roughness.surrogate.versioning import MAX_MODEL_VERSION, SHIPPED_MODEL_VERSION

    p.add_argument("--version", type=Number(int, low=1, high=MAX_MODEL_VERSION), required=True,
                   help=f"model version, a whole number from 1 to 2**63 - 2: the next after the model it replaces "
                        f"(the shipped model is {SHIPPED_MODEL_VERSION})")
    finish(p, run, model="MODEL", model_version="--version")


def run(args: argparse.Namespace) -> int:
    from roughness.surrogate.versioning import stamp

    for path in args.models:
        stamp(path, args.version)
    return 0

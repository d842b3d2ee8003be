"""`roughness train` and `roughness export`: the CNN surrogate (needs torch)."""
from __future__ import annotations

import argparse
import json
import os
import sys

from .common import at_least_one


def add_parser(sub) -> None:
    tr = sub.add_parser("train", help="train the CNN surrogate on a dataset file (CPU, needs torch)")
    tr.add_argument("data", help="HDF5 dataset from `roughness dataset build`")
    tr.add_argument("--out", required=True, help="folder for checkpoint.pt, metrics.json, history.csv")
    tr.add_argument("--seed", type=int, default=0)
    tr.add_argument("--holdout-family", help="family never trained on, scored as out-of-family (default: the "
                    "dataset recipe's; 'none' to train on all)")
    tr.add_argument("--max-epochs", type=int, default=200)
    tr.add_argument("--max-minutes", type=float, default=25.0, help="wall-clock budget for the epochs")
    tr.add_argument("--threads", type=int, default=2, help="torch threads")
    tr.set_defaults(run=train)
    ex = sub.add_parser("export", help="export a training checkpoint to ONNX, checked against PyTorch")
    ex.add_argument("checkpoint")
    ex.add_argument("--out", required=True, help="ONNX file to write")
    ex.add_argument("--int8", metavar="FILE", help="also write an int8 model (static QDQ, per-channel weights)")
    ex.set_defaults(run=export)


def train(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError

    _require_torch("train")
    from roughness.surrogate.train import TrainConfig, train

    if not os.path.isfile(args.data):
        raise InputError(f"dataset file not found: {args.data}")
    at_least_one("--max-epochs", args.max_epochs)
    at_least_one("--threads", args.threads)
    train(TrainConfig(data=args.data, out=args.out, seed=args.seed, holdout_family=args.holdout_family,
                      max_epochs=args.max_epochs, max_minutes=args.max_minutes, threads=args.threads))
    return 0


def export(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError

    _require_torch("export")
    from roughness.surrogate.export import ExportError, export

    try:
        report = export(args.checkpoint, args.out)
    except ValueError as err:
        raise InputError(str(err)) from None
    except ExportError as err:
        print(f"roughness: export check failed, nothing written: {err}", file=sys.stderr)
        return 1
    print(json.dumps(report))
    if args.int8:
        from roughness.surrogate.quantize import QuantizationError, quantize

        try:
            print(json.dumps(quantize(args.out, args.int8)))
        except QuantizationError as err:
            print(f"roughness: int8 check failed, {args.int8} not written: {err}", file=sys.stderr)
            return 1
    return 0


def _require_torch(command: str) -> None:
    from importlib.util import find_spec

    from roughness.core.errors import InputError

    if find_spec("torch") is None or find_spec("onnx") is None:
        raise InputError(f"`roughness {command}` needs PyTorch and onnx: pip install \".[train]\" "
                         "(torch==2.13.0 is the CPU build)")

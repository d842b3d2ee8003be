"""`roughness ensemble CHECKPOINT... --out MODEL.onnx`: trained members as one ONNX graph that returns their mean
and spread (surrogate/ensemble.py; needs torch)."""
from __future__ import annotations

import argparse
import sys

from .common import add_overwrite, count, finish, json_text
from .train import require_torch, write_int8


def add_parser(sub) -> None:
    p = sub.add_parser("ensemble", help="join the checkpoints of `roughness train` runs (seeds) into one ONNX graph "
                                        "that returns their mean and spread, checked against PyTorch (needs torch)")
    p.add_argument("checkpoints", nargs="+", metavar="CHECKPOINT",
                   help="member training checkpoints (checkpoint.pt), at least 2")
    p.add_argument("--out", required=True, help="ONNX file to write; refused if it exists unless --overwrite")
    p.add_argument("--data", nargs="+", metavar="DATASET",
                   help="the members' training dataset (.h5; a multi-fidelity model's files in training order): "
                        "calibrate the spread on its validation split and report it on the test split (default: not "
                        "calibrated)")
    p.add_argument("--int8", metavar="FILE", help="also write the int8 graph of the ensemble (surrogate/quantize.py; "
                                                  "nothing is written if it strays from fp32 beyond its limits) "
                                                  "(default: none); refused if it exists unless --overwrite")
    from roughness.surrogate.versioning import MAX_MODEL_VERSION

    p.add_argument("--model-version", type=count(MAX_MODEL_VERSION), default=1,
                   help="the model's version (ONNX model_version), the next whole number (default: 1)")
    add_overwrite(p)
    finish(p, run, checkpoint="CHECKPOINT", checkpoints="CHECKPOINT")


def run(args: argparse.Namespace) -> int:
    from roughness.core.files import check_distinct, check_output

    check_distinct({"--out": args.out, "--int8": args.int8}, {"CHECKPOINT": args.checkpoints, "--data": args.data})
    require_torch("ensemble")
    from roughness.surrogate.ensemble import export_ensemble
    from roughness.surrogate.export import ExportError

    check_output(args.out, args.overwrite, "out")  # both outputs checked before anything is computed or written
    if args.int8:
        check_output(args.int8, args.overwrite, "int8")
    try:
        report = export_ensemble(args.checkpoints, args.out, args.data, args.overwrite, args.model_version)
    except ExportError as err:
        print(f"roughness: ensemble check failed, nothing written: {err}", file=sys.stderr)
        return 1
    print(json_text({k: v for k, v in report.items() if k != "member_val"}))
    return write_int8(args.out, args.int8, args.overwrite) if args.int8 else 0

"""`roughness train` and `roughness export`: the CNN surrogate (needs torch)."""
from __future__ import annotations

import argparse
import sys

from roughness.core.limits import MAX_CHANNELS

from .common import (
    BATCH,
    FRACTION,
    LENGTH,
    PARALLEL,
    SEED,
    add_overwrite,
    count,
    count_list,
    defaults,
    finish,
    json_text,
    positive,
)

MAX_EPOCHS = 100_000  # --max-epochs: an epoch of the shipped 3,000 samples takes seconds; --max-minutes stops sooner
MAX_MINUTES = 10_080.0  # --max-minutes: a week
MAX_FEM_WEIGHT = 1000.0  # --fem-weight: beyond, the spectral labels weigh nothing (train on FEM data alone)
MAX_LOG_OFFSET = 1.0  # --log-offset: above every V of the training sets (< 0.5): log(V + offset) resolves no V


def add_parser(sub) -> None:
    from roughness.surrogate.config import TrainConfig
    from roughness.surrogate.versioning import MAX_MODEL_VERSION

    d = defaults(TrainConfig)
    tr = sub.add_parser("train", help="train the CNN surrogate on a dataset file (CPU, needs torch)")
    tr.add_argument("data", metavar="DATASET",
                    help=f"HDF5 dataset from `roughness dataset build`: at least {d['batch_size']} training samples "
                         f"(the batch size) after the splits, about {TrainConfig('', '').minimum_samples()} ok "
                         "samples with the default fractions; thousands for a useful model")
    tr.add_argument("--out", required=True, help="folder for checkpoint.pt, metrics.json, history.csv, "
                                                 "predictions.csv; refused if it holds files unless --overwrite")
    tr.add_argument("--seed", type=SEED, default=d["seed"], help=f"seed of weights and batches (default: {d['seed']})")
    tr.add_argument("--holdout-family", default=d["holdout_family"],
                    help="family (or comma-separated families, e.g. knit,waffle) never trained on, scored as "
                         "out-of-family, with every mixture or shallow texture made of it (default: the dataset "
                         "recipe's; 'none' to train on all)")
    tr.add_argument("--batch-size", type=BATCH, default=d["batch_size"],
                    help=f"training batch size (default: {d['batch_size']})")
    tr.add_argument("--max-epochs", type=count(MAX_EPOCHS), default=d["max_epochs"],
                    help=f"epochs of the cosine schedule (default: {d['max_epochs']})")
    tr.add_argument("--max-minutes", type=positive(MAX_MINUTES), default=d["max_minutes"],
                    help=f"wall-clock budget for the epochs in minutes (default: {d['max_minutes']:g})")
    tr.add_argument("--widths", type=count_list, default=d["widths"], metavar="W1,W2,...",
                    help="channels of the convolution stages; each stage halves the grid (default: "
                         f"{','.join(map(str, d['widths']))})")
    tr.add_argument("--hidden", type=count(MAX_CHANNELS), default=d["hidden"],
                    help=f"units of the dense layer (default: {d['hidden']})")
    tr.add_argument("--threads", type=PARALLEL, default=d["threads"], help=f"torch threads (default: {d['threads']})")
    tr.add_argument("--levels", choices=("last", "all"), default=d["levels"],
                    help="labels: 'last', each sample's V; 'all', every mesh level the FEM solved for it (a default "
                         "build holds each texture's coarse V too), the contact spacing an input of the network "
                         f"(multi-fidelity) (default: {d['levels']})")
    tr.add_argument("--extra-data", nargs="+", default=[], metavar="DATASET",
                    help="--levels all: more datasets under the same physics, e.g. a fine build of the recipe's first "
                         "N samples, or FEM builds beside a spectral one (the engine is then an input and the model "
                         "answers as the FEM) (default: none)")
    tr.add_argument("--query-h-mm", type=LENGTH, default=d["query_h_mm"],
                    help="--levels all: the contact spacing in mm the model answers for (default: the finest "
                         "labelled)")
    tr.add_argument("--max-label-error", type=FRACTION, default=d["max_label_error"], metavar="FRACTION",
                    help="keep only the FEM labels whose estimated discretization error is at most FRACTION (e.g. "
                         "0.03), each at its finest level (default: all)")
    tr.add_argument("--fem-weight", type=positive(MAX_FEM_WEIGHT), default=d["fem_weight"],
                    help=f"loss weight of a FEM label relative to a spectral one (default: {d['fem_weight']:g})")
    tr.add_argument("--log-offset", type=positive(MAX_LOG_OFFSET), default=d["log_offset"],
                    help="the network predicts log(V + offset); a smaller offset resolves smaller V (default: "
                         f"{d['log_offset']:g})")
    tr.add_argument("--resume", action="store_true",
                    help="continue the interrupted run in --out from its last finished epoch (its resume.pt; the "
                         "same options and data, --threads aside); without a resume.pt, start a new run")
    add_overwrite(tr)
    finish(tr, train, data="DATASET")
    ex = sub.add_parser("export", help="export a training checkpoint to ONNX, checked against PyTorch")
    ex.add_argument("checkpoint", metavar="CHECKPOINT", help="checkpoint.pt of a `roughness train` run")
    ex.add_argument("--out", required=True, help="ONNX file to write; refused if it exists unless --overwrite")
    ex.add_argument("--int8", metavar="FILE", help="also write an int8 model (static QDQ, per-channel weights) "
                                                   "(default: none); refused if it exists unless --overwrite")
    ex.add_argument("--model-version", type=count(MAX_MODEL_VERSION), default=1,
                    help="the model's version, written as the ONNX model_version: the next whole number after the "
                         "model it replaces (the shipped models are 2) (default: 1)")
    add_overwrite(ex)
    finish(ex, export, checkpoint="CHECKPOINT")


def train(args: argparse.Namespace) -> int:
    import os

    from roughness.core.errors import InputError

    require_torch("train")
    from roughness.core.files import check_distinct, check_output_folder
    from roughness.surrogate.resume import RESUME_FILE
    from roughness.surrogate.train import TrainConfig, train

    check_distinct({"--out": args.out}, {"DATASET": args.data, "--extra-data": args.extra_data})
    if not (args.resume and os.path.isfile(os.path.join(args.out, RESUME_FILE))):
        check_output_folder(args.out, args.overwrite)
    for path, flag in [(args.data, "DATASET"), *((p, "--extra-data") for p in args.extra_data)]:
        if not os.path.isfile(path):
            raise InputError(f"{flag}: dataset file not found: {path}")
    if args.levels == "last" and (args.extra_data or args.query_h_mm is not None):
        raise InputError("--extra-data and --query-h-mm need --levels all (labels of several mesh levels)")
    train(TrainConfig(data=args.data, out=args.out, seed=args.seed, holdout_family=args.holdout_family,
                      batch_size=args.batch_size, max_epochs=args.max_epochs, max_minutes=args.max_minutes,
                      threads=args.threads, extra_data=tuple(args.extra_data), levels=args.levels,
                      query_h_mm=args.query_h_mm, widths=args.widths, hidden=args.hidden,
                      max_label_error=args.max_label_error, fem_weight=args.fem_weight, log_offset=args.log_offset),
          overwrite=args.overwrite, resume=args.resume)
    return 0


def export(args: argparse.Namespace) -> int:
    from roughness.core.files import check_distinct, check_output

    check_distinct({"--out": args.out, "--int8": args.int8}, {"CHECKPOINT": args.checkpoint})
    require_torch("export")
    from roughness.surrogate.export import ExportError, export

    check_output(args.out, args.overwrite, "out")  # both outputs checked before anything is computed or written
    if args.int8:
        check_output(args.int8, args.overwrite, "int8")
    try:
        report = export(args.checkpoint, args.out, overwrite=args.overwrite, model_version=args.model_version)
    except ExportError as err:
        print(f"roughness: export check failed, nothing written: {err}", file=sys.stderr)
        return 1
    print(json_text(report))
    return write_int8(args.out, args.int8, args.overwrite) if args.int8 else 0


def write_int8(model: str, int8: str, overwrite: bool) -> int:
    """Quantise ``model`` to ``int8`` and print the checks' numbers; exit code 1 (nothing written) if a check fails."""
    from roughness.surrogate.quantize import QuantizationError, quantize

    try:
        print(json_text(quantize(model, int8, overwrite=overwrite)))
    except QuantizationError as err:
        print(f"roughness: int8 check failed, {int8} not written: {err}", file=sys.stderr)
        return 1
    return 0


def require_torch(command: str) -> None:
    """InputError unless PyTorch and onnx are installed (``command``: the subcommand that needs them)."""
    from importlib.util import find_spec

    from roughness.core.errors import InputError

    if find_spec("torch") is None or find_spec("onnx") is None:
        raise InputError(f"`roughness {command}` needs PyTorch and onnx: pip install \".[train]\" "
                         "(torch==2.13.0 is the CPU build)")

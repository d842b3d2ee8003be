"""`roughness card RUN MODEL --card CARD.md --plots FOLDER`: the model card and accuracy plots of an exported
surrogate, from its training run (surrogate/card.py)."""
from __future__ import annotations

import argparse
from pathlib import Path

from .common import add_overwrite, finish


def add_parser(sub) -> None:
    p = sub.add_parser("card", help="write the model card (Markdown) of an exported surrogate and its accuracy and "
                                    "training plots, from its training run")
    p.add_argument("run_dir", metavar="RUN", help="folder of the model's `roughness train` run (predictions.csv, "
                                              "history.csv, metrics.json; an ensemble's member 0); refused unless "
                                              "it made MODEL")
    p.add_argument("model", metavar="MODEL", help="exported ONNX model")
    p.add_argument("--card", required=True, metavar="FILE", help="Markdown file to write; refused if it exists "
                                                                 "unless --overwrite")
    p.add_argument("--plots", required=True, metavar="FOLDER",
                   help="existing folder for the two PNG plots (surrogate_accuracy.png, surrogate_training.png); "
                        "refused if they exist unless --overwrite")
    p.add_argument("--latency", metavar="JSON", help="surrogate_latency.json of benchmarks/surrogate_latency.py "
                                                     "(default: none; used only if it timed this model)")
    add_overwrite(p)
    finish(p, run, run_dir="RUN", model="MODEL", model_path="MODEL", latency_path="--latency")


def run(args: argparse.Namespace) -> int:
    from roughness.core.files import check_distinct
    from roughness.surrogate.card import ACCURACY_PNG, TRAINING_PNG, write_card

    folder, plots = Path(args.run_dir), Path(args.plots)
    check_distinct({"--card": args.card, "--plots": [plots / ACCURACY_PNG, plots / TRAINING_PNG]},
                   {"RUN": [folder / name for name in ("predictions.csv", "history.csv", "metrics.json")],
                    "MODEL": args.model, "--latency": args.latency})
    write_card(folder, Path(args.model), Path(args.card), plots, Path(args.latency) if args.latency else None,
               args.overwrite)
    return 0

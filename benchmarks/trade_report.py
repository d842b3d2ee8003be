"""The speed/accuracy report of the shipped model on the committed validation set.

The validation set is `datasets/validation.json` (160 textures, all eight families, none in the
training set); its FEM `fine` labels are committed in benchmarks/results/trade/results.jsonl, the
cache of `roughness compare`, so regenerating the report recomputes nothing that is cached:

    python benchmarks/trade_report.py [--labels validation-fine.h5]

With ``--labels`` (the set built at fine fidelity by
`roughness dataset build --recipe datasets/validation.json --n 160 --fidelity fine --out validation-fine.h5`)
the stored fine labels are read from that file; without it, missing fine labels are computed
(about 13 s per texture). Writes table.{csv,md}, pareto.png, predicted_vs_reference.png,
error_by_family.png and report.md to benchmarks/results/trade/.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[1]
RECIPE = ROOT / "datasets" / "validation.json"
OUT = Path(__file__).parent / "results" / "trade"
N = 160
ENGINES = ("fem:coarse", "fem:default", "surrogate", "surrogate:models/roughness-cnn-int8.onnx", "ra", "p90",
           "glcm_sum_of_squares", "glcm_sum_variance")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--labels", help="the validation set built at fine fidelity (HDF5); the committed report "
                                         "(of the recipe) is replaced by the report of this file")
    args = parser.parse_args()
    from roughness.cli import main as cli

    source = ([str(Path(args.labels).resolve()), "--overwrite"] if args.labels
              else [str(RECIPE.relative_to(ROOT)), "--n", str(N)])
    os.chdir(ROOT)  # engine specs and the report name paths relative to the repository
    return cli(["compare", *source, "--out", str(OUT.relative_to(ROOT)), "--reference", "fem:fine", "--engines",
                *ENGINES])


if __name__ == "__main__":
    sys.exit(main())

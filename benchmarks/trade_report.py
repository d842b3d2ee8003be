"""The speed/accuracy report of the shipped model on the committed validation set.

The validation set is `recipes/validation.json` (160 textures, all eight families, none in the
training set). Its reference labels come from a build of that recipe: FEM converged to 1%
(`fem:converged@0.01`, the reference of Surrogate v2, issue 12), or earlier `fine`. Results are
cached in benchmarks/results/trade/results.jsonl (the cache of `roughness compare`, keyed by texture
content and engine configuration), so regenerating the report recomputes nothing that is cached:

    roughness dataset build --recipe recipes/validation.json --n 160 --fidelity converged --tolerance 0.01 \
        --workers 2 --out validation-converged.h5
    python benchmarks/trade_report.py --labels validation-converged.h5

The reference is the engine of the labels file (its stored V); without ``--labels`` missing `fine`
labels are computed (about 13 s per texture). Writes table.{csv,md}, pareto.png,
predicted_vs_reference.png, error_by_family.png and report.md to benchmarks/results/trade/.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[1]
RECIPE = ROOT / "recipes" / "validation.json"
OUT = Path(__file__).parent / "results" / "trade"
N = 160
ENGINES = ("fem:coarse", "fem:default", "fem:fine", "spectral", "surrogate",
           "surrogate:models/roughness-cnn-int8.onnx",
           "surrogate:models/roughness-cnn-v2.onnx",  # the previous model, kept for comparison
           "ra", "p90", "glcm_sum_of_squares", "glcm_sum_variance")


def reference_of(labels: Path) -> str:
    """The engine spec whose results a labels file stores (``fem:fine``, ``fem:converged@0.01``, ...)."""
    from roughness.dataset.reader import open_dataset
    from roughness.engines import fem_spec

    with open_dataset(labels) as data:
        return fem_spec(data.config.simulation)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--labels", help="the validation set built by FEM (HDF5), e.g. converged to 1%%; its labels "
                                         "are the reference, and the committed report is replaced by this one")
    args = parser.parse_args()
    from roughness.cli import main as cli

    if args.labels:
        labels = Path(args.labels).resolve()
        source, reference = [str(labels), "--overwrite"], reference_of(labels)
    else:
        source, reference = [str(RECIPE.relative_to(ROOT)), "--n", str(N)], "fem:fine"
    os.chdir(ROOT)  # engine specs and the report name paths relative to the repository
    engines = [e for e in ENGINES if e != reference]
    return cli(["compare", *source, "--out", str(OUT.relative_to(ROOT)), "--reference", reference,
                "--engines", *engines])


if __name__ == "__main__":
    sys.exit(main())

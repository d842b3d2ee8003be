"""Dataset generation throughput on this machine: samples per hour with 1 and 2 Dask workers.

Builds the first N samples of a training recipe into a temporary file, once per worker count,
in one run (so the ratio is measured under the same conditions). Wall time includes starting
the cluster and preparing the skin block(s) on every worker (meshes come from the on-disk cache
when present).

    python benchmarks/dataset_throughput.py [--n 30]   # coarse, recipes/training.json: dataset_throughput.md
    python benchmarks/dataset_throughput.py --recipe recipes/training-v2.json --fidelity converged \
        --workers 2 --n 40                             # writes dataset_throughput_converged.md
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from roughness.dataset.build import BUILD_CONFIG, build
from roughness.dataset.recipe import load_recipe
from roughness.simulate.config import FIDELITIES

ROOT = Path(__file__).parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=30, help="samples per run (default 30)")
    ap.add_argument("--fidelity", choices=FIDELITIES, default=BUILD_CONFIG.fidelity,
                    help=f"FEM fidelity (default {BUILD_CONFIG.fidelity}, as training sets are built)")
    ap.add_argument("--recipe", type=Path, default=ROOT / "recipes" / "training.json",
                    help="recipe (default recipes/training.json)")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="worker counts (default 1 2)")
    args = ap.parse_args()
    recipe = load_recipe(args.recipe)
    rows = []
    for workers in args.workers:
        with tempfile.TemporaryDirectory() as tmp:
            t = time.perf_counter()
            counts = build(str(Path(tmp) / "t.h5"), args.n, recipe, replace(BUILD_CONFIG, fidelity=args.fidelity),
                           workers=workers, quiet=True)
            wall = time.perf_counter() - t
        rows.append({"workers": workers, "samples": args.n, "failed": counts["failed"], "wall_s": wall,
                     "samples_per_hour": 3600 * args.n / wall})
        print(rows[-1], flush=True)
    speedup = rows[-1]["samples_per_hour"] / rows[0]["samples_per_hour"] if len(rows) > 1 else None
    out = ROOT / "benchmarks" / "results"
    stem = "dataset_throughput" + ("" if args.fidelity == "coarse" else f"_{args.fidelity}")
    (out / f"{stem}.json").write_text(json.dumps({"recipe": args.recipe.name, "fidelity": args.fidelity,
                                                  "rows": rows, "speedup": speedup}, indent=1))
    lines = [f"Dataset generation, first {args.n} samples of recipes/{args.recipe.name}, {args.fidelity} fidelity, "
             "2-core machine (wall time includes cluster start and block preparation per worker):", "",
             "| workers | samples | failed | wall (s) | samples / hour |", "|---|---|---|---|---|"]
    lines += [f"| {r['workers']} | {r['samples']} | {r['failed']} | {r['wall_s']:.1f} | {r['samples_per_hour']:.0f} |"
              for r in rows]
    if speedup is not None:
        lines += ["", f"{rows[-1]['workers']} workers / {rows[0]['workers']}: {speedup:.2f}x"]
    (out / f"{stem}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

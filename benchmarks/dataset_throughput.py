"""Dataset generation throughput on this machine: samples per hour with 1 and 2 Dask workers.

Builds the first N samples of the training recipe at coarse fidelity into a temporary file,
once per worker count, in one run (so the ratio is measured under the same conditions).
Wall time includes starting the cluster and preparing the skin block on every worker.

    python benchmarks/dataset_throughput.py [--n 30]   # writes benchmarks/results/dataset_throughput.md
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
    args = ap.parse_args()
    recipe = load_recipe(ROOT / "datasets" / "training.json")
    rows = []
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as tmp:
            t = time.perf_counter()
            counts = build(str(Path(tmp) / "t.h5"), args.n, recipe, replace(BUILD_CONFIG, fidelity=args.fidelity),
                           workers=workers, quiet=True)
            wall = time.perf_counter() - t
        rows.append({"workers": workers, "samples": args.n, "failed": counts["failed"], "wall_s": wall,
                     "samples_per_hour": 3600 * args.n / wall})
        print(rows[-1], flush=True)
    speedup = rows[1]["samples_per_hour"] / rows[0]["samples_per_hour"]
    out = ROOT / "benchmarks" / "results"
    (out / "dataset_throughput.json").write_text(json.dumps({"rows": rows, "speedup": speedup}, indent=1))
    lines = [f"Dataset generation, first {args.n} samples of datasets/training.json, {args.fidelity} fidelity, "
             "2-core machine (wall time includes cluster start and block preparation per worker):", "",
             "| workers | samples | failed | wall (s) | samples / hour |", "|---|---|---|---|---|"]
    lines += [f"| {r['workers']} | {r['samples']} | {r['failed']} | {r['wall_s']:.1f} | {r['samples_per_hour']:.0f} |"
              for r in rows]
    lines += ["", f"2 workers / 1 worker: {speedup:.2f}x"]
    (out / "dataset_throughput.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

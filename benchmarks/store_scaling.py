"""Dataset store at scale: write, open and iterate a synthetic dataset of N samples.

Samples are synthetic (random maps, fake FEM result fields, like tests/test_store.py); map sizes
are the --map/--strain sides in pixels. Times are wall-clock seconds on this machine, one run each:

- write:   N ``write_result`` calls and the writer's ``close`` (which packs the file)
- open:    ``open_dataset`` (reads the index) and ``len``, on a fresh process's first open
- table:   ``Dataset.table()``
- iterate: ``iter_samples()`` over every sample, maps included

    python benchmarks/store_scaling.py [--n 10000] [--label after]   # appends to benchmarks/results/store_scaling.md

Run it from outside a source tree (or with PYTHONPATH naming the tree) to measure another checkout.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "store_scaling.md"
CONFIG = {"simulation": {"fidelity": "coarse", "force_n": 10.0}, "recipe": {"name": "synthetic"}}
READ = """
import sys, time
from roughness.dataset.reader import open_dataset
t = time.perf_counter()
ds = open_dataset(sys.argv[1]); n = len(ds)
t_open = time.perf_counter() - t
t = time.perf_counter(); ds.table(); t_table = time.perf_counter() - t
t = time.perf_counter(); m = sum(1 for _ in ds.iter_samples(None)); t_iter = time.perf_counter() - t
ds.close()
print(n, m, t_open, t_table, t_iter)
"""


def fields(i: int) -> dict:
    return {"roughness": 0.1 + i * 1e-5, "roughness_stderr": 0.002, "contact_fraction": 0.9, "indentation_mm": 0.6,
            "converged": True, "iterations": 3, "unresolved_nodes": 0, "cycled": False, "seconds": 1.5,
            "contact_history": [10, 12, 12], "grid_axis_mm": np.linspace(-4, 4, 41)}


def write(path: Path, n: int, side: int, strain_side: int) -> float:
    from roughness.dataset.writer import DatasetWriter

    rng = np.random.default_rng(0)
    start = time.perf_counter()
    with DatasetWriter(path, CONFIG, "benchmark") as writer:
        for i in range(n):
            texture_record = {"family": "fbm", "params": {"hurst": 0.5}, "seed": i, "perturbation": None}
            writer.write_result(texture_record, rng.random((side, side)), 0.05, fields(i),
                                rng.normal(size=(strain_side, strain_side)))
    return time.perf_counter() - start


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=10000, help="samples (default 10000)")
    ap.add_argument("--map", type=int, default=64, help="heightmap side in pixels (default 64)")
    ap.add_argument("--strain", type=int, default=41, help="fluctuation map side in pixels (default 41)")
    ap.add_argument("--label", default="", help="row label, e.g. the store version (default: none)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "synthetic.h5"
        t_write = write(path, args.n, args.map, args.strain)
        size_mb = path.stat().st_size / 1e6
        out = subprocess.run([sys.executable, "-c", READ, str(path)], capture_output=True, text=True, check=True,
                             cwd=tmp)  # not the current folder: the code read is the one PYTHONPATH names
        n, m, t_open, t_table, t_iter = out.stdout.split()
    assert int(n) == int(m) == args.n, (n, m)
    row = (f"| {args.label} | {args.n} | {args.map}/{args.strain} | {size_mb:.0f} | {t_write:.1f} | "
           f"{float(t_open):.3f} | {float(t_table):.3f} | {float(t_iter):.1f} |")
    print(row)
    if not RESULTS.exists():
        RESULTS.write_text("# Dataset store at scale (benchmarks/store_scaling.py)\n\n"
                           "| store | samples | map/strain px | file MB | write s | open s | table s | iterate s |\n"
                           "|---|---|---|---|---|---|---|---|\n")
    with open(RESULTS, "a") as f:
        f.write(row + "\n")


if __name__ == "__main__":
    main()

"""Old against new source tree on the slowest validation textures, warm, alternating fresh processes.

Each process prepares the block with one slow partial-contact texture (not timed), then solves
three more one after the other (the tail textures of benchmarks/fem_tail.py) and reports seconds,
contact rounds, CG iterations, AMG set-ups and V. The two trees run alternately ``--repeats``
times, so a change of machine speed hits both.

    git archive <commit> | tar -x -C /tmp/base
    python benchmarks/fem_slow_ab.py --baseline /tmp/base [--fidelity fine] [--repeats 2]
    # writes benchmarks/results/fem_slow_ab.{md,json}
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results"
PREPARE = "0d8f15a921f63835"  # validation textures (recipes/validation.json) of the fem_tail table
TEXTURES = ("1e04876c42a53a11", "0d8f15a921f63835", "caf9f9db88bb4dab")


def one_process(fidelity: str) -> list[dict]:
    from roughness.dataset.recipe import expand, load_recipe, realise
    from roughness.dataset.schema import sample_id
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    records = {sample_id(r): r for r in expand(load_recipe(ROOT / "recipes" / "validation.json"), 160)}
    sim = Simulator(SimConfig(fidelity=fidelity))
    sim.run(realise(records[PREPARE]), estimate_error=False)
    rows = []
    for sid in TEXTURES:
        start = time.perf_counter()
        r = sim.run(realise(records[sid]), estimate_error=False)
        rows.append({"id": sid, "seconds": time.perf_counter() - start, "rounds": r.iterations,
                     "cg_iterations": r.cg_iterations, "amg_setups": r.amg_setups, "V": r.roughness})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--baseline", type=Path, help="the old source tree (required unless --one)")
    parser.add_argument("--fidelity", default="fine", choices=("coarse", "default", "fine"),
                        help="fidelity (default fine)")
    parser.add_argument("--repeats", type=int, default=2, help="processes per tree (default 2)")
    parser.add_argument("--one", action="store_true", help="internal: one process of this tree, print JSON")
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one_process(args.fidelity)))
        return
    if args.baseline is None:
        parser.error("--baseline DIR is required")
    runs: dict[str, list[list[dict]]] = {"old": [], "new": []}
    for _ in range(args.repeats):
        for name, source in (("old", args.baseline), ("new", ROOT)):
            env = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(source)}
            out = subprocess.run([sys.executable, __file__, "--one", "--fidelity", args.fidelity], env=env,
                                 check=True, capture_output=True, text=True).stdout
            runs[name].append(json.loads(out.strip().splitlines()[-1]))
            print(name, runs[name][-1], flush=True)
    OUT.mkdir(exist_ok=True)
    (OUT / "fem_slow_ab.json").write_text(json.dumps({"fidelity": args.fidelity, "baseline": str(args.baseline),
                                                      "runs": runs}, indent=1))
    lines = [f"# Slow partial-contact textures, old (`{args.baseline.name}`) against new, {args.fidelity}, warm", "",
             f"Regenerate: `python benchmarks/fem_slow_ab.py --baseline DIR --fidelity {args.fidelity}`. "
             f"{args.repeats} fresh processes per tree, alternating; one BLAS thread.", "",
             "| run | tree | seconds per texture | total (s) | rounds | CG iterations | AMG set-ups | V |",
             "|---|---|---|---|---|---|---|---|"]
    for i in range(args.repeats):
        for name in ("old", "new"):
            rows = runs[name][i]
            seconds = ", ".join(f"{r['seconds']:.2f}" for r in rows)
            values = ", ".join(f"{r['V']:.6g}" for r in rows)
            lines.append(f"| {i + 1} | {name} | {seconds} | "
                         f"{sum(r['seconds'] for r in rows):.1f} | {[r['rounds'] for r in rows]} | "
                         f"{[r['cg_iterations'] for r in rows]} | {[r['amg_setups'] for r in rows]} | "
                         f"{values} |")
    totals = {name: [sum(r["seconds"] for r in rows) for rows in runs[name]] for name in runs}
    ratios = [new / old for new, old in zip(totals["new"], totals["old"])]
    lines += ["", f"new / old total seconds per run: {', '.join(f'{x:.3f}' for x in ratios)}"]
    (OUT / "fem_slow_ab.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

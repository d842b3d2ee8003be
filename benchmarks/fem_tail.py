"""Tail latency of the FEM: which textures take long, and why (contact rounds, CG iterations).

Takes the validation textures whose stored `fine` labels took longest (the committed trade
cache, benchmarks/results/trade/results.jsonl, holds each label's build time) and a few of
median time, solves each once with a warm block, and records per contact round the nodes in
contact, released and added, and the CG iterations; plus the contact fraction and V.

    python benchmarks/fem_tail.py [--fidelity default] [--slowest 8] [--typical 4]
    # writes benchmarks/results/fem_tail.{md,json} (other fidelities: fem_tail_<fidelity>.{md,json})
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[1]
CACHE = ROOT / "benchmarks" / "results" / "trade" / "results.jsonl"
OUT = ROOT / "benchmarks" / "results"


def stored_fine_seconds() -> dict[str, float]:
    """Texture id -> seconds of its stored fem:fine label (from the validation build)."""
    rows = [json.loads(line) for line in CACHE.read_text().splitlines() if line.strip()]
    return {r["texture"]: r["seconds"] for r in rows if r.get("engine") == "fem:fine" and "texture" in r}


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fidelity", default="default", choices=("coarse", "default", "fine"),
                        help="fidelity to re-solve the textures at (default: default)")
    parser.add_argument("--slowest", type=int, default=8, help="slowest stored textures to solve (default 8)")
    parser.add_argument("--typical", type=int, default=4, help="textures of median stored time (default 4)")
    return parser.parse_args()


def main() -> None:
    args = parse_args()
    from roughness.dataset.recipe import expand, load_recipe, realise
    from roughness.dataset.schema import sample_id
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    seconds = stored_fine_seconds()
    ranked = sorted(seconds, key=seconds.get, reverse=True)
    middle = len(ranked) // 2
    chosen = ranked[:args.slowest] + ranked[middle - args.typical // 2:middle + (args.typical + 1) // 2]
    records = {sample_id(r): r for r in expand(load_recipe(ROOT / "recipes" / "validation.json"), len(seconds))}
    sim = Simulator(SimConfig(fidelity=args.fidelity))
    sim.run(realise(records[chosen[0]]), estimate_error=False)  # the block is prepared once (not timed)
    rows = []
    for sid in chosen:
        rounds = []
        start = time.perf_counter()
        result = sim.run(realise(records[sid]), estimate_error=False, callback=rounds.append)
        rows.append({"id": sid, "family": records[sid]["family"], "stored_fine_s": seconds[sid],
                     "slow": sid in ranked[:args.slowest], "seconds": time.perf_counter() - start,
                     "rounds": len(rounds), "cg_iterations": sum(r.cg_iterations for r in rounds),
                     "contact_fraction": result.contact_fraction, "V": result.roughness,
                     "per_round": [(r.in_contact, r.released, r.added, r.cg_iterations) for r in rounds]})
        print(json.dumps(rows[-1]), flush=True)
    OUT.mkdir(exist_ok=True)
    stem = "fem_tail" + ("" if args.fidelity == "default" else f"_{args.fidelity}")
    (OUT / f"{stem}.json").write_text(json.dumps({"fidelity": args.fidelity, "rows": rows}, indent=1))
    lines = [f"# FEM tail latency ({args.fidelity}, warm block, one BLAS thread)", "",
             f"Regenerate: `python benchmarks/fem_tail.py --fidelity {args.fidelity}`. The slowest validation textures by the build time of "
             "their stored `fine` label, and some of median time, solved again one after the other in one "
             "process. Per round: nodes in contact / released / added / CG iterations.", "",
             "| texture | family | stored fine (s) | now (s) | rounds | CG iterations | contact fraction | rounds |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        per = " ".join(f"{a}/{b}/{c}/{d}" for a, b, c, d in r["per_round"])
        lines.append(f"| {r['id']}{' (slow)' if r['slow'] else ''} | {r['family']} | {r['stored_fine_s']:.1f} | "
                     f"{r['seconds']:.2f} | {r['rounds']} | {r['cg_iterations']} | {r['contact_fraction']:.3f} | {per} |")
    slow = [r for r in rows if r["slow"]]
    typical = [r for r in rows if not r["slow"]]
    for name, group in (("slow", slow), ("typical", typical)):
        if group:
            lines.append(f"\n{name}: median {statistics.median(r['seconds'] for r in group):.2f} s, "
                         f"{statistics.median(r['rounds'] for r in group):g} rounds, "
                         f"{statistics.median(r['cg_iterations'] for r in group):g} CG iterations, contact fraction "
                         f"{statistics.median(r['contact_fraction'] for r in group):.3f}")
    (OUT / f"{stem}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

"""FEM cost per stage and peak memory at each fidelity, and the linear-solver choice.

Each fidelity runs in a fresh process with an empty mesh cache (cold: mesh, assembly,
sampler, base field with the AMG set-up), then on five standard textures with the block
warm. A second table times one constrained solve of the default block with each solver.

    python benchmarks/fem_stages.py            # writes benchmarks/results/fem_stages.{md,json,png}
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

OUT = Path(__file__).parent / "results"
FIDELITIES = ("coarse", "default", "fine")
WARM_TEXTURES = [(0.75, 1), (1.0, 2), (1.25, 3), (1.5, 4), (0.625, 5)]


def one_fidelity(fidelity: str) -> dict:
    from roughness.dataset.textures import standard_texture
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    sim = Simulator(SimConfig(fidelity=fidelity))
    t = time.perf_counter()
    first = sim.run(standard_texture(1.0, seed=0))
    cold = time.perf_counter() - t
    warm = []
    for lam, seed in WARM_TEXTURES:
        rounds = []
        r = sim.run(standard_texture(lam, seed=seed), callback=rounds.append)
        warm.append({"seconds": r.seconds, **r.stage_seconds, "rounds": r.iterations,
                     "cg_iterations": [x.cg_iterations for x in rounds], "amg_setups": r.amg_setups})
    stages = {k: float(sum(w[k] for w in warm) / len(warm)) for k in ("contact", "strain", "variation")}
    return {
        "fidelity": fidelity, "nodes": first.nodes, "dofs": first.dofs, "h_contact_mm": first.config.h_contact_mm,
        "cold_seconds": cold, "cold_stages": first.stage_seconds,
        "warm_seconds_mean": sum(w["seconds"] for w in warm) / len(warm),
        "warm_seconds_max": max(w["seconds"] for w in warm),
        "warm_stages": stages, "warm_rounds": [w["rounds"] for w in warm],
        "warm_cg_iterations": [w["cg_iterations"] for w in warm], "warm_amg_setups": [w["amg_setups"] for w in warm],
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def solver_comparison() -> list[dict]:
    """One solve of the default block with every bottom node held (the textures' regime)."""
    import numpy as np
    import pyamg
    import scipy.sparse.linalg as sla

    from roughness.simulate.config import SimConfig
    from roughness.simulate.linsolve import AMGCache, constrain
    from roughness.simulate.model import Block

    block = Block(SimConfig().resolved().block_spec())
    p = block.problem
    fixed = p.constraints(np.ones(len(p.bottom), dtype=bool), frictionless=False)
    values = np.zeros(p.n_dofs)
    values[3 * p.top + 2] = -1.0
    k = p.stiffness
    free = ~fixed
    a = k[free][:, free].tocsc()
    b = -(k[free][:, fixed] @ values[fixed])
    rows = []
    t = time.perf_counter()
    system = constrain(k, fixed, AMGCache(p.amg.near_null))  # a fresh hierarchy is built here
    setup = time.perf_counter() - t
    t = time.perf_counter()
    u = system.solve(values).u
    rows.append({"solver": "pyamg SA + CG (fresh hierarchy)", "setup_s": setup, "solve_s": time.perf_counter() - t})
    t = time.perf_counter()
    system.solve(values, x0=u + 1e-3 * np.random.default_rng(0).standard_normal(len(u)))
    rows.append({"solver": "pyamg SA + CG (reused hierarchy, warm start)", "setup_s": 0.0,
                 "solve_s": time.perf_counter() - t})
    t = time.perf_counter()
    lu = sla.splu(a)
    setup = time.perf_counter() - t
    t = time.perf_counter()
    x = lu.solve(b)
    rows.append({"solver": "scipy splu (SuperLU)", "setup_s": setup, "solve_s": time.perf_counter() - t,
                 "max_diff_to_amg": float(np.abs(x - u[free]).max() / np.abs(x).max())})
    try:
        import pypardiso
        import scipy.sparse as sp

        solver = pypardiso.PyPardisoSolver()
        solver.set_matrix_type(2)
        t = time.perf_counter()
        solver.factorize(sp.triu(a).tocsr())
        setup = time.perf_counter() - t
        t = time.perf_counter()
        solver.solve(sp.triu(a).tocsr(), b)
        rows.append({"solver": "MKL Pardiso (pypardiso)", "setup_s": setup, "solve_s": time.perf_counter() - t})
    except ImportError:
        pass
    t = time.perf_counter()
    ml = pyamg.smoothed_aggregation_solver(a.tocsr(), symmetry="symmetric")
    setup = time.perf_counter() - t
    t = time.perf_counter()
    ml.solve(b, tol=1e-7, accel="cg")
    rows.append({"solver": "pyamg SA + CG without rigid-body modes", "setup_s": setup, "solve_s": time.perf_counter() - t})
    for r in rows:
        r["dofs"] = int(free.sum())
    return rows


def plot(rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
    names = ["mesh", "assembly", "sampler", "base_field"]
    bottom = [0.0] * len(rows)
    labels = [f"{r['fidelity']}\n{r['nodes']} nodes" for r in rows]
    for name in names:
        vals = [r["cold_stages"].get(name, 0.0) for r in rows]
        ax.bar(labels, vals, bottom=bottom, label=f"cold: {name}")
        bottom = [b + v for b, v in zip(bottom, vals)]
    for name in ("contact", "strain", "variation"):
        vals = [r["warm_stages"][name] for r in rows]
        ax.bar(labels, vals, bottom=bottom, label=f"per texture: {name}", hatch="//")
        bottom = [b + v for b, v in zip(bottom, vals)]
    ax.set(ylabel="seconds", title="FEM cost per stage (2 cores)")
    ax.legend(fontsize=7)
    fig.savefig(OUT / "fem_stages.png", dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--one", choices=FIDELITIES, help="internal: measure one fidelity in this process, print JSON")
    parser.add_argument("--solvers", action="store_true", help="internal: only the solver comparison, print JSON")
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one_fidelity(args.one)))
        return
    if args.solvers:
        print(json.dumps(solver_comparison()))
        return
    OUT.mkdir(exist_ok=True)
    rows = []
    for fidelity in FIDELITIES:
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "ROUGHNESS_CACHE": cache, "OMP_NUM_THREADS": "2"}
            out = subprocess.run([sys.executable, __file__, "--one", fidelity], env=env, check=True,
                                 capture_output=True, text=True).stdout
            rows.append(json.loads(out.strip().splitlines()[-1]))
            print(rows[-1], flush=True)
    env = {**os.environ, "OMP_NUM_THREADS": "2"}
    solvers = json.loads(subprocess.run([sys.executable, __file__, "--solvers"], env=env, check=True,
                                        capture_output=True, text=True).stdout.strip().splitlines()[-1])
    (OUT / "fem_stages.json").write_text(json.dumps({"fidelities": rows, "solvers": solvers}, indent=1))
    lines = ["| fidelity | h (mm) | nodes | mesh (s) | assembly (s) | sampler (s) | base field + AMG (s) | "
             "cold total (s) | contact (s/texture) | strain (s) | variation (s) | warm total (s/texture, mean / max) "
             "| contact rounds | peak RSS (MB) |", "|" + "---|" * 14]
    for r in rows:
        c, w = r["cold_stages"], r["warm_stages"]
        lines.append(f"| {r['fidelity']} | {r['h_contact_mm']} | {r['nodes']} | {c['mesh']:.2f} | {c['assembly']:.2f} "
                     f"| {c['sampler']:.2f} | {c['base_field']:.2f} | {r['cold_seconds']:.2f} | {w['contact']:.2f} "
                     f"| {w['strain']:.3f} | {w['variation']:.4f} | {r['warm_seconds_mean']:.2f} / "
                     f"{r['warm_seconds_max']:.2f} | {r['warm_rounds']} | {r['peak_rss_mb']:.0f} |")
    lines += ["", f"Linear solvers, one solve of the default block ({solvers[0]['dofs']} free DOFs, all contact nodes held):",
              "", "| solver | set-up (s) | solve (s) |", "|---|---|---|"]
    lines += [f"| {s['solver']} | {s['setup_s']:.2f} | {s['solve_s']:.2f} |" for s in solvers]
    (OUT / "fem_stages.md").write_text("\n".join(lines) + "\n")
    plot(rows)
    print("\n".join(lines))


if __name__ == "__main__":
    main()

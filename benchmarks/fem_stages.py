"""FEM cost per stage and peak memory at each fidelity, and the linear-solver choice.

Each fidelity runs in a fresh process with an empty mesh cache (cold: mesh, assembly,
sampler, base field with the AMG set-up), then on the 24 textures of the convergence panel
(studies/convergence_panel.py: every family, small-feature, sparse and low-relief textures)
with the block warm. A second table times one constrained solve of the default block with each solver.

``--baseline DIR`` also runs every fidelity with the source tree in DIR (e.g. the commit
before a speed change: ``git archive <commit> | tar -x -C DIR``), alternating old and new
processes, and adds a table of new/old time ratios and the largest relative change of V.
On a shared machine, only those same-run ratios are meaningful.

    python benchmarks/fem_stages.py                          # writes benchmarks/results/fem_stages.{md,json,png}
    python benchmarks/fem_stages.py --baseline /tmp/base     # plus the old-vs-new table
"""
from __future__ import annotations

import argparse
import inspect
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

OUT = Path(__file__).parent / "results"
FIDELITIES = ("coarse", "default", "fine")
REPEATS = 5


def _first_texture(fidelity: str):
    """A fresh simulator, the run options, its first (cold) result and that run's seconds."""
    from roughness.dataset.textures import standard_texture
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    sim = Simulator(SimConfig(fidelity=fidelity))
    # one level per texture: the discretization estimate's coarser solve is not a stage (older trees lack the flag)
    single = {"estimate_error": False} if "estimate_error" in inspect.signature(sim.run).parameters else {}
    t = time.perf_counter()
    first = sim.run(standard_texture(1.0, seed=0), **single)
    return sim, single, first, time.perf_counter() - t


def cold_only(fidelity: str) -> dict:
    """Seconds of the first texture in a fresh process (mesh, assembly, sampler, base field, solve)."""
    _, _, first, cold = _first_texture(fidelity)
    return {"fidelity": fidelity, "cold_seconds": cold, "cold_stages": first.stage_seconds}


def one_fidelity(fidelity: str) -> dict:
    from studies.convergence_panel import panel

    sim, single, first, cold = _first_texture(fidelity)
    warm = []
    roughness = [first.roughness]
    for make in panel().values():
        rounds = []
        r = sim.run(make(), callback=rounds.append, **single)
        roughness.append(r.roughness)
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
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "roughness": roughness,
    }


def _mean(values: list[float]) -> float:
    return sum(values) / len(values)


def solver_comparison(direct: bool, fidelity: str = "default") -> list[dict]:
    """One solve of the ``fidelity`` block with every bottom node held (the textures' regime).

    Each time is the best of ``REPEATS`` (the machine may be shared); ``direct`` adds SuperLU
    and MKL Pardiso (if pypardiso is installed), whose factorizations are timed once.
    """
    import numpy as np
    import pyamg
    import scipy.sparse as sp
    import scipy.sparse.linalg as sla

    from roughness.simulate.config import SimConfig
    from roughness.simulate.linsolve import AMGCache, constrain
    from roughness.simulate.model import Block

    block = Block(SimConfig(fidelity=fidelity).resolved().block_spec())
    p = block.problem
    fixed = p.constraints(np.ones(len(p.bottom), dtype=bool), frictionless=False)
    values = np.zeros(p.n_dofs)
    values[3 * p.top + 2] = -1.0
    k = p.stiffness
    free = ~fixed
    rng = np.random.default_rng(0)

    def best(fn, repeats: int = REPEATS) -> tuple[float, object]:
        times, out = [], None
        for _ in range(repeats):
            t = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t)
        return min(times), out

    def ours(name: str, precision: type) -> tuple[dict, np.ndarray, np.ndarray]:
        setup, system = best(lambda: constrain(k, fixed, AMGCache(p.amg.near_null, precision=precision)))
        solve, sol = best(lambda: system.solve(values))
        x0 = sol.u + 1e-3 * rng.standard_normal(len(sol.u))
        warm, warm_sol = best(lambda: system.solve(values, x0=x0))
        row = {"solver": f"pyamg SA + CG, {name}", "setup_s": setup, "solve_s": solve, "warm_solve_s": warm,
               "iterations": sol.iterations, "warm_iterations": warm_sol.iterations}
        return row, sol.u, x0

    rows = [ours("float32 V-cycle (now)", np.float32)[0]]
    row, u, x0 = ours("float64 V-cycle", np.float64)
    rows.append(row)
    system = constrain(k, fixed, p.amg)
    reference = u
    # Before: pyamg's own preconditioner, which also evaluates two residuals per application.
    matrix, b = system.matrix, np.where(fixed, system.diag * values, -(k @ np.where(fixed, values, 0.0)))
    setup, ml = best(lambda: pyamg.smoothed_aggregation_solver(matrix, B=p.amg.near_null, symmetry="symmetric"))
    m = ml.aspreconditioner(cycle="V")
    tol = {"rtol": 0.0, "atol": 1e-6 * np.linalg.norm(b)}
    solve, (x, _) = best(lambda: sla.cg(matrix, b, M=m, **tol))
    warm, _ = best(lambda: sla.cg(matrix, b, x0=x0, M=m, **tol))
    rows.insert(0, {"solver": "pyamg SA + CG, pyamg aspreconditioner (before)", "setup_s": setup, "solve_s": solve,
                    "warm_solve_s": warm, "max_diff": float(np.abs(x - reference).max() / np.abs(reference).max())})
    if direct:
        a = k[free][:, free].tocsc()
        rhs = b[free]
        setup, lu = best(lambda: sla.splu(a), 1)  # tens of seconds
        solve, _ = best(lambda: lu.solve(rhs))
        rows.append({"solver": "scipy splu (SuperLU)", "setup_s": setup, "solve_s": solve})
        try:
            import pypardiso
        except ImportError:
            pypardiso = None
        if pypardiso is not None:
            upper = sp.triu(a).tocsr()
            solver = pypardiso.PyPardisoSolver()
            solver.set_matrix_type(2)
            setup, _ = best(lambda: solver.factorize(upper), 1)
            solve, _ = best(lambda: solver.solve(upper, rhs))
            rows.append({"solver": "MKL Pardiso (pypardiso)", "setup_s": setup, "solve_s": solve})
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


def measure(fidelity: str, threads: int, source: Path | None = None, mode: str = "--one") -> dict:
    """``one_fidelity`` (``mode`` "--cold": ``cold_only``) in a fresh process with an empty mesh cache,
    importing roughness from ``source`` (default: this tree)."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "ROUGHNESS_CACHE": cache, "OMP_NUM_THREADS": str(threads)}
        env["PYTHONPATH"] = str(source or Path(__file__).resolve().parents[1])  # roughness and studies
        out = subprocess.run([sys.executable, __file__, mode, fidelity], env=env, check=True,
                             capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def stage_table(rows: list[dict]) -> list[str]:
    lines = [("| fidelity | h (mm) | nodes | mesh (s) | assembly (s) | sampler (s) | base field + AMG (s) | "
             "cold total (s) | contact (s/texture) | strain (s) | variation (s) | warm total (s/texture, mean / max) "
             "| contact rounds (mean / max) | peak RSS (MB) |"), "|" + "---|" * 14]
    for r in rows:
        c, w = r["cold_stages"], r["warm_stages"]
        lines.append(f"| {r['fidelity']} | {r['h_contact_mm']} | {r['nodes']} | {c['mesh']:.2f} | {c['assembly']:.2f} "
                     f"| {c['sampler']:.2f} | {c['base_field']:.2f} | {r['cold_seconds']:.2f} | {w['contact']:.2f} "
                     f"| {w['strain']:.3f} | {w['variation']:.4f} | {r['warm_seconds_mean']:.2f} / "
                     f"{r['warm_seconds_max']:.2f} | {_mean(r['warm_rounds']):.1f} / {max(r['warm_rounds'])} "
                     f"| {r['peak_rss_mb']:.0f} |")
    return lines


def ratio_table(pairs: list[tuple[dict, dict]]) -> list[str]:
    """New/old time ratios per stage and the largest relative change of V, per fidelity."""
    lines = [("| fidelity | assembly | base field + AMG | cold total | contact (warm) | warm total (mean) "
             "| max relative change of V | CG iterations per texture (mean), old -> new |"), "|" + "---|" * 8]
    for old, new in pairs:
        change = max(abs(a - b) / abs(b) for a, b in zip(new["roughness"], old["roughness"]))
        cg = f"{_mean([sum(x) for x in old['warm_cg_iterations']]):.1f} -> {_mean([sum(x) for x in new['warm_cg_iterations']]):.1f}"
        lines.append(f"| {new['fidelity']} | {new['cold_stages']['assembly'] / old['cold_stages']['assembly']:.2f} "
                     f"| {new['cold_stages']['base_field'] / old['cold_stages']['base_field']:.2f} "
                     f"| {new['cold_seconds'] / old['cold_seconds']:.2f} "
                     f"| {new['warm_stages']['contact'] / old['warm_stages']['contact']:.2f} "
                     f"| {new['warm_seconds_mean'] / old['warm_seconds_mean']:.2f} | {change:.1e} | {cg} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--one", choices=FIDELITIES, help="internal: measure one fidelity in this process, print JSON")
    parser.add_argument("--cold", choices=FIDELITIES, help="internal: only the first texture in this process, print JSON")
    parser.add_argument("--cold-repeats", type=int, default=3,
                        help="fresh processes per fidelity (and tree) timing only the cold first texture (default 3)")
    parser.add_argument("--solvers", action="store_true", help="internal: only the solver comparison, print JSON")
    parser.add_argument("--fidelities", nargs="+", choices=FIDELITIES, default=list(FIDELITIES),
                        help="fidelities to measure (default: all three)")
    parser.add_argument("--baseline", type=Path, metavar="DIR",
                        help="a source tree of roughness to compare against, run alternately in the same session")
    parser.add_argument("--threads", type=int, default=2, help="OMP_NUM_THREADS of the measured processes (default 2)")
    parser.add_argument("--direct", action="store_true",
                        help="also time direct solvers (SuperLU, and MKL Pardiso if pypardiso is installed)")
    parser.add_argument("--solver-fidelity", choices=FIDELITIES, default="default",
                        help="block of the solver comparison (default: default)")
    parser.add_argument("--note", default="", help="a sentence on the machine's state, written above the tables")
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one_fidelity(args.one)))
        return
    if args.cold:
        print(json.dumps(cold_only(args.cold)))
        return
    if args.solvers:
        print(json.dumps(solver_comparison(args.direct, args.solver_fidelity)))
        return
    OUT.mkdir(exist_ok=True)
    rows, pairs = [], []
    for fidelity in args.fidelities:
        if args.baseline is not None:
            old = measure(fidelity, args.threads, args.baseline)
            print("baseline", old, flush=True)
        rows.append(measure(fidelity, args.threads))
        print(rows[-1], flush=True)
        if args.baseline is not None:
            pairs.append((old, rows[-1]))
    trees = [("new", None)] + ([("old", args.baseline)] if args.baseline is not None else [])
    colds: dict[str, dict[str, list[float]]] = {f: {name: [] for name, _ in trees} for f in args.fidelities}
    for fidelity in args.fidelities:
        for _ in range(args.cold_repeats):  # the trees alternate, so a change of machine speed hits both
            for name, source in trees:
                colds[fidelity][name].append(measure(fidelity, args.threads, source, "--cold")["cold_seconds"])
        print("cold", fidelity, colds[fidelity], flush=True)
    env = {**os.environ, "OMP_NUM_THREADS": str(args.threads)}
    command = [sys.executable, __file__, "--solvers", "--solver-fidelity", args.solver_fidelity]
    command += ["--direct"] if args.direct else []
    solvers = json.loads(subprocess.run(command, env=env, check=True, capture_output=True,
                                        text=True).stdout.strip().splitlines()[-1])
    (OUT / "fem_stages.json").write_text(json.dumps(
        {"threads": args.threads, "note": args.note, "solver_fidelity": args.solver_fidelity, "fidelities": rows, "solvers": solvers,
         "baseline": [old for old, _ in pairs], "cold_repeats": colds}, indent=1))
    lines = ([args.note, ""] if args.note else []) + [f"OMP_NUM_THREADS={args.threads}.", ""] + stage_table(rows)
    if pairs:
        lines += ["", (f"New / old, measured alternately in the same session against the source tree "
                      f"`{args.baseline.name}` (below 1: faster now):"), ""] + ratio_table(pairs)
    if args.cold_repeats:
        lines += ["", (f"Cold first texture (default force, standard lambda 1 mm) in {args.cold_repeats} more fresh "
                       "processes per fidelity and tree, alternating, empty mesh cache: min / median (s)"), "",
                  "| fidelity | " + " | ".join(name for name, _ in trees) + " |", "|---|" + "---|" * len(trees)]
        lines += [f"| {f} | " + " | ".join(f"{min(colds[f][name]):.2f} / {statistics.median(colds[f][name]):.2f}"
                                          for name, _ in trees) + " |" for f in args.fidelities]
    lines += ["", (f"Linear solvers, one solve of the {args.solver_fidelity} block ({solvers[0]['dofs']} free DOFs, all contact nodes "
                  f"held; best of {REPEATS}):"), "", "| solver | set-up (s) | solve (s) | warm-started solve (s) |",
              "|---|---|---|---|"]
    lines += [f"| {s['solver']} | {s['setup_s']:.2f} | {s['solve_s']:.2f} | "
              f"{s['warm_solve_s']:.2f} |" if "warm_solve_s" in s else
              f"| {s['solver']} | {s['setup_s']:.2f} | {s['solve_s']:.2f} | |" for s in solvers]
    (OUT / "fem_stages.md").write_text("\n".join(lines) + "\n")
    plot(rows)
    print("\n".join(lines))


if __name__ == "__main__":
    main()

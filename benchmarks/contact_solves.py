"""Where a warm texture's contact time goes: texture solves, unit-bone solves, system set-up, the rest.

The contact loop (simulate/contact.py) solves twice per round on the same constrained
system: the texture gaps with the bone held, and a unit bone displacement. This script wraps
``ConstrainedSystem`` (timing only, nothing changes) and splits each warm texture's contact
time into those two solves, the constrained-system construction and the loop's own work,
so that the levers "one solve per round" and "fewer rounds" can be priced.

    python benchmarks/contact_solves.py                     # default fidelity, five standard textures
    python benchmarks/contact_solves.py --fidelity fine
"""
from __future__ import annotations

import argparse
import time
from collections import defaultdict

WARM_TEXTURES = [(0.75, 1), (1.0, 2), (1.25, 3), (1.5, 4), (0.625, 5)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fidelity", choices=("coarse", "default", "fine"), default="default",
                        help="mesh fidelity (default: default)")
    args = parser.parse_args()

    import numpy as np

    from roughness.dataset.textures import standard_texture
    from roughness.simulate import linsolve
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    clock: dict[str, float] = defaultdict(float)
    count: dict[str, int] = defaultdict(int)
    build, solve = linsolve.ConstrainedSystem.__init__, linsolve.ConstrainedSystem.solve

    def timed_build(self, *a, **k):
        t = time.perf_counter()
        build(self, *a, **k)
        clock["system"] += time.perf_counter() - t

    def timed_solve(self, values, load=None, x0=None):
        kind = "unit" if np.all(values[values != 0] == -1.0) else "texture"  # unit: -1 mm on the bone face only
        t = time.perf_counter()
        out = solve(self, values, load, x0)
        clock[kind] += time.perf_counter() - t
        count[kind + "_iterations"] += out.iterations
        count[kind] += 1
        return out

    linsolve.ConstrainedSystem.__init__, linsolve.ConstrainedSystem.solve = timed_build, timed_solve
    sim = Simulator(SimConfig(fidelity=args.fidelity))
    sim.run(standard_texture(1.0, seed=0), estimate_error=False)
    print(f"{args.fidelity}, per warm texture: contact s | texture solves s (n, CG it) | unit-bone solves s (n, CG it) "
          "| system set-up s | rest s | rounds")
    totals = defaultdict(float)
    for lam, seed in WARM_TEXTURES:
        clock.clear()
        count.clear()
        r = sim.run(standard_texture(lam, seed=seed), estimate_error=False)
        contact = r.stage_seconds["contact"]
        rest = contact - clock["texture"] - clock["unit"] - clock["system"]
        print(f"lambda {lam}: {contact:.2f} | {clock['texture']:.2f} ({count['texture']}, {count['texture_iterations']}) "
              f"| {clock['unit']:.2f} ({count['unit']}, {count['unit_iterations']}) | {clock['system']:.2f} "
              f"| {rest:.2f} | {r.iterations}", flush=True)
        for key, value in (("contact", contact), ("texture", clock["texture"]), ("unit", clock["unit"]),
                           ("system", clock["system"]), ("rounds", r.iterations)):
            totals[key] += value
    share = {k: totals[k] / totals["contact"] for k in ("texture", "unit", "system")}
    print(f"shares of contact time: texture solves {share['texture']:.0%}, unit-bone solves {share['unit']:.0%}, "
          f"system set-up {share['system']:.0%}; {totals['contact'] / totals['rounds']:.2f} s per round")


if __name__ == "__main__":
    main()

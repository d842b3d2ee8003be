"""Where a warm texture's contact time goes: force-controlled solves, system set-up, the rest.

The contact loop (simulate/contact.py) solves once per round: the texture gaps prescribed and
the bone a force-controlled rigid plate (``ConstrainedSystem.solve_plate``; until 2026-11 it
solved twice, texture and unit bone, and combined them). This script wraps
``ConstrainedSystem`` (timing only, nothing changes) and splits each warm texture's contact
time into the plate solves, plain solves (the bone's unit response, once per block), the
constrained-system construction and the loop's own work, so that the levers "fewer rounds"
and "cheaper rounds" can be priced.

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

    from roughness.dataset.textures import standard_texture
    from roughness.simulate import linsolve
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    clock: dict[str, float] = defaultdict(float)
    count: dict[str, int] = defaultdict(int)
    build = linsolve.ConstrainedSystem.__init__

    def timed_build(self, *a, **k):
        t = time.perf_counter()
        build(self, *a, **k)
        clock["system"] += time.perf_counter() - t

    def timed(kind, solve):
        def wrapped(self, *a, **k):
            t = time.perf_counter()
            out = solve(self, *a, **k)
            clock[kind] += time.perf_counter() - t
            count[kind + "_iterations"] += out.iterations
            count[kind] += 1
            return out
        return wrapped

    linsolve.ConstrainedSystem.__init__ = timed_build
    linsolve.ConstrainedSystem.solve = timed("plain", linsolve.ConstrainedSystem.solve)
    linsolve.ConstrainedSystem.solve_plate = timed("plate", linsolve.ConstrainedSystem.solve_plate)
    sim = Simulator(SimConfig(fidelity=args.fidelity))
    sim.run(standard_texture(1.0, seed=0), estimate_error=False)
    print(f"{args.fidelity}, per warm texture: contact s | plate solves s (n, CG it) | plain solves s (n, CG it) "
          "| system set-up s | rest s | rounds")
    totals = defaultdict(float)
    for lam, seed in WARM_TEXTURES:
        clock.clear()
        count.clear()
        r = sim.run(standard_texture(lam, seed=seed), estimate_error=False)
        contact = r.stage_seconds["contact"]
        rest = contact - clock["plate"] - clock["plain"] - clock["system"]
        print(f"lambda {lam}: {contact:.2f} | {clock['plate']:.2f} ({count['plate']}, {count['plate_iterations']}) "
              f"| {clock['plain']:.2f} ({count['plain']}, {count['plain_iterations']}) | {clock['system']:.2f} "
              f"| {rest:.2f} | {r.iterations}", flush=True)
        for key, value in (("contact", contact), ("plate", clock["plate"]), ("plain", clock["plain"]),
                           ("system", clock["system"]), ("rounds", r.iterations)):
            totals[key] += value
    share = {k: totals[k] / totals["contact"] for k in ("plate", "plain", "system")}
    print(f"shares of contact time: plate solves {share['plate']:.0%}, plain solves {share['plain']:.0%}, "
          f"system set-up {share['system']:.0%}; {totals['contact'] / totals['rounds']:.2f} s per round")


if __name__ == "__main__":
    main()

"""Effect of the CG tolerance (relative residual) on V and on the time per texture, default fidelity.

    python benchmarks/cg_tolerance.py 1e-7     # V of five standard textures, mean/max seconds, rounds, CG work
"""
from __future__ import annotations

import argparse

WARM_TEXTURES = [(0.75, 1), (1.0, 2), (1.25, 3), (1.5, 4), (0.625, 5)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("rtol", type=float, help="CG stopping tolerance |b - A u| / |b| (the model uses 1e-6)")
    args = parser.parse_args()

    import numpy as np

    from roughness.dataset.textures import standard_texture
    from roughness.simulate import SimConfig, Simulator

    sim = Simulator(SimConfig())
    sim.block(SimConfig().resolved()).problem.rtol = args.rtol  # before the first solve on the block
    sim.run(standard_texture(1.0, seed=0), estimate_error=False)
    out = []
    for lam, seed in WARM_TEXTURES:
        rounds = []
        r = sim.run(standard_texture(lam, seed=seed), callback=rounds.append, estimate_error=False)
        out.append((r.roughness, r.seconds, r.iterations, [x.cg_iterations for x in rounds], r.amg_setups))
    print(args.rtol, [f"{v:.6f}" for v, *_ in out], "mean s", round(float(np.mean([o[1] for o in out])), 2),
          "max", round(max(o[1] for o in out), 2), "rounds", [o[2] for o in out],
          "CG iterations per round", [o[3] for o in out], "AMG set-ups", [o[4] for o in out])


if __name__ == "__main__":
    main()

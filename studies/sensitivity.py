"""Sensitivity of V to force, Poisson ratio and the sampling (d, r), as in the paper's Figure 18.

The 13 standard textures (lambda 0.625..1.625 mm), two realisations each (seeds 100, 101), at
`coarse` fidelity. Force and nu rerun the FEM; (d, r) resample the strain fluctuation maps of the
10 N baseline (pair distance d and disk radius r, mm). Without perceptual data, "sensitivity" is
shown as V against lambda per setting, the change of V against the baseline, and whether the
ordering by lambda survives (Spearman of lambda and V).

    python studies/sensitivity.py      # about 6 min on 2 cores; writes studies/results/sensitivity.*
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy.stats import spearmanr  # noqa: E402

OUT = Path(__file__).parent / "results"
FORCES_N = (5.0, 7.5, 10.0, 15.0, 20.0)
POISSON = (0.3, 0.4, 0.45, 0.49)
DISTANCES_MM = (0.4, 0.6, 0.8, 1.0, 1.2, 1.6)
RADII_MM = (0.2, 0.4, 0.6, 0.8, 1.0)
SEEDS = (100, 101)


def sweep(sim, textures: dict, **override) -> tuple[np.ndarray, list]:
    """Mean V over seeds per lambda, and the baseline results (for resampling)."""
    results = [[sim.run(hm, estimate_error=False, **override) for hm in by_seed] for by_seed in textures.values()]
    return np.array([[r.roughness for r in row] for row in results]).mean(1), results


def main() -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    from roughness.dataset.textures import STANDARD_LAMBDAS_MM, standard_texture
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator
    from roughness.simulate.variation import PairSampling, variation

    lambdas = np.array(STANDARD_LAMBDAS_MM)
    textures = {lam: [standard_texture(lam, seed=s) for s in SEEDS] for lam in lambdas}
    sim = Simulator(SimConfig(fidelity="coarse"))
    force = {}
    for f in FORCES_N:
        force[f], results = sweep(sim, textures, force_n=f)
        if f == 10.0:
            baseline = results
        print(f"force {f} N: {np.round(force[f], 4).tolist()}", flush=True)
    poisson = {}
    for nu in POISSON:
        poisson[nu] = force[10.0] if nu == 0.45 else sweep(sim, textures, poisson=nu)[0]
        print(f"nu {nu}: {np.round(poisson[nu], 4).tolist()}", flush=True)
    sampling = {}
    for d in DISTANCES_MM:
        for r in RADII_MM:
            if 4.0 - d / 2 - r <= 0:
                continue
            pairs = PairSampling(8.0, d, r, 8000, 0)
            v = np.array([[variation(res.fluctuation, res.grid_axis_mm, pairs)[0] for res in row] for row in baseline])
            sampling[(d, r)] = v.mean(1)
    result = {
        "lambdas_mm": lambdas.tolist(), "seeds": list(SEEDS), "fidelity": "coarse",
        "force": {str(k): v.tolist() for k, v in force.items()},
        "poisson": {str(k): v.tolist() for k, v in poisson.items()},
        "sampling": {f"{d},{r}": v.tolist() for (d, r), v in sampling.items()},
    }
    OUT.mkdir(exist_ok=True)
    (OUT / "sensitivity.json").write_text(json.dumps(result, indent=1))
    plot(lambdas, force, poisson, sampling)
    write_table(lambdas, force, poisson, sampling)


def rho(lambdas: np.ndarray, v: np.ndarray) -> float:
    return float(spearmanr(lambdas, v).statistic)


def plot(lambdas, force, poisson, sampling) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, figsize=(19, 4.4))
    for f, v in force.items():
        axes[0].plot(lambdas, v, "o-", ms=3, label=f"{f:g} N (rho {rho(lambdas, v):.2f})")
    axes[0].set(title="force", xlabel="lambda (mm)", ylabel="V (mean of 2 seeds)")
    for nu, v in poisson.items():
        axes[1].plot(lambdas, v, "o-", ms=3, label=f"nu {nu:g} (rho {rho(lambdas, v):.2f})")
    axes[1].set(title="Poisson ratio", xlabel="lambda (mm)")
    ratio = np.array([force[f] / force[10.0] for f in force])
    axes[2].plot(list(force), ratio, color="0.7", lw=0.8)
    axes[2].plot(list(force), ratio.mean(1), "k-o", label="mean over lambda")
    axes[2].axvspan(5, 20, color="tab:green", alpha=0.08, label="50-200% of 10 N")
    axes[2].set(title="V / V(10 N), each lambda", xlabel="force (N)")
    d_vals, r_vals = sorted({d for d, _ in sampling}), sorted({r for _, r in sampling})
    grid = np.full((len(r_vals), len(d_vals)), np.nan)
    for (d, r), v in sampling.items():
        grid[r_vals.index(r), d_vals.index(d)] = rho(lambdas, v)
    im = axes[3].imshow(grid, origin="lower", cmap="viridis", vmin=0.5, vmax=1.0, aspect="auto")
    axes[3].set_xticks(range(len(d_vals)), [f"{d:g}" for d in d_vals])
    axes[3].set_yticks(range(len(r_vals)), [f"{r:g}" for r in r_vals])
    for (i, j), value in np.ndenumerate(grid):
        if np.isfinite(value):
            axes[3].text(j, i, f"{value:.2f}", ha="center", va="center", fontsize=7, color="w")
    axes[3].set(title="Spearman(lambda, V) by sampling", xlabel="pair distance d (mm)", ylabel="disk radius r (mm)")
    fig.colorbar(im, ax=axes[3])
    for ax in axes[:3]:
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(OUT / "sensitivity.png", dpi=100)
    plt.close(fig)


def write_table(lambdas, force, poisson, sampling) -> None:
    base = force[10.0]
    lines = ["# Sensitivity of V (standard scale, coarse FEM, 2 seeds per lambda)\n",
             "Regenerate: `python studies/sensitivity.py`. Plot: [sensitivity.png](sensitivity.png).\n",
             "| setting | Spearman(lambda, V) | mean V / baseline | range over lambda |", "|---|---|---|---|"]
    rows = [(f"force {f:g} N", v) for f, v in force.items()] + [(f"nu {nu:g}", v) for nu, v in poisson.items()]
    rows += [(f"d = {d:g} mm, r = {r:g} mm", v) for (d, r), v in sampling.items()]
    for name, v in rows:
        ratio = v / base
        lines.append(f"| {name} | {rho(lambdas, v):.3f} | {ratio.mean():.3f} | {ratio.min():.3f}..{ratio.max():.3f} |")
    lines.append("\nBaseline: 10 N, nu = 0.45, d = r = 0.8 mm.")
    (OUT / "sensitivity.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()

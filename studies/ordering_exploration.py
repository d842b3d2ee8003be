"""Does V grow with lambda over the standard scale? Explore the parameters the paper left open.

One factor at a time around the baseline (10 N, nu 0.45, cone base 0.9 mm, stick):
force, Poisson ratio, cone base diameter, tangential contact condition; then a wide
cone base combined with the other factors. Each setting runs
the 13 standard textures with several random realisations; the verdict is the Spearman
correlation between lambda and the per-lambda mean V. Results are appended to a JSON-lines
file as they arrive, so an interrupted run resumes where it stopped.

    python studies/ordering_exploration.py [--fidelity coarse] [--seeds 3]
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy.stats import spearmanr  # noqa: E402

from roughness.dataset.textures import STANDARD_LAMBDAS_MM, standard_texture  # noqa: E402
from roughness.simulate.config import SimConfig  # noqa: E402
from roughness.simulate.model import Simulator  # noqa: E402

OUT = Path(__file__).parent / "results"
BASELINE = {"force_n": 10.0, "poisson": 0.45, "base_diameter_mm": 0.9, "contact": "stick"}
VARIATIONS = {
    "force_n": [2.0, 5.0, 20.0],
    "poisson": [0.3, 0.49],
    "base_diameter_mm": [0.6, 1.2, 1.5, 1.8, 1.9],
    "contact": ["frictionless"],
}
# Robustness of a wider cone base (the parameter the paper leaves open) to the others.
WIDE_BASE = {**BASELINE, "base_diameter_mm": 1.5}
COMBINATIONS = [
    {**WIDE_BASE, "force_n": 5.0},
    {**WIDE_BASE, "force_n": 20.0},
    {**WIDE_BASE, "poisson": 0.49},
    {**WIDE_BASE, "contact": "frictionless"},
]


def settings() -> list[dict]:
    out = [dict(BASELINE)]
    for key, values in VARIATIONS.items():
        out += [{**BASELINE, key: v} for v in values]
    return out + COMBINATIONS


def label(s: dict) -> str:
    return f"F={s['force_n']:g}N nu={s['poisson']} base={s['base_diameter_mm']}mm {s['contact']}"


def run(fidelity: str, seeds: int, path: Path) -> list[dict]:
    done = {}
    if path.exists():
        for line in path.read_text().splitlines():
            row = json.loads(line)
            done[(row["setting"], row["lambda_mm"], row["seed"])] = row
    sims: dict[tuple, Simulator] = {}
    with path.open("a") as f:
        for s in settings():
            for lam in STANDARD_LAMBDAS_MM:
                for seed in range(seeds):
                    key = (label(s), lam, seed)
                    if key in done:
                        continue
                    cfg = SimConfig(fidelity=fidelity, force_n=s["force_n"], poisson=s["poisson"], contact=s["contact"])
                    sim = sims.setdefault((s["poisson"],), Simulator(cfg))
                    hm = standard_texture(lam, seed=seed, base_diameter_mm=s["base_diameter_mm"])
                    r = sim.run(hm, force_n=s["force_n"], contact=s["contact"], estimate_error=False)
                    row = {"setting": label(s), **s, "lambda_mm": lam, "seed": seed, "V": r.roughness,
                           "V_stderr": r.roughness_stderr, "contact_fraction": r.contact_fraction,
                           "indentation_mm": r.indentation_mm, "converged": r.converged, "rounds": r.iterations,
                           "seconds": r.seconds}
                    f.write(json.dumps(row) + "\n")
                    f.flush()
                    done[key] = row
                    print(f"{label(s)} lambda={lam} seed={seed}: V={r.roughness:.4f} ({r.seconds:.1f}s)", flush=True)
    return list(done.values())


def summarise(rows: list[dict], fidelity: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lines = [f"Standard scale ordering at {fidelity} fidelity (Spearman of lambda vs per-lambda mean V)", "",
             "| setting | Spearman | V(0.625) | V(1.0) | V(1.625) | contact fraction | indentation (mm) | not converged |",
             "|---|---|---|---|---|---|---|---|"]
    fig, ax = plt.subplots(figsize=(10, 6), constrained_layout=True)
    summary = []
    for i, s in enumerate(settings()):
        sub = [r for r in rows if r["setting"] == label(s)]
        if not sub:
            continue
        lams = sorted({r["lambda_mm"] for r in sub})
        mean = np.array([np.mean([r["V"] for r in sub if r["lambda_mm"] == lam]) for lam in lams])
        sd = np.array([np.std([r["V"] for r in sub if r["lambda_mm"] == lam]) for lam in lams])
        rho = spearmanr(lams, mean).statistic if len(lams) > 2 else float("nan")
        v = dict(zip(lams, mean))
        cf = np.mean([r["contact_fraction"] for r in sub])
        ind = np.mean([r["indentation_mm"] for r in sub])
        bad = sum(not r["converged"] for r in sub)
        lines.append(f"| {label(s)} | {rho:.3f} | {v.get(0.625, np.nan):.4f} | {v.get(1.0, np.nan):.4f} | "
                     f"{v.get(1.625, np.nan):.4f} | {100 * cf:.1f}% | {ind:.2f} | {bad}/{len(sub)} |")
        ax.errorbar(lams, mean / mean.max(), yerr=sd / mean.max(), marker="o", ms=3, capsize=2,
                    color=plt.cm.tab20(i % 20), linestyle="--" if s["contact"] == "frictionless" else "-",
                    label=f"{label(s)} (rho={rho:.2f})")
        summary.append({"setting": label(s), "spearman": rho, "lambdas": lams, "mean_V": mean.tolist()})
    ax.set(xlabel="bump spacing lambda (mm)", ylabel="V / max V", title=f"Standard scale, {fidelity} fidelity")
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.savefig(OUT / f"ordering_{fidelity}.png", dpi=110)
    (OUT / f"ordering_{fidelity}.md").write_text("\n".join(lines) + "\n")
    (OUT / f"ordering_{fidelity}.json").write_text(json.dumps(summary, indent=1))
    print("\n".join(lines))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--fidelity", default="coarse")
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    OUT.mkdir(exist_ok=True)
    rows = run(args.fidelity, args.seeds, OUT / f"ordering_{args.fidelity}.jsonl")
    summarise(rows, args.fidelity)


if __name__ == "__main__":
    main()

"""The FEM on the closest pair of each printer-aware palette, as printed (issue 40: "verified >= 2 JND apart as
printed by the spectral engine, with the FEM on the closest pair").

studies/print_palettes.py chose and verified each palette with the spectral engine. Here the two members of the
closest pair as the palette's own printer prints them are rebuilt from their recipes (the family scaled by its
height and lateral factors), printed by that profile, and solved by the FEM at the shipped model's label fidelity
(the design tools' default verifier); each V with its Monte Carlo standard error, its equivalent wavelength on the
FEM standard scale, and the pair's distance in JND with a +-2 sigma band (both members' V moved apart and together
by two standard errors).

    python studies/print_palettes_fem.py          # reads results/print_palettes.json; minutes per FEM solve

Writes results/print_palettes_fem.json and .md.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

RESULTS = Path(__file__).parent / "results"
PROFILES = ("fdm-0.4-0.2", "sla1s-47um")
LOG_JND = math.log(1.19)


def closest_pair(palette: dict, profile: str) -> tuple[dict, dict]:
    """The two members whose prints by ``profile`` are closest on the spectral scale."""
    members = sorted(palette["members"], key=lambda m: m["printed"][profile]["lambda_mm"])
    gaps = [math.log(b["printed"][profile]["lambda_mm"] / a["printed"][profile]["lambda_mm"]) for a, b in
            zip(members, members[1:])]
    i = gaps.index(min(gaps))
    return members[i], members[i + 1]


def rebuild(recipe: dict):
    """A printer-aware palette member's digital heightmap from its recipe."""
    from roughness.dataset.catalogue import make_texture
    from roughness.design.palette import variant

    return variant(make_texture(recipe["name"], seed=recipe["seed"])[0], recipe["height_factor"],
                   recipe["lateral_factor"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fidelity", help="FEM fidelity (default: the shipped model's label fidelity)")
    args = parser.parse_args()
    from roughness.design.evaluation import Evaluator
    from roughness.surface.printing import PROFILES as SHIPPED

    spectral = json.loads((RESULTS / "print_palettes.json").read_text())
    rows = {}
    for profile in PROFILES:
        palette = spectral[f"for {profile}"]
        pair = closest_pair(palette, profile)
        evaluator = Evaluator(fidelity=args.fidelity, printer=SHIPPED[profile])
        solved = []
        for member in pair:
            t = time.perf_counter()
            fem = evaluator.verify(rebuild(member["recipe"]))
            solved.append({"name": member["name"], "V": fem.roughness, "V_stderr": fem.roughness_stderr,
                           "lambda_mm": fem.equivalent_lambda_mm, "on_scale": fem.on_scale,
                           "spectral_lambda_mm": member["printed"][profile]["lambda_mm"],
                           "seconds": time.perf_counter() - t})
            print(f"{profile} {member['name']}: V {fem.roughness:.4f} ± {fem.roughness_stderr:.4f}, lambda "
                  f"{fem.equivalent_lambda_mm:.3f} mm ({time.perf_counter() - t:.0f} s)", flush=True)
        lo, hi = sorted(solved, key=lambda s: s["V"])

        def gap(v_lo: float, v_hi: float) -> float:
            return math.log(evaluator.lambda_of(v_hi) / evaluator.lambda_of(v_lo)) / LOG_JND

        spectral_gap = math.log(hi["spectral_lambda_mm"] / lo["spectral_lambda_mm"]) / LOG_JND
        rows[profile] = {"fidelity": evaluator.verifier, "members": solved, "fem_jnd": gap(lo["V"], hi["V"]),
                         "fem_jnd_2sigma": [gap(lo["V"] + 2 * lo["V_stderr"], hi["V"] - 2 * hi["V_stderr"]),
                                            gap(lo["V"] - 2 * lo["V_stderr"], hi["V"] + 2 * hi["V_stderr"])],
                         "spectral_jnd": spectral_gap}
    (RESULTS / "print_palettes_fem.json").write_text(json.dumps(rows, indent=1) + "\n")
    lines = ["# The FEM on each printer-aware palette's closest pair, as printed", "",
             "Regenerate: `python studies/print_palettes_fem.py` (the palettes of `results/print_palettes.md`).", "",
             "| printer | verifier | pair | V as printed (± s.e.) | lambda mm | FEM JND apart (±2σ) | spectral JND |",
             "|---|---|---|---|---|---|---|"]
    for profile, row in rows.items():
        a, b = row["members"]
        lo2, hi2 = row["fem_jnd_2sigma"]
        lines.append(f"| {profile} | {row['fidelity']} | {a['name']}, {b['name']} | {a['V']:.4f} ± "
                     f"{a['V_stderr']:.4f}, {b['V']:.4f} ± {b['V_stderr']:.4f} | {a['lambda_mm']:.3f}, "
                     f"{b['lambda_mm']:.3f} | {row['fem_jnd']:.2f} ({lo2:.2f}..{hi2:.2f}) | {row['spectral_jnd']:.2f} |")
    (RESULTS / "print_palettes_fem.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

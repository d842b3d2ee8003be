"""How the slicers' fuzzy skin feels on a printed wall (issue 44): Classic over thickness x point distance at
fdm-0.4-0.2, each of OrcaSlicer's noise types at its defaults, and the plain wall, by the spectral engine.

Each setting is printed as a 12 mm periodic wall tile (roughness.surface.fuzzy_skin.fuzzy_wall, 0.05 mm pixels)
with seeds 0-2 (the slicers draw new random numbers at every slice: the spread over seeds is how much one print
differs from the next) and judged flat by the spectral engine (roughness.fuzzy_feel.fuzzy_skin_feel). V is the
mean over seeds with the largest of the seeds' Monte Carlo error and their standard deviation; lambda is the
mean V's equivalent wavelength on the spectral standard scale; JND is against Classic at OrcaSlicer's and
PrusaSlicer's default (0.3 mm thickness, 0.8 mm point distance).

    python studies/fuzzy_skin.py            # about two minutes on one shared core
    python studies/fuzzy_skin.py --render   # table and plot again from results/fuzzy_skin.json

Writes results/fuzzy_skin.json, .md and .png.
"""
from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

OUT = Path(__file__).parent / "results" / "fuzzy_skin"
PRINTER = "fdm-0.4-0.2"
SEEDS = (0, 1, 2)
THICKNESSES_MM = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8)
POINT_DISTANCES_MM = (0.2, 0.3, 0.4, 0.6, 0.8, 1.0, 1.2, 1.5)
NOISE_TYPES = ("classic", "perlin", "billow", "ridgedmulti", "voronoi")


def judged(skin) -> dict:
    """V over the seeds, its uncertainty and its place on the spectral standard scale."""
    from roughness.fuzzy_feel import fuzzy_skin_feel

    feel = fuzzy_skin_feel(skin, PRINTER, "spectral", SEEDS[0], draws=len(SEEDS))
    feels = feel.predictions
    v = np.array([p.roughness for p in feels])
    return {"v_seeds": v.tolist(), "v": float(v.mean()), "v_seed_std": float(v.std(ddof=1)),
            "v_mc_stderr": max(p.roughness_stderr for p in feels)}


def path_only(point_distance_mm: float) -> float:
    """Mean V over the seeds of Classic 0.3 mm walls without the bead: each layer's path alone (the ablation)."""
    from roughness.prediction import PredictOptions, predict
    from roughness.surface.fuzzy_skin import FuzzySkin, fuzzy_wall
    from roughness.surface.printing import PROFILES

    walls = {str(s): fuzzy_wall(FuzzySkin(0.3, point_distance_mm), PROFILES[PRINTER], seed=s, bead=False).heightmap
             for s in SEEDS}
    return float(np.mean([p.roughness for p in predict(walls, engine="spectral", options=PredictOptions(tile=True))]))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--render", action="store_true", help="only the table and plot, from the JSON")
    args = parser.parse_args(argv)
    if not args.render:
        from dataclasses import asdict, replace

        from roughness.surface.fuzzy_skin import FuzzySkin

        start = time.monotonic()
        classic = []
        for t in THICKNESSES_MM:
            for d in POINT_DISTANCES_MM:
                classic.append({"thickness_mm": t, "point_distance_mm": d, **judged(FuzzySkin(t, d))})
                print(f"classic {t:g} x {d:g}: V {classic[-1]['v']:.4f}", flush=True)
        noises = [{"noise_type": kind, **judged(replace(FuzzySkin(), fuzzy_skin_noise_type=kind))}
                  for kind in NOISE_TYPES]
        plain = judged(FuzzySkin(0.0))
        bead = [{"point_distance_mm": d, "printed": judged(FuzzySkin(0.3, d))["v"], "path_only": path_only(d)}
                for d in POINT_DISTANCES_MM]
        result = {"printer": PRINTER, "seeds": list(SEEDS), "engine": "spectral", "tile_mm": 12.0, "pixel_mm": 0.05,
                  "defaults": asdict(FuzzySkin()), "classic": classic,
                  "noise_types": noises, "plain_wall": plain, "bead_ablation": bead, "seconds": time.monotonic() - start}
        OUT.with_suffix(".json").write_text(json.dumps(result, indent=1) + "\n")
    result = json.loads(OUT.with_suffix(".json").read_text())
    render(result)
    return 0


def _placed(v: float, scale, reference_lambda: float | None) -> tuple[str, str]:
    from roughness.perceptual_scale import jnd

    where = scale.place(v)
    if where.equivalent_lambda_mm is None:
        return "below the scale", ""
    lam = f"{where.equivalent_lambda_mm:.3f}" + ("" if where.on_scale else " (extrap.)")
    return lam, "" if reference_lambda is None else f"{jnd(where.equivalent_lambda_mm, reference_lambda):+.1f}"


def render(result: dict) -> None:
    from roughness.perceptual_scale import load_scale

    scale = load_scale("spectral")
    default = next(r for r in result["classic"] if r["thickness_mm"] == 0.3 and r["point_distance_mm"] == 0.8)
    ref = scale.place(default["v"]).equivalent_lambda_mm

    def v_cell(r: dict) -> str:
        return f"{r['v']:.4f} ± {max(r['v_seed_std'], r['v_mc_stderr']):.4f}"

    lines = ["# Fuzzy skin on a printed wall (issue 44)", "",
             f"Written by `studies/fuzzy_skin.py` ({result['seconds']:.0f} s). Printer {result['printer']} (0.2 mm "
             f"layers, 0.45 mm lines); {result['tile_mm']:g} mm periodic wall tiles on {result['pixel_mm']:g} mm "
             f"pixels, seeds {', '.join(map(str, result['seeds']))}, judged flat by the {result['engine']} engine. "
             "V: mean over seeds ± the larger of their standard deviation and the Monte Carlo error; lambda: the "
             "mean's equivalent wavelength (mm) on the spectral standard scale; JND: against Classic at the "
             "slicers' default (0.3 mm x 0.8 mm).", "",
             "## Classic: thickness x point distance", "",
             "| thickness (mm) | point distance (mm) | V | lambda (mm) | JND vs default |", "|---|---|---|---|---|"]
    for r in result["classic"]:
        lam, jnd = _placed(r["v"], scale, ref)
        lines.append(f"| {r['thickness_mm']:g} | {r['point_distance_mm']:g} | {v_cell(r)} | {lam} | {jnd} |")
    d = result["defaults"]
    lines += ["", f"## OrcaSlicer's noise types at its defaults (thickness {d['fuzzy_skin_thickness']:g} mm, point "
              f"distance {d['fuzzy_skin_point_distance']:g} mm, feature size {d['fuzzy_skin_scale']:g} mm, "
              f"{d['fuzzy_skin_octaves']} octaves, persistence {d['fuzzy_skin_persistence']:g})", "",
              "| noise type | V | lambda (mm) | JND vs Classic default |", "|---|---|---|---|"]
    for r in result["noise_types"]:
        lam, jnd = _placed(r["v"], scale, ref)
        lines.append(f"| {r['noise_type']} | {v_cell(r)} | {lam} | {jnd} |")
    plain = result["plain_wall"]
    lam, _ = _placed(plain["v"], scale, None)
    lines.append(f"| plain wall (no fuzzy skin) | {plain['v']:.2e} | {lam} (floor V {scale.place(plain['v']).floor:.4f})"
                 " | |")
    lines += ["", "## What the bead changes (Classic, thickness 0.3 mm)", "",
              "Each layer's path alone over the layer's rows (`fuzzy_wall(..., bead=False)`: no bead rounding, no bead "
              "profile between layers) against the printed wall; mean V over the same seeds.", "",
              "| point distance (mm) | V printed | V path only | printed / path only |", "|---|---|---|---|"]
    lines += [f"| {r['point_distance_mm']:g} | {r['printed']:.4f} | {r['path_only']:.4f} | "
              f"{r['printed'] / r['path_only']:.3f} |" for r in result["bead_ablation"]]
    OUT.with_suffix(".md").write_text("\n".join(lines) + "\n")
    plot(result, scale)


def plot(result: dict, scale) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5), gridspec_kw={"width_ratios": [3, 2]})
    for t in THICKNESSES_MM:
        rows = [r for r in result["classic"] if r["thickness_mm"] == t]
        left.errorbar([r["point_distance_mm"] for r in rows], [r["v"] for r in rows],
                      yerr=[max(r["v_seed_std"], r["v_mc_stderr"]) for r in rows], marker="o", ms=3, capsize=2,
                      label=f"{t:g} mm")
    left.axvline(0.45, color="grey", ls=":", lw=1)
    left.text(0.46, left.get_ylim()[1] * 0.95, "line width", color="grey", fontsize=8, va="top")
    left.set(xlabel="fuzzy_skin_point_distance (mm)", ylabel="V (spectral)",
             title=f"Classic fuzzy skin, {result['printer']}")
    left.legend(title="thickness", fontsize=8)
    names = [r["noise_type"] for r in result["noise_types"]] + ["plain"]
    values = [r["v"] for r in result["noise_types"]] + [result["plain_wall"]["v"]]
    errors = [max(r["v_seed_std"], r["v_mc_stderr"]) for r in result["noise_types"]] + [0.0]
    right.bar(names, values, yerr=errors, capsize=3, color="tab:blue")
    right.set(ylabel="V (spectral)", title="OrcaSlicer noise types, defaults")
    right.tick_params(axis="x", rotation=30)
    fig.tight_layout()
    fig.savefig(OUT.with_suffix(".png"), dpi=120)


if __name__ == "__main__":
    raise SystemExit(main())

"""The spectral engine against the FEM reference: the validation set and the convergence panel.

References: the 160 validation textures with their FEM labels converged to 1% (a build of
``recipes/validation.json``, see ``recipes/build-v2.sh``), and the 24-texture convergence panel's
P1 h = 0.1 mm results (``studies/results/convergence_panel.jsonl``). For every texture the spectral
engine runs once per variant of what the infinite layer stands for (``VARIANTS``), so the choice is
measured, not assumed. Writes
results/spectral_validation.{jsonl,md} and results/spectral_validation.png.

    roughness dataset build --recipe recipes/validation.json --n 160 --fidelity converged --tolerance 0.01 \\
        --labels recipes/labels/validation-converged.labels.jsonl.gz --workers 2 --out validation-converged.h5
    python studies/spectral_validation.py --labels validation-converged.h5
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).parent
OUT = HERE / "results" / "spectral_validation"
PANEL = HERE / "results" / "convergence_panel.jsonl"
# block: the FEM block's centre strain and pressure (the default); block_mean_pressure: its strain at the
# footprint's mean pressure; layer: the infinite layer's own uniaxial state at the mean pressure
VARIANTS = {"block": {}, "block_mean_pressure": {"pressure": "mean"}, "layer": {"flat_state": "layer"}}
WORST = 10


def _spectral(heightmap, variant: str) -> dict:
    from roughness.simulate.spectral.engine import SpectralSimulator

    result = SpectralSimulator(**VARIANTS[variant]).run(heightmap)
    return {"V": result.roughness, "contact_fraction": result.contact_fraction, "converged": result.converged,
            "iterations": result.iterations, "seconds": result.seconds}


def _stored(jsonl: Path) -> dict[tuple[str, str], dict]:
    """Rows already computed, by (set, id): the study resumes after an interruption."""
    rows = [json.loads(line) for line in jsonl.read_text().splitlines()] if jsonl.exists() else []
    return {(r["set"], r["id"]): r for r in rows}


def _keep(jsonl: Path, row: dict) -> dict:
    with jsonl.open("a") as f:
        f.write(json.dumps(row, sort_keys=True) + "\n")
    return row


def validation_rows(labels: Path, jsonl: Path) -> list[dict]:
    from roughness.dataset.reader import Dataset

    rows, done = [], _stored(jsonl)
    with Dataset(labels) as data:
        for sample in data.iter_samples():
            if ("validation", sample.id) in done:
                rows.append(done["validation", sample.id])
                continue
            row = {"set": "validation", "id": sample.id, "family": sample.texture_record.get("family", "?"),
                   "V_ref": sample.values["V"], "contact_fraction_ref": sample.values["contact_fraction"]}
            for variant in VARIANTS:
                row[variant] = _spectral(sample.heightmap, variant)
            rows.append(_keep(jsonl, row))
            print(f"{len(rows):4d} {row['family']:10s} ref {row['V_ref']:.4f} block {row['block']['V']:.4f} "
                  f"layer {row['layer']['V']:.4f} cf {row['contact_fraction_ref']:.3f} {row['block']['contact_fraction']:.3f}", file=sys.stderr, flush=True)
    return rows


def panel_rows(jsonl: Path) -> list[dict]:
    sys.path.insert(0, str(HERE))
    from convergence_panel import REFERENCE, _rows, panel

    textures = panel()
    reference = {r["texture"]: r for r in _rows(PANEL) if (r["element"], r["h_contact_mm"]) == REFERENCE}
    rows, done = [], _stored(jsonl)
    for name, make in textures.items():
        if name not in reference:
            continue
        if ("panel", name) in done:
            rows.append(done["panel", name])
            continue
        row = {"set": "panel", "id": name, "family": name.split("-")[0], "V_ref": reference[name]["roughness"],
               "contact_fraction_ref": reference[name].get("contact_fraction")}
        for variant in VARIANTS:
            row[variant] = _spectral(make(), variant)
        rows.append(_keep(jsonl, row))
    return rows


def _relative(value: float, reference: float) -> float:
    """value / reference - 1; 0 where both are 0 (a flat texture), infinite where only the reference is."""
    if value == reference:
        return 0.0
    return value / reference - 1 if reference else float("inf")


def _errors(rows: list[dict], variant: str) -> np.ndarray:
    return np.array([_relative(r[variant]["V"], r["V_ref"]) for r in rows])


def _stats(rows: list[dict], variant: str) -> dict:
    from scipy.stats import spearmanr

    err = _errors(rows, variant)
    ref = [r["V_ref"] for r in rows]
    got = [r[variant]["V"] for r in rows]
    return {"n": len(rows), "median_abs": float(np.median(np.abs(err))), "p95_abs": float(np.percentile(np.abs(err), 95)),
            "median_signed": float(np.median(err)), "spearman": float(spearmanr(ref, got).statistic),
            "seconds_median": float(np.median([r[variant]["seconds"] for r in rows]))}


def _pct(value: float | None) -> str:
    return "–" if value is None else f"{100 * value:.1f}%"


def write_report(rows: list[dict], out: Path) -> str:
    lines = ["# The spectral engine against the FEM reference", "",
             "Relative error of V = spectral / reference - 1; reference: FEM converged to 1% (validation set) or "
             "P1 at h = 0.1 mm (convergence panel). Regenerate: `python studies/spectral_validation.py --labels "
             "validation-converged.h5`.", ""]
    for name in ("validation", "panel"):
        subset = [r for r in rows if r["set"] == name]
        if not subset:
            continue
        lines += [f"## {name} ({len(subset)} textures)", "",
                  "| variant | median abs | p95 abs | median signed | Spearman | median s |", "|---|---|---|---|---|---|"]
        for variant in VARIANTS:
            s = _stats(subset, variant)
            lines.append(f"| {variant} | {100 * s['median_abs']:.1f}% | {100 * s['p95_abs']:.1f}% | "
                         f"{100 * s['median_signed']:+.1f}% | {s['spearman']:.4f} | {s['seconds_median']:.3f} |")
        lines += ["", "Per family (variant block):", "",
                  "| family | n | median abs | p95 abs | median signed |", "|---|---|---|---|---|"]
        for family in sorted({r["family"] for r in subset}):
            group = [r for r in subset if r["family"] == family]
            err = _errors(group, "block")
            lines.append(f"| {family} | {len(group)} | {100 * np.median(np.abs(err)):.1f}% | "
                         f"{100 * np.percentile(np.abs(err), 95):.1f}% | {100 * np.median(err):+.1f}% |")
        lines += ["", f"Worst {WORST} (variant block):", "",
                  "| texture | family | V ref | V spectral | error | contact ref | contact spectral |",
                  "|---|---|---|---|---|---|---|"]
        for r in sorted(subset, key=lambda r: -abs(_relative(r["block"]["V"], r["V_ref"])))[:WORST]:
            lines.append(f"| {r['id'][:16]} | {r['family']} | {r['V_ref']:.4f} | {r['block']['V']:.4f} | "
                         f"{100 * _relative(r['block']['V'], r['V_ref']):+.1f}% | {_pct(r['contact_fraction_ref'])} | "
                         f"{100 * r['block']['contact_fraction']:.1f}% |")
        partial = [r for r in subset if (r["contact_fraction_ref"] or 1.0) < 0.98]
        if partial:
            lines += ["", f"On the {len(partial)} textures below 98% contact in the FEM (contact fraction: spectral "
                      "minus FEM, in percentage points):", "",
                      "| variant | median | largest abs | within 2 points | V median abs | V p95 abs |",
                      "|---|---|---|---|---|---|"]
            for variant in VARIANTS:
                gap = np.array([r[variant]["contact_fraction"] - r["contact_fraction_ref"] for r in partial])
                err = np.abs(_errors(partial, variant))
                lines.append(f"| {variant} | {100 * np.median(gap):+.1f} | {100 * np.abs(gap).max():.1f} | "
                             f"{100 * np.mean(np.abs(gap) <= 0.02):.0f}% | {100 * np.median(err):.1f}% | "
                             f"{100 * np.percentile(err, 95):.1f}% |")
        lines.append("")
    text = "\n".join(lines)
    out.with_suffix(".md").write_text(text)
    return text


def plot(rows: list[dict], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 5))
    for name, marker in (("validation", "o"), ("panel", "s")):
        subset = [r for r in rows if r["set"] == name]
        ax.scatter([r["V_ref"] for r in subset], [r["block"]["V"] for r in subset], s=14, marker=marker, label=name)
    values = [r["V_ref"] for r in rows]
    line = [min(values), max(values)]
    ax.plot(line, line, "k:", lw=1)
    ax.set(xscale="log", yscale="log", xlabel="V, FEM reference", ylabel="V, spectral")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out.with_suffix(".png"), dpi=120)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--labels", type=Path, help="validation set with converged FEM labels (.h5)")
    parser.add_argument("--report-only", action="store_true", help="rewrite the report from the stored JSONL")
    parser.add_argument("--fresh", action="store_true", help="recompute every row (after a change to the engine)")
    args = parser.parse_args(argv)
    jsonl = OUT.with_suffix(".jsonl")
    if args.fresh:
        jsonl.unlink(missing_ok=True)
    if args.report_only:
        rows = [json.loads(line) for line in jsonl.read_text().splitlines()]
    else:
        rows = (validation_rows(args.labels, jsonl) if args.labels else []) + panel_rows(jsonl)
    print(write_report(rows, OUT))
    plot(rows, OUT)
    return 0


if __name__ == "__main__":
    sys.exit(main())

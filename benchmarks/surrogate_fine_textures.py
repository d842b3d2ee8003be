"""The shipped surrogate and the previous one on new fine, low-relief textures, against the spectral engine.

Surrogate v3's issue (29) found v2's tail on fine, low-relief textures (features of 0.1-0.5 mm, relief below
0.15 mm), where the `fine` FEM labels v2 imitates are themselves unconverged. The spectral engine resolves every
pixel (against FEM converged to 1%: median 1.9%, p95 7.0%, studies/results/spectral_validation.md), so it is the
reference here, where it holds (contact fraction >= ``SPECTRAL_MIN_CONTACT``; the others are counted, not scored).

Textures are drawn from the v3 recipe (recipes/training-v3.json) from sample ``--start`` on (default 100,000: past
the 100,000 samples v3 was trained on; none was seen by v2 either) until ``--per-group`` of each group are found:
"fine, low relief" (feature size 2 pi std / rms slope <= 0.5 mm and relief p99.5 - p0.5 <= 0.15 mm over the
footprint, at the map's own pixels) and "other". The families held out of either model's training are reported apart as well.

    python benchmarks/surrogate_fine_textures.py [--per-group 60] [--model models/roughness-cnn.onnx]
        [--baseline models/roughness-cnn-v2.onnx]
    # writes benchmarks/results/surrogate_fine_textures.{md,json}
"""
from __future__ import annotations

import argparse
import json
import os
from dataclasses import dataclass
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUT = Path(__file__).parent / "results"
MODELS = ROOT / "models"
FINE_FEATURE_MM = 0.5  # at most this feature size ...
LOW_RELIEF_MM = 0.15  # ... and at most this relief: the "fine, low relief" group
V_FLOOR = 0.001  # relative errors against max(V_ref, V_FLOOR), as the trade report takes them


@dataclass(frozen=True)
class Row:
    index: int
    family: str
    group: str  # "fine, low relief" or "other"
    feature_mm: float
    relief_mm: float
    reference: float  # the spectral engine's V
    contact_fraction: float
    predicted: dict[str, float]  # model file name -> V


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-group", type=int, default=60, help="textures per group (default: 60)")
    parser.add_argument("--start", type=int, default=100_000,
                        help="first recipe sample to draw from (default: 100000, past the v3 training set)")
    parser.add_argument("--model", default=str(MODELS / "roughness-cnn.onnx"), help="the model (default: shipped)")
    parser.add_argument("--baseline", default=str(MODELS / "roughness-cnn-v2.onnx"),
                        help="the model to compare with (default: the v2 model)")
    return parser.parse_args()


def group_of(hm) -> tuple[str, float, float]:
    """The texture's group, feature size (mm) and relief (mm) over the footprint at the map's own pixels."""
    from roughness.surrogate.patch import batch_descriptors, footprint_patch

    relief, feature, _, _ = batch_descriptors(footprint_patch(hm, pixel_mm=hm.pixel_mm)[None], hm.pixel_mm)[0]
    fine = feature <= FINE_FEATURE_MM and relief <= LOW_RELIEF_MM
    return ("fine, low relief" if fine else "other"), float(feature), float(relief)


def draw(per_group: int, start: int, models: list) -> list[Row]:
    """Recipe textures from ``start`` on until each group has ``per_group``, with every model's answer."""
    from roughness.dataset.recipe import load_recipe, realise, sample_record
    from roughness.engines import SpectralEngine

    recipe = load_recipe(ROOT / "recipes" / "training-v3.json")
    wanted = {"fine, low relief": per_group, "other": per_group}
    spectral = SpectralEngine.of(models[0].meta.simulation)  # the physics the first model was trained for
    rows = []
    for index in range(start, start + 1_000_000):
        record = sample_record(recipe, index)
        hm = realise(record)
        group, feature, relief = group_of(hm)
        if wanted[group] == 0:
            continue
        wanted[group] -= 1
        result = spectral.simulate(hm)
        predicted = {m.path.name: float(m.run(m.patch(hm)[None])[0][0]) for m in models}
        rows.append(Row(index, record["family"], group, feature, relief, result.roughness, result.contact_fraction,
                        predicted))
        print(f"{index:7d} {record['family']:10s} {group:16s} feature {feature:.3f} relief {relief:.3f} "
              f"spectral {result.roughness:.4f} " + " ".join(f"{k} {v:.4f}" for k, v in predicted.items()), flush=True)
        if not any(wanted.values()):
            return rows
    return rows


def scores(rows: list[Row], name: str) -> dict:
    """Median, p95 and worst relative error and Spearman of model ``name`` against the spectral engine."""
    from scipy.stats import spearmanr

    if len(rows) < 3:
        return {"n": len(rows)}
    ref = np.array([r.reference for r in rows])
    pred = np.array([r.predicted[name] for r in rows])
    rel = np.abs(pred - ref) / np.maximum(ref, V_FLOOR)
    return {"n": len(rows), "median_rel_err": float(np.median(rel)), "p95_rel_err": float(np.percentile(rel, 95)),
            "worst_rel_err": float(rel.max()), "spearman": float(spearmanr(ref, pred).statistic),
            "median_ratio": float(np.median(pred / np.maximum(ref, 1e-12)))}


def main() -> None:
    from roughness.prediction import SPECTRAL_MIN_CONTACT
    from roughness.surrogate.predictor import SurrogateModel

    args = parse_args()
    models = [SurrogateModel(args.model, threads=1), SurrogateModel(args.baseline, threads=1)]
    rows = draw(args.per_group, args.start, models)
    holds = [r for r in rows if r.contact_fraction >= SPECTRAL_MIN_CONTACT]
    names = [m.path.name for m in models]
    held_out = {name: set(filter(None, (m.meta.holdout_family or "").split(","))) for name, m in zip(names, models)}
    parts = {"fine, low relief": [r for r in holds if r.group == "fine, low relief"],
             "other": [r for r in holds if r.group == "other"],
             **{f"{f} (held out of {' and '.join(n for n in names if f in held_out[n])})":
                [r for r in holds if r.family == f] for f in sorted(set.union(*held_out.values()))},
             "all": holds}
    table = {part: {name: scores(part_rows, name) for name in names} for part, part_rows in parts.items()}
    OUT.mkdir(exist_ok=True)
    (OUT / "surrogate_fine_textures.json").write_text(json.dumps(
        {"models": names, "start": args.start, "per_group": args.per_group, "scores": table,
         "partial_contact_not_scored": len(rows) - len(holds), "rows": [r.__dict__ for r in rows]}, indent=1) + "\n")

    def cell(s: dict) -> str:
        if "median_rel_err" not in s:
            return "-"
        return (f"{100 * s['median_rel_err']:.1f}% / {100 * s['p95_rel_err']:.1f}% / {100 * s['worst_rel_err']:.0f}% "
                f"/ {s['spearman']:.3f}")

    lines = [f"# {names[0]} and {names[1]} on new fine, low-relief textures (reference: the spectral engine)", "",
             f"Textures of recipes/training-v3.json from sample {args.start:,} on (seen by neither model), "
             f"{args.per_group} per group; \"fine, low relief\": feature size <= {FINE_FEATURE_MM} mm and relief <= "
             f"{LOW_RELIEF_MM} mm over the footprint. Scored where the spectral engine holds (contact fraction >= "
             f"{SPECTRAL_MIN_CONTACT}); {len(rows) - len(holds)} of {len(rows)} were in partial contact and are not "
             "scored. Relative errors against max(V, 0.001). Regenerate: "
             "`python benchmarks/surrogate_fine_textures.py`.", "",
             "Each cell: median / p95 / worst relative error / Spearman.", "",
             "| textures | n | " + " | ".join(names) + " |", "|---|---|" + "---|" * len(names),
             *(f"| {part} | {len(parts[part])} | " + " | ".join(cell(table[part][n]) for n in names) + " |"
               for part in parts)]
    (OUT / "surrogate_fine_textures.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

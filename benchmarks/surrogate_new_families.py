"""How the shipped surrogate does on new textures of the engineered and composite families.

Draws ``--per-family`` textures of each family of dataset/engineered.py from the training-v2 recipe
(recipes/training-v2.json, with its perturbations), from sample ``--start`` on (default 6000: past the
6,000 samples the v2 model was trained on, so none of them was seen; ``waffle`` was held out
entirely), runs the FEM at the model's label fidelity and
the surrogate on each, and reports per family the median and worst relative error, the Spearman
correlation and how many inputs the surrogate flags as out of domain.

    python benchmarks/surrogate_new_families.py [--per-family 8] [--model models/roughness-cnn.onnx]
        [--cache FOLDER]
    # writes benchmarks/results/surrogate_new_families.{md,json}
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUT = Path(__file__).parent / "results"


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-family", type=int, default=8, help="textures per family (default: 8)")
    parser.add_argument("--start", type=int, default=6000,
                        help="first recipe sample to draw from (default: 6000, past the v2 training set)")
    parser.add_argument("--model", default=str(ROOT / "models" / "roughness-cnn.onnx"),
                        help="ONNX model (default: models/roughness-cnn.onnx)")
    parser.add_argument("--cache", type=Path,
                        help="keep the FEM results in this folder, keyed by texture content and FEM configuration, "
                             "so that scoring another model reruns only the surrogate")
    return parser.parse_args()


def main() -> None:
    from scipy.stats import spearmanr

    from roughness.dataset.engineered import FAMILIES
    from roughness.dataset.recipe import load_recipe, realise, sample_record
    from roughness.engines import FemEngine
    from roughness.perception.values import fem_value
    from roughness.result_cache import ResultCache
    from roughness.surrogate.predictor import SurrogateModel

    args = parse_args()
    model = SurrogateModel(args.model)
    fem = FemEngine.of(model.fidelity, model.meta.simulation)
    cache = ResultCache(args.cache, {fem.spec: fem.identity}) if args.cache else None
    recipe = load_recipe(ROOT / "recipes" / "training-v2.json")
    wanted = dict.fromkeys(FAMILIES, args.per_family)
    rows = []
    for index in range(args.start, args.start + 100_000):
        record = sample_record(recipe, index)
        if wanted.get(record["family"], 0) == 0:
            continue
        wanted[record["family"]] -= 1
        hm = realise(record)
        v_fem = fem_value(str(index), hm, cache, fem)[0].roughness if cache else fem.simulate(hm).roughness
        [v], [why] = model.run(model.patch(hm)[None])
        rows.append({"index": index, "family": record["family"], "V_fem": v_fem, "V_surrogate": float(v),
                     "out_of_domain": bool(why), "params": record["params"]})
        print(f"{index:6d} {record['family']:10s} FEM {v_fem:.4f} surrogate {v:.4f}"
              f"{' (out of domain)' if why else ''}", flush=True)
        if not any(wanted.values()):
            break
    table = []
    for family in FAMILIES:
        part = [r for r in rows if r["family"] == family]
        fem_v = np.array([r["V_fem"] for r in part])
        sur_v = np.array([r["V_surrogate"] for r in part])
        rel = np.abs(sur_v - fem_v) / np.maximum(fem_v, 1e-3)
        table.append((family, len(part), float(spearmanr(fem_v, sur_v)[0]), float(np.median(sur_v / np.maximum(
            fem_v, 1e-12))), float(np.median(rel)), float(rel.max()), sum(r["out_of_domain"] for r in part)))
    OUT.mkdir(exist_ok=True)
    (OUT / "surrogate_new_families.json").write_text(json.dumps({"model": Path(args.model).name,
                                                                 "fidelity": model.fidelity, "samples": rows},
                                                                indent=1))
    lines = ["| family | n | Spearman | median surrogate/FEM | median rel. error | worst rel. error | flagged |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {f} | {n} | {rho:.2f} | {ratio:.2f} | {100 * med:.0f}% | {100 * worst:.0f}% | {flag} |"
              for f, n, rho, ratio, med, worst, flag in table]
    (OUT / "surrogate_new_families.md").write_text(
        f"# {Path(args.model).name} on the engineered and composite families (FEM {model.fidelity})\n\n"
        f"{args.per_family} textures per family from recipes/training-v2.json, samples {args.start} on; "
        "relative errors against "
        "max(V_fem, 0.001). Regenerate: `python benchmarks/surrogate_new_families.py`.\n\n" + "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

"""Surrogate v3 (issue 29): every target in one report, the previous model's numbers beside it, by one command.

    python benchmarks/surrogate_report.py --labels validation-converged.h5 [--model models/roughness-cnn.onnx]
        [--baseline models/roughness-cnn-v2.onnx]
    # writes benchmarks/results/surrogate_report.{md,json} and surrogate_routing.png; also regenerates trade/,
    # surrogate_latency.* and surrogate_map.* (skip those two timing runs with --no-timing: their committed results
    # are read)

``--labels``: the validation recipe built at the reference fidelity (FEM converged to 1%):
`roughness dataset build --recipe recipes/validation.json --n 160 --fidelity converged --tolerance 0.01
--out validation-converged.h5`. Sections:

- accuracy against that reference (median and p95 relative error, Spearman), with the other engines
  (benchmarks/trade_report.py, whose cached results are reused), for the model and the baseline;
- the families held out of training one by one: on the validation set, and from the ensemble's own export (its
  metadata: scores on the held-out rows of the training data, labelled at the fidelity it imitates);
- the uncertainty on the validation set: the share of references inside the +-2 sigma interval, and what
  ``--engine auto`` with its default ``--max-std`` sends to a physics engine and catches (predictions off by more
  than 15%); then auto itself run on every texture (``roughness.predict``): which engine answered (the spectral
  engine where it holds, else the FEM) and how far its answers are from the reference;
- the int8 graph against the fp32 one on the validation textures;
- latency (batch 1, a fresh process) and map throughput (benchmarks/surrogate_latency.py and
  surrogate_map.py), training cost in core-hours with the break-even against each engine, and the textures the
  surrogate gets most wrong.
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results"
LARGE_ERROR = 0.15  # issues 12 and 29: auto must catch predictions off by more than this
V_FLOOR = 0.001  # relative errors are taken against max(V_ref, V_FLOOR), as the trade report does
MODELS = ROOT / "models"
ROUTING_THRESHOLDS = (0.05, 0.08, 0.10, 0.12, 0.15, 0.20, 0.25, 0.30, 0.40)  # relative spreads tried as --max-std


@dataclass(frozen=True)
class Target:
    what: str
    goal: str
    reached: str
    met: bool | None  # None: not measured here
    baseline: str = "-"  # the same measure of the baseline model ("-": not measured for it)


@dataclass(frozen=True)
class Measures:
    """What the report measures of one model on the validation set."""

    predictions: dict
    overall: dict  # accuracy of every texture
    split: dict[str, dict]  # accuracy of the trained families, then of each held-out family
    uncertainty: dict


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--labels", required=True, help="the validation set labelled by the reference FEM (.h5)")
    parser.add_argument("--model", default=str(MODELS / "roughness-cnn.onnx"),
                        help="the ensemble to report on (default: the shipped model)")
    parser.add_argument("--int8", help="its int8 graph (default: the model's name with -int8)")
    parser.add_argument("--baseline", default=str(MODELS / "roughness-cnn-v2.onnx"),
                        help="the previous ensemble, measured beside it (default: the v2 model)")
    parser.add_argument("--no-timing", action="store_true",
                        help="read the committed latency and map results instead of measuring them again")
    return parser.parse_args()


def run(script: str, *args: str) -> None:
    """Run one of the benchmarks beside this one in a fresh process (its own timings, its own outputs)."""
    subprocess.run([sys.executable, str(Path(__file__).parent / script), *args], check=True, cwd=ROOT)


def validation_heightmaps(labels: Path) -> list[tuple[str, str, float, object]]:
    """(id, family, reference V, heightmap) of every ok texture of the labels file."""
    from roughness.dataset.reader import open_dataset

    with open_dataset(labels) as data:
        return [(s.id, s.texture_record["family"], float(s.values["V"]), s.heightmap) for s in data.iter_samples("ok")]


def validation_predictions(textures: list, model_path: str) -> dict:
    """Reference V, predicted V, its relative spread and domain flag for every validation texture."""
    from roughness.surrogate.predictor import SurrogateModel

    model = SurrogateModel(model_path, threads=1)
    estimate = model.evaluate(np.stack([model.patch(hm) for *_, hm in textures]))
    if estimate.relative_std is None:
        raise SystemExit(f"{model_path} is a single network: this report needs an ensemble (a spread per answer)")
    return {"id": np.array([t[0] for t in textures]), "family": np.array([t[1] for t in textures]),
            "reference": np.array([t[2] for t in textures]), "predicted": estimate.roughness,
            "relative_std": estimate.relative_std, "in_domain": np.array([not r for r in estimate.reasons]),
            "log_offset": model.meta.log_offset, "max_std": (model.meta.ensemble or {}).get("max_std"),
            "meta": model.meta}


def relative_error(predicted: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """|predicted - reference| / max(reference, V_FLOOR), as the trade report takes it."""
    return np.abs(predicted - reference) / np.maximum(reference, V_FLOOR)


def trained_on(p: dict) -> np.ndarray:
    """Which validation textures belong to a family the model was trained on (not held out)."""
    return ~np.isin(p["family"], list(filter(None, (p["meta"].holdout_family or "").split(","))))


def sent_by_auto(p: dict, max_std: float | None) -> np.ndarray:
    """The textures ``--engine auto`` answers with a physics engine: out of domain, or spread above ``max_std``."""
    return ~p["in_domain"] | (p["relative_std"] > max_std) if max_std is not None else ~p["in_domain"]


def uncertainty(p: dict) -> dict:
    """Coverage of the +-2 sigma interval (in log(V + offset), the space the spread is made in) and auto's
    routing with its default threshold, on the validation textures."""
    offset = p["log_offset"]
    z = np.abs(np.log(p["reference"] + offset) - np.log(p["predicted"] + offset)) / p["relative_std"]
    rel = relative_error(p["predicted"], p["reference"])
    sent = sent_by_auto(p, p["max_std"])
    large = rel > LARGE_ERROR
    return {"n": len(z), "coverage_2sigma": float(np.mean(z <= 2)), "sent": float(sent.mean()),
            "sent_out_of_domain": float((~p["in_domain"]).mean()), "large_errors": int(large.sum()),
            "large_errors_caught": float(sent[large].mean()) if large.any() else None,
            "median_rel_err_kept": float(np.median(rel[~sent])) if (~sent).any() else None,
            "p95_rel_err_kept": float(np.percentile(rel[~sent], 95)) if (~sent).any() else None}


def routing(p: dict, rows: np.ndarray, thresholds: tuple[float, ...] = ROUTING_THRESHOLDS) -> list[dict]:
    """What auto would send to a physics engine and catch at other thresholds (the default's trade, seen whole)."""
    large = (relative_error(p["predicted"], p["reference"]) > LARGE_ERROR)[rows]
    out = []
    for t in thresholds:
        sent = sent_by_auto(p, t)[rows]
        out.append({"max_std": t, "sent": float(sent.mean()),
                    "large_errors_caught": float(sent[large].mean()) if large.any() else None})
    return out


def plot_routing(curves: dict[str, list[dict]], default: float | None, out: Path) -> None:
    """Share of large errors caught against share of inputs sent to a physics engine, one curve per set."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.6, 4.2))
    for name, rows in curves.items():
        x = [100 * r["sent"] for r in rows]
        y = [100 * (r["large_errors_caught"] or 0) for r in rows]
        ax.plot(x, y, "o-", label=name)
        for r, xi, yi in zip(rows, x, y):
            ax.annotate(f"{r['max_std']:g}", (xi, yi), fontsize=6, xytext=(3, -8), textcoords="offset points")
    ax.axvline(10, color="grey", ls=":", lw=0.8)
    ax.axhline(90, color="grey", ls=":", lw=0.8)
    ax.set(xlabel="inputs sent to the spectral engine or the FEM (%)",
           ylabel=f"predictions off by > {100 * LARGE_ERROR:.0f}% caught (%)",
           title=f"--engine auto: threshold on the relative spread (default {default:.3g})" if default else
           "--engine auto: threshold on the relative spread")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def accuracy(predicted: np.ndarray, reference: np.ndarray) -> dict:
    """Median and p95 relative error and Spearman of predictions against the reference."""
    from scipy.stats import spearmanr

    rel = relative_error(predicted, reference)
    return {"n": len(rel), "median_rel_err": float(np.median(rel)), "p95_rel_err": float(np.percentile(rel, 95)),
            "spearman": float(spearmanr(reference, predicted).statistic)}


def by_training(p: dict) -> dict[str, dict]:
    """Accuracy on the validation families the model was trained on, and on each family held out of training."""
    seen = trained_on(p)
    out = {"trained families": accuracy(p["predicted"][seen], p["reference"][seen])} if seen.any() else {}
    for f in np.unique(p["family"][~seen]):
        rows = p["family"] == f
        if rows.sum() >= 3:
            out[f"{f} (never trained on)"] = accuracy(p["predicted"][rows], p["reference"][rows])
    return out


def measure(textures: list, model_path: str) -> Measures:
    """The accuracy, the per-family split and the uncertainty of one model on the validation textures."""
    p = validation_predictions(textures, model_path)
    return Measures(p, accuracy(p["predicted"], p["reference"]), by_training(p), uncertainty(p))


def percent(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.1f}%"


def accuracy_targets(m: Measures) -> dict[str, tuple[str, str, bool | None]]:
    """Issue 29's accuracy and uncertainty targets, measured on one model: what -> (goal, reached, met)."""
    from roughness.surrogate.data import held_out_name

    a, unc = m.overall, m.uncertainty
    out = {"validation, median rel. error vs reference": ("<= 1.5%", percent(a["median_rel_err"]),
                                                          a["median_rel_err"] <= 0.015),
           "validation, p95 rel. error vs reference": ("<= 10%", percent(a["p95_rel_err"]), a["p95_rel_err"] <= 0.10),
           "validation, Spearman vs reference": (">= 0.998", f"{a['spearman']:.4f}", a["spearman"] >= 0.998)}
    for part, s in m.split.items():  # the validation set again: the families trained on, then each held out
        reached = f"{percent(s['median_rel_err'])} / {percent(s['p95_rel_err'])} / {s['spearman']:.4f}"
        if part == "trained families":
            out[f"validation, {part} only, median / p95 / Spearman"] = (
                "<= 1.5% / <= 10% / >= 0.998", reached,
                s["median_rel_err"] <= 0.015 and s["p95_rel_err"] <= 0.10 and s["spearman"] >= 0.998)
        else:
            out[f"validation, {part} (n={s['n']}), median / p95 / Spearman"] = (
                "<= 8% / - / >= 0.97", reached, s["median_rel_err"] <= 0.08 and s["spearman"] >= 0.97)
    meta = m.predictions["meta"]
    for family, s in (meta.ensemble or {}).get("ood_by_family", {}).items():
        name = held_out_name(family, meta.holdout_family)
        out[f"unseen family {name} (training data's {meta.label_fidelity} labels), median / Spearman"] = (
            "<= 8% / >= 0.97", f"{percent(s['median_rel_err'])} / {s['spearman']:.4f} (n={s['n']})",
            s["median_rel_err"] <= 0.08 and s["spearman"] >= 0.97)
    cover, caught, sent = unc["coverage_2sigma"], unc["large_errors_caught"], unc["sent"]
    out |= {"validation, +-2 sigma holds the reference": ("90-97%", percent(cover), 0.90 <= cover <= 0.97),
            f"auto catches predictions off by > {100 * LARGE_ERROR:.0f}%": (
                ">= 90%", f"{percent(caught)} of {unc['large_errors']}", None if caught is None else caught >= 0.90),
            "auto sends to the spectral engine or the FEM": ("<= 10%", percent(sent), sent <= 0.10)}
    return out


def int8_agreement(textures: list, fp32: np.ndarray, int8: str) -> dict:
    """How far the int8 graph's V moves from the fp32 graph's V ``fp32`` on the validation textures (relative,
    V_FLOOR)."""
    from roughness.surrogate.predictor import SurrogateModel

    model = SurrogateModel(int8, threads=1)
    rel = relative_error(model.evaluate(np.stack([model.patch(hm) for *_, hm in textures])).roughness, fp32)
    return {"n": len(rel), "median": float(np.median(rel)), "p95": float(np.percentile(rel, 95)),
            "max": float(rel.max())}


def auto_answers(textures: list, model_path: str) -> dict:
    """``--engine auto`` run on every validation texture: which engine answered, its accuracy and time."""
    from roughness.prediction import predict

    answers = predict([(t[0], t[3]) for t in textures], engine="auto", model=model_path)
    reference = np.array([t[2] for t in textures])
    value = np.array([a.roughness for a in answers])
    engines = np.array([a.engine for a in answers])
    return {"by_engine": {e: int((engines == e).sum()) for e in np.unique(engines)},
            "seconds": float(sum(a.seconds for a in answers)), **accuracy(value, reference),
            "surrogate_kept": accuracy(value[engines == "surrogate"], reference[engines == "surrogate"])}


def worst(p: dict, k: int = 10) -> list[dict]:
    """The k textures the surrogate gets most wrong against the reference."""
    rel = relative_error(p["predicted"], p["reference"])
    order = np.argsort(-rel)[:k]
    return [{"id": str(p["id"][i]), "family": str(p["family"][i]), "reference": float(p["reference"][i]),
             "predicted": float(p["predicted"][i]), "relative_std": float(p["relative_std"][i]),
             "in_domain": bool(p["in_domain"][i]), "rel_err": float(rel[i])} for i in order]


def trade_rows() -> dict[str, dict]:
    """The trade report's rows by engine spec."""
    with open(RESULTS / "trade" / "table.csv", newline="") as f:
        return {row["engine"]: row for row in csv.DictReader(f)}


def spec_of(model: str) -> str:
    """The trade report's engine spec of a model file (the shipped one, or one of the repository by its path)."""
    if Path(model) == (MODELS / "roughness-cnn.onnx").resolve():
        return "surrogate"
    if not Path(model).is_relative_to(ROOT):
        raise SystemExit(f"{model} is outside the repository: the trade report names its models by their path in it")
    return f"surrogate:{Path(model).relative_to(ROOT)}"


def break_even(cost_core_hours: float, rows: dict[str, dict], surrogate: str) -> list[dict]:
    """Textures after which the surrogate's cost (training and its labels, core-hours) is paid back against each
    physics engine, from the median seconds per texture of the trade report (one core each)."""
    t_model = float(rows[surrogate]["median_s"])
    out = []
    for spec, row in rows.items():
        if row["kind"] in ("fem", "spectral"):
            saved = float(row["median_s"]) - t_model
            out.append({"engine": spec, "median_s": float(row["median_s"]),
                        "textures": cost_core_hours * 3600 / saved if saved > 0 else None})
    return out


def timing_targets(latency: dict, maps: dict, int8: dict) -> list[Target]:
    e2e = latency["end_to_end_1thread_ms_median"]
    fresh = latency.get("fresh_cli_predict_wall_s", latency["fresh_process_wall_s"])
    rate = maps["map_footprints_per_s"]
    return [Target("end to end, batch 1, 1 thread", "<= 2 ms", f"{e2e:.2f} ms", e2e <= 2.0),
            Target("fresh process, `roughness predict` wall", "<= 0.3 s", f"{fresh:.2f} s", fresh <= 0.3),
            Target("roughness map, 2 threads", ">= 3,000 footprints/s", f"{rate:,.0f} footprints/s", rate >= 3000),
            Target(f"int8 V against fp32 V, validation textures (n={int8['n']}), max", "<= 2%",
                   f"{percent(int8['max'])} (median {percent(int8['median'])})", int8["max"] <= 0.02)]


def markdown(result: dict, table: list[Target], curves: dict, labels: Path, model: Measures, auto: dict,
             baseline_name: str) -> str:
    mark = {True: "yes", False: "**no**", None: "-"}
    unc, meta = model.uncertainty, model.predictions["meta"]
    lines = [f"# Surrogate v3 against its targets ({result['model']})", "",
             f"Reference: `{result['reference']}` on the validation set ({labels.name}, {unc['n']} textures); the "
             f"model answers as FEM `{meta.label_fidelity}`. Regenerate: `python benchmarks/surrogate_report.py "
             f"--labels {labels.name}`. The last column is the previous model, {baseline_name}, on the same "
             "textures.", "",
             f"| target | goal | reached | met | {baseline_name} |", "|---|---|---|---|---|",
             *(f"| {t.what} | {t.goal} | {t.reached} | {mark[t.met]} | {t.baseline} |" for t in table), "",
             f"Training cost (all members): {result['training_core_hours']:.2f} core-hours; its labels cost "
             f"{result['data_core_hours']:.1f} core-hours (spectral and FEM). All engines against the reference: "
             "[trade/report.md](trade/report.md); latency: [surrogate_latency.md](surrogate_latency.md); maps: "
             "[surrogate_map.md](surrogate_map.md).", "",
             "Break-even: the number of textures after which the surrogate's whole cost (training and labels, "
             "one core each) is paid back against answering every texture with the engine instead:", "",
             "| engine | median s per texture | break-even (textures) |", "|---|---|---|",
             *(f"| {b['engine']} | {b['median_s']:.3g} | "
               f"{'-' if b['textures'] is None else format(round(b['textures']), ',')} |" for b in result["break_even"]),
             "", "## --engine auto", "",
             f"With its default `--max-std` ({model.predictions['max_std']:.3g}), the textures it keeps have median "
             f"error {percent(unc['median_rel_err_kept'])} and p95 {percent(unc['p95_rel_err_kept'])}; "
             f"{percent(unc['sent_out_of_domain'])} are sent on as out of domain.", "",
             "Run on every validation texture (`roughness.predict(engine=\"auto\")`), it answered with "
             + ", ".join(f"{e} {n}" for e, n in auto["by_engine"].items())
             + f" times in {auto['seconds']:.1f} s in all; its answers have median error "
               f"{percent(auto['median_rel_err'])}, p95 {percent(auto['p95_rel_err'])} and Spearman "
               f"{auto['spearman']:.4f} against the reference.", "",
             "Other thresholds on the same textures (`--max-std T`; out-of-domain inputs are always sent on):", "",
             "| --max-std | " + " | ".join(f"{name}: sent / caught" for name in curves) + " |",
             "|---|" + "---|" * len(curves),
             *(f"| {t:g} | " + " | ".join(f"{percent(c[i]['sent'])} / {percent(c[i]['large_errors_caught'])}"
                                          for c in curves.values()) + " |" for i, t in enumerate(ROUTING_THRESHOLDS)),
             "", "![routing](surrogate_routing.png)", "",
             "## Textures the surrogate gets most wrong", "",
             "| texture | family | reference V | surrogate V | relative spread | in domain | rel. error |",
             "|---|---|---|---|---|---|---|",
             *(f"| {w['id']} | {w['family']} | {w['reference']:.4f} | {w['predicted']:.4f} | "
               f"{percent(w['relative_std'])} | {'yes' if w['in_domain'] else 'no'} | {percent(w['rel_err'])} |"
               for w in result["worst"])]
    return "\n".join(lines) + "\n"


def main() -> None:
    args = parse_args()
    labels = Path(args.labels).resolve()
    model_path, baseline_path = str(Path(args.model).resolve()), str(Path(args.baseline).resolve())
    int8_path = str(Path(args.int8).resolve()) if args.int8 else model_path.replace(".onnx", "-int8.onnx")
    spec = spec_of(model_path)
    run("trade_report.py", "--labels", str(labels))
    if not args.no_timing:
        run("surrogate_latency.py", "--model", model_path)
        run("surrogate_map.py", "--model", model_path)
    latency = json.loads((RESULTS / "surrogate_latency.json").read_text())
    maps = json.loads((RESULTS / "surrogate_map.json").read_text())

    textures = validation_heightmaps(labels)
    model, baseline = measure(textures, model_path), measure(textures, baseline_path)
    p, meta = model.predictions, model.predictions["meta"]
    int8 = int8_agreement(textures, p["predicted"], int8_path)
    auto = auto_answers(textures, model_path)
    rows = trade_rows()
    if spec not in rows:
        raise SystemExit(f"the trade report has no row for {spec}: add it to trade_report.ENGINES")
    curves = {"all validation textures": routing(p, np.ones(len(p["id"]), bool)),
              "trained families only": routing(p, trained_on(p))}
    plot_routing(curves, p["max_std"], RESULTS / "surrogate_routing.png")
    baseline_targets = accuracy_targets(baseline)
    table = [Target(what, goal, reached, met, baseline_targets.get(what, ("", "-", None))[1])
             for what, (goal, reached, met) in accuracy_targets(model).items()] + timing_targets(latency, maps, int8)
    cost = meta.cost_core_seconds or {}
    training_h, data_h = cost.get("training", 0.0) / 3600, cost.get("data_fem", 0.0) / 3600
    result = {"model": Path(model_path).name, "baseline": Path(baseline_path).name, "labels": labels.name,
              "reference": json.loads((RESULTS / "trade" / "compare.json").read_text())["reference"],
              "targets": [t.__dict__ for t in table], "by_training": model.split, "uncertainty": model.uncertainty,
              "baseline_by_training": baseline.split, "baseline_uncertainty": baseline.uncertainty,
              "routing": curves, "auto": auto, "int8": int8, "worst": worst(p),
              "ensemble": {k: v for k, v in (meta.ensemble or {}).items() if k != "member_val"},
              "training_core_hours": training_h, "data_core_hours": data_h, "label_fidelity": meta.label_fidelity,
              "break_even": break_even(training_h + data_h, rows, spec)}
    (RESULTS / "surrogate_report.json").write_text(json.dumps(result, indent=1) + "\n")
    text = markdown(result, table, curves, labels, model, auto, Path(baseline_path).name)
    (RESULTS / "surrogate_report.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()

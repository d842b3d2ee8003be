"""The comparison report: per-engine table (CSV, Markdown), plots, disagreements, break-even.

Estimators of V (FEM fidelities, the surrogate) are scored directly against the reference.
Classical measures are not in units of V: they are mapped to V by a power law fitted on the same
textures (least squares of log V on log measure), which flatters them; their Spearman needs no fit.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from scipy.stats import spearmanr

from roughness.core.figures import new_figure, save_figure
from roughness.core.files import atomic_write
from roughness.surrogate.metrics import scores

from .compare import SETUP_KEY, STORED, Outcome, Texture
from .result_cache import ResultCache

if TYPE_CHECKING:
    from matplotlib.figure import Figure

COLUMNS = ("engine", "kind", "n", "failures", "median_s", "p95_s", "median_rel_err", "p95_rel_err", "spearman",
           "r2_log")
STORED_MARK = "†"  # on times read from a dataset file: its build's times, not measured by the comparison


@dataclass
class EngineScore:
    engine: str
    kind: str
    keys: list[str]  # textures scored (both engine and reference answered, reference V > 0)
    reference: np.ndarray
    estimate: np.ndarray  # V, or the fitted power law of a classical measure
    raw: np.ndarray
    seconds: np.ndarray
    failures: int
    stored_times: bool  # some times come from a dataset's build (possibly a contended machine), not this comparison

    def row(self) -> dict:
        row = {"engine": self.engine, "kind": self.kind, "n": len(self.keys), "failures": self.failures,
               "median_s": _q(self.seconds, 50), "p95_s": _q(self.seconds, 95), "stored_times": self.stored_times}
        errors = scores(self.reference, self.estimate)  # reference V > 0 here, so nothing is left out
        if "spearman" not in errors:  # fewer than 3 textures
            return row | {k: math.nan for k in ("median_rel_err", "p95_rel_err", "spearman", "r2_log")}
        return row | {k: errors[k] for k in ("median_rel_err", "p95_rel_err", "r2_log")} | {
            "spearman": float(spearmanr(self.reference, self.raw).statistic)}  # of the measure itself, not its fit


def _q(values: np.ndarray, q: float) -> float:
    return float(np.percentile(values, q)) if len(values) else math.nan


def score(content: dict[str, str], kinds: dict[str, str], reference: str, cache: ResultCache) -> list[EngineScore]:
    """Scores of every engine (the reference first) on the textures ``content`` names (name -> content key).

    The scored ``keys`` of each EngineScore are texture names.
    """
    ref = {name: cache.get(reference, key) for name, key in content.items()}
    ref_ok = {k: e["value"] for k, e in ref.items() if e and e.get("error") is None and e["value"] > 0}
    scores = []
    for engine, kind in kinds.items():
        entries = {name: cache.get(engine, key) for name, key in content.items()}
        done = {k: e for k, e in entries.items() if e and e.get("error") is None}
        keys = [k for k in done if k in ref_ok and (kind != "classical" or done[k]["value"] > 0)]
        reference_v = np.array([ref_ok[k] for k in keys])
        raw = np.array([done[k]["value"] for k in keys], dtype=float)
        estimate = _power_law(raw, reference_v) if kind == "classical" else raw
        seconds = np.array([e["seconds"] for e in done.values() if e.get("seconds") is not None], dtype=float)
        failures = sum(1 for e in entries.values() if e and e.get("error") is not None)
        stored = any(e.get("source") == STORED for e in done.values())
        scores.append(EngineScore(engine, kind, keys, reference_v, estimate, raw, seconds, failures, stored))
    return scores


def _power_law(measure: np.ndarray, reference: np.ndarray) -> np.ndarray:
    if len(measure) < 2 or np.ptp(np.log(measure)) == 0:
        return np.full_like(reference, np.exp(np.mean(np.log(reference))) if len(reference) else np.nan)
    slope, intercept = np.polyfit(np.log(measure), np.log(reference), 1)
    return np.exp(intercept + slope * np.log(measure))


def write_tables(rows: list[dict], folder: Path) -> str:
    """table.csv and table.md; returns the Markdown (times read from a dataset marked with STORED_MARK)."""
    def write_csv(tmp: str) -> None:
        with open(tmp, "w", newline="") as f:
            writer = csv.DictWriter(f, COLUMNS)
            writer.writeheader()
            writer.writerows({k: row[k] for k in COLUMNS} for row in rows)

    atomic_write(folder / "table.csv", write_csv)
    head = ("| engine | kind | n | failures | median s | p95 s | median rel. error | p95 rel. error | Spearman | "
            "R² (log V) |\n|---|---|---|---|---|---|---|---|---|---|\n")
    mark = lambda r: STORED_MARK if r["stored_times"] else ""  # noqa: E731
    lines = "".join(
        f"| {r['engine']} | {r['kind']} | {r['n']} | {r['failures']} | {_sec(r['median_s'])}{mark(r)} | "
        f"{_sec(r['p95_s'])}{mark(r)} | {_pct(r['median_rel_err'])} | {_pct(r['p95_rel_err'])} | {r['spearman']:.3f} | "
        f"{r['r2_log']:.3f} |\n" for r in rows)
    write_text(folder / "table.md", head + lines)
    return head + lines


def write_text(path: Path, text: str) -> None:
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))


def _sec(s: float) -> str:
    return "-" if math.isnan(s) else f"{1e3 * s:.2f} ms" if s < 0.1 else f"{s:.2f} s"


def _pct(x: float) -> str:
    return "-" if math.isnan(x) else f"{100 * x:.1f}%"


def pareto_front(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point beats in both time and error, by increasing time."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


MARKERS = {"fem": ("s", "FEM"), "spectral": ("D", "spectral (the skin as an infinite layer)"),
           "surrogate": ("o", "surrogate (CNN)"), "classical": ("^", "classical measure (power-law fit)")}
LABEL_OFFSETS = [(7, 7), (7, -13), (-7, 7), (-7, -13), (7, 19), (7, -25), (-7, 19), (-7, -25), (7, 31), (7, -37)]


def plot_pareto(rows: list[dict], reference: str, out: Path | None = None) -> Figure:
    """Median time against median error per engine: marker by kind (legend), labels placed not to overlap."""
    fig = new_figure(figsize=(7.5, 5))
    ax = fig.subplots()
    rows = [r for r in rows if not math.isnan(r["median_s"]) and not math.isnan(r["median_rel_err"])]
    points = [(r["median_s"], 100 * r["median_rel_err"]) for r in rows]
    for kind, (marker, name) in MARKERS.items():
        mine = [p for r, p in zip(rows, points) if r["kind"] == kind]
        if mine:
            ax.scatter(*zip(*mine), marker=marker, s=60, zorder=3, label=name)
    front = pareto_front(points)
    ax.plot([points[i][0] for i in front], [points[i][1] for i in front], "k--", lw=1, label="Pareto front")
    stored = " († stored build times)" if any(r.get("stored_times") for r in rows) else ""
    ax.set(xscale="log", xlabel=f"median seconds per texture (one core){stored}",
           ylabel=f"median relative error vs {reference} (%)", title="Speed / accuracy trade")
    ax.margins(x=0.15, y=0.12)
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    _place_labels(fig, ax, [label(r["engine"]) + (STORED_MARK if r.get("stored_times") else "") for r in rows], points)
    return save_figure(fig, out, 110)


def _place_labels(fig, ax, texts: list[str], points: list[tuple[float, float]]) -> None:
    """Annotate each point with the first offset whose text overlaps no earlier label, marker or the legend."""
    renderer = fig.canvas.get_renderer()
    taken = [ax.get_legend().get_window_extent(renderer)]
    for x, y in points:
        px, py = ax.transData.transform((x, y))
        taken.append(_box(px - 6, py - 6, px + 6, py + 6))
    for text, point in zip(texts, points):
        for dx, dy in LABEL_OFFSETS:
            note = ax.annotate(text, point, textcoords="offset points", xytext=(dx, dy), fontsize=8,
                               ha="left" if dx > 0 else "right")
            box = note.get_window_extent(renderer)
            if not any(box.overlaps(other) for other in taken):
                break
            note.remove()
        else:  # every place is taken: the first one, with a leader line
            note = ax.annotate(text, point, textcoords="offset points", xytext=LABEL_OFFSETS[0], fontsize=8,
                               arrowprops={"arrowstyle": "-", "lw": 0.5})
            box = note.get_window_extent(renderer)
        taken.append(box)


def _box(x0: float, y0: float, x1: float, y1: float):
    from matplotlib.transforms import Bbox

    return Bbox([[x0, y0], [x1, y1]])


def label(engine: str) -> str:
    """Short engine name for plots: a model path becomes its file stem."""
    kind, _, path = engine.partition(":")
    return f"{kind}:{Path(path).stem}" if kind == "surrogate" and path else engine


def plot_scatter(scores: list[EngineScore], reference: str, out: Path | None = None) -> Figure:
    """Each engine's estimate against the reference's V, one panel per engine (log axes)."""
    shown = [s for s in scores if s.engine != reference and len(s.keys)]
    cols = min(4, max(len(shown), 1))
    rows = math.ceil(len(shown) / cols) or 1
    fig = new_figure(figsize=(3.4 * cols, 3.2 * rows))
    axes = fig.subplots(rows, cols, squeeze=False)
    for ax, s in zip(axes.ravel(), shown):
        ax.scatter(s.reference, s.estimate, s=8, alpha=0.7)
        lo, hi = min(s.reference.min(), s.estimate.min()), max(s.reference.max(), s.estimate.max())
        ax.plot([lo, hi], [lo, hi], "k--", lw=0.8)
        fitted = " (power-law fit)" if s.kind == "classical" else ""
        ax.set(xscale="log", yscale="log", title=f"{label(s.engine)}{fitted}", xlabel=f"{reference} V",
               ylabel="estimate")
        ax.title.set_fontsize(9)
    for ax in axes.ravel()[len(shown):]:
        ax.axis("off")
    fig.tight_layout()
    return save_figure(fig, out, 100)


def family_errors(scores: list[EngineScore], families: dict[str, str], reference: str) -> dict[str, dict[str, float]]:
    """Median relative error per engine and family."""
    out: dict[str, dict[str, float]] = {}
    for s in scores:
        if s.engine == reference or not len(s.keys):
            continue
        rel = np.abs(s.estimate - s.reference) / s.reference
        fam = np.array([families[k] for k in s.keys])
        out[s.engine] = {f: float(np.median(rel[fam == f])) for f in sorted(set(fam))}
    return out


def plot_family_errors(errors: dict[str, dict[str, float]], out: Path | None = None) -> Figure:
    """Median relative error (%) per engine and texture family (bars, log axis)."""
    families = sorted({f for e in errors.values() for f in e})
    fig = new_figure(figsize=(max(7, 1.1 * len(families) + 4), 4.2))
    ax = fig.subplots()
    width = 0.8 / max(len(errors), 1)
    for i, (engine, per_family) in enumerate(errors.items()):
        x = np.arange(len(families)) + i * width
        ax.bar(x, [100 * per_family.get(f, np.nan) for f in families], width, label=label(engine))
    ax.set_xticks(np.arange(len(families)) + 0.4 - width / 2, families, rotation=20)
    ax.set(yscale="log", ylabel="median relative error (%)", title="Error by texture family")
    ax.legend(fontsize=7, bbox_to_anchor=(1.01, 1), loc="upper left")
    fig.tight_layout()
    return save_figure(fig, out, 110)


def disagreements(s: EngineScore, families: dict[str, str], count: int = 8) -> list[dict]:
    """The textures where an engine is furthest from the reference (by |log ratio|)."""
    ratio = s.estimate / s.reference
    order = np.argsort(-np.abs(np.log(np.maximum(ratio, 1e-12))))[:count]
    return [{"key": s.keys[i], "family": families[s.keys[i]], "reference": float(s.reference[i]),
             "estimate": float(s.estimate[i]), "ratio": float(ratio[i])} for i in order]


def break_even(rows: list[dict], cost_core_seconds: dict | None) -> list[dict]:
    """Predictions after which generating data and training paid for themselves, per FEM engine."""
    if not cost_core_seconds:
        return []
    surrogate = next((r for r in rows if r["kind"] == "surrogate"), None)
    if surrogate is None:
        return []
    fixed = sum(cost_core_seconds.values())
    out = []
    for r in rows:
        if r["kind"] == "fem" and r["median_s"] > surrogate["median_s"]:
            out.append({"engine": r["engine"], "fixed_core_hours": fixed / 3600,
                        "saving_s_per_prediction": r["median_s"] - surrogate["median_s"],
                        "predictions": math.ceil(fixed / (r["median_s"] - surrogate["median_s"]))})
    return out


def write_report(textures: list[Texture], outcome: Outcome, kinds: dict[str, str], reference: str,
                 cache: ResultCache, out: Path, cost_core_seconds: dict | None, source: str) -> str:
    """Tables, plots and report.md in ``out``; returns the Markdown table."""
    setup_seconds = {e: entry["seconds"] for e in kinds if (entry := cache.get(e, SETUP_KEY))}
    families = {t.name: t.family for t in textures}
    scores = score(outcome.keys, kinds, reference, cache)
    rows = [s.row() for s in scores]
    out.mkdir(parents=True, exist_ok=True)
    table = write_tables(rows, out)
    plot_pareto(rows, reference, out / "pareto.png")
    plot_scatter(scores, reference, out / "predicted_vs_reference.png")
    errors = family_errors(scores, families, reference)
    plot_family_errors(errors, out / "error_by_family.png")
    counts = {f: sum(1 for t in textures if t.family == f) for f in sorted(set(families.values()))}
    text = [f"# Speed / accuracy: engines against `{reference}`\n",
            f"Input: `{source}`; {len(textures)} textures ({', '.join(f'{f} {n}' for f, n in counts.items())}).",
            "Regenerate with the same `roughness compare` command: cached results are reused.\n",
            table,
            "Times are per texture on one core: FEM with its block prepared (one-time set-up per process: "
            + (", ".join(f"{k} {v:.2f} s" for k, v in setup_seconds.items()) or "not measured here")
            + "); the surrogate end to end "
            "(patch, domain check, network) at batch 1. Classical measures are not in units of V: their errors "
            "are those of a power law fitted to the reference on these same textures (flattering them); "
            "Spearman needs no fit. Relative errors and R² leave out textures whose reference V is 0."
            + (f" {STORED_MARK} Times read from the dataset file: measured while it was built (several workers, "
               "possibly a contended machine), not by this comparison; do not compare them with the other times."
               if any(r["stored_times"] for r in rows) else "") + "\n",
            "![Pareto](pareto.png)\n", "![predicted vs reference](predicted_vs_reference.png)\n",
            "![error by family](error_by_family.png)\n"]
    if outcome.input_errors:
        text += [f"## Inputs not compared ({len(outcome.input_errors)})\n",
                 *(f"- `{name}`: {message}" for name, message in outcome.input_errors), ""]
    text.append("## Textures that disagree most\n")
    for s in scores:
        if s.kind in ("fem", "spectral", "surrogate") and s.engine != reference and len(s.keys):
            text.append(f"`{s.engine}`:\n\n| texture | family | {reference} V | estimate | ratio |\n|---|---|---|---|---|")
            text += [f"| {d['key']} | {d['family']} | {d['reference']:.4f} | {d['estimate']:.4f} | {d['ratio']:.2f} |"
                     for d in disagreements(s, families)]
            text.append("")
    even = break_even(rows, cost_core_seconds)
    if even:
        fixed = even[0]["fixed_core_hours"]
        text += ["## Break-even\n",
                 f"Generating the training data and training the surrogate cost {fixed:.2f} core-hours "
                 f"({', '.join(f'{k} {v / 3600:.2f} h' for k, v in cost_core_seconds.items())}). Each prediction "
                 "by the surrogate instead of FEM saves the difference in median time per texture:\n",
                 "| instead of | saving per prediction | predictions to break even |\n|---|---|---|"]
        stored = {r["engine"] for r in rows if r["stored_times"]}
        text += [f"| {e['engine']} | {e['saving_s_per_prediction']:.2f} s{STORED_MARK if e['engine'] in stored else ''} | "
                 f"{e['predictions']:,}{STORED_MARK if e['engine'] in stored else ''} |" for e in even]
        text.append("")
    write_text(out / "report.md", "\n".join(text))
    return table

"""Model card and accuracy plots of an exported surrogate, from its training run.

    roughness card RUN_DIR MODEL.onnx --card CARD.md --plots FOLDER [--latency LATENCY.json]

Reads the model's metadata, the run's ``predictions.csv`` and ``history.csv`` (the run refused unless its
``metrics.json`` records the model's training: ``check_provenance``) and, if given, the latency benchmark's
JSON (used only if it timed this model); writes the card and
``surrogate_accuracy.png`` / ``surrogate_training.png`` into the plots folder. The shipped card:
``roughness card runs/cnn models/roughness-cnn.onnx --card models/MODEL_CARD.md --plots benchmarks/results
--latency benchmarks/results/surrogate_latency.json --overwrite``.
"""
from __future__ import annotations

import csv
import json
import os
from collections import Counter
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.errors import InputError
from roughness.core.figures import new_figure, save_figure
from roughness.core.files import atomic_write, check_output
from roughness.core.hashing import file_sha256
from roughness.core.provenance import model_id

from .data import held_out_name
from .metadata import ModelMetadata, load_onnx, onnx_metadata, read_metadata
from .patch import DESCRIPTOR_NAMES, FOOTPRINT_MM
from .predictor import DEFAULT_MODEL

if TYPE_CHECKING:
    from matplotlib.figure import Figure

SPLIT_NAMES = {"train": "training", "val": "validation", "test": "held-out (unseen base textures)",
               "ood": "out-of-family"}


def plot_accuracy(rows: list[dict], holdout: str | None, fidelity: str, out: Path | None = None) -> Figure:
    """Surrogate V against FEM V on the held-out and out-of-family splits (log axes); PNG to ``out`` if given."""
    import matplotlib

    fig = new_figure(figsize=(10, 4.8))
    axes = fig.subplots(1, 2, sharex=True, sharey=True)
    families = sorted({r["family"] for r in rows})
    colours = dict(zip(families, matplotlib.colormaps["tab20"](np.arange(len(families)) % 20)))  # the v2 data has 14 families
    for ax, split in zip(axes, ("test", "ood")):
        part = [r for r in rows if r["split"] == split and float(r["V_fem"]) > 0]
        for family in families:
            pts = [(float(r["V_fem"]), float(r["V_predicted"])) for r in part if r["family"] == family]
            if pts:
                x, y = np.array(pts).T
                ax.scatter(x, y, s=10, color=colours[family], label=family, alpha=0.8)
        ax.plot([1e-3, 0.4], [1e-3, 0.4], "k--", lw=0.8)
        ax.set(xscale="log", yscale="log", xlabel=f"FEM V ({fidelity} fidelity)",
               title=f"{SPLIT_NAMES[split]} (n = {len(part)})")
    axes[0].set_ylabel("surrogate V")
    for ax in axes:
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="upper left")
    fig.suptitle(f"Surrogate vs FEM (held-out family: {holdout})")
    fig.tight_layout()
    return save_figure(fig, out, 110)


def plot_history(rows: list[dict], out: Path | None = None) -> Figure:
    """Training and validation loss per epoch; PNG to ``out`` if given."""
    epoch = [int(r["epoch"]) for r in rows]
    fig = new_figure(figsize=(6, 3.6))
    ax = fig.subplots()
    ax.semilogy(epoch, [float(r["train_loss"]) for r in rows], label="training (augmented)")
    ax.semilogy(epoch, [float(r["val_loss"]) for r in rows], label="validation")
    ax.set(xlabel="epoch", ylabel="MSE of log(V + 0.001)", title="Training history")
    ax.legend()
    fig.tight_layout()
    return save_figure(fig, out, 110)


def metric_table(metrics: dict, names: dict) -> str:
    """Markdown table of scores; a sentence instead if no row has enough samples (3) for scores."""
    if not any("spearman" in (metrics.get(key) or {}) for key in names):
        counts = ", ".join(f"{label} {metrics[key]['n']}" for key, label in names.items() if key in metrics)
        return f"Too few samples for scores (at least 3 with V > 0 are needed; n: {counts or 'none'})."
    lines = ["| split | n | Spearman | R² (log V) | median rel. error | p95 rel. error | flagged out of domain |",
             "|---|---|---|---|---|---|---|"]
    for key, label in names.items():
        m = metrics.get(key)
        if m and "spearman" in m:
            flagged = f"{100 * m['out_of_domain']:.1f}%" if "out_of_domain" in m else "-"
            lines.append(f"| {label} | {m['n']} | {m['spearman']:.3f} | {m['r2_log']:.3f} | "
                         f"{100 * m['median_rel_err']:.1f}% | {100 * m['p95_rel_err']:.1f}% | {flagged} |")
    return "\n".join(lines)


def int8_section(model_path: Path, meta: ModelMetadata, latency: dict | None) -> str:
    """The int8 sibling ``<stem>-int8.onnx``, if it exists and was quantised from this model."""
    path = model_path.with_name(model_path.stem + "-int8.onnx")
    if not path.exists():
        return ""
    int8 = onnx_metadata(path)
    if int8.int8 is None or replace(int8, int8=None) != meta:
        return ""
    report = int8.int8
    speed = (f" Graph latency {latency['int8']['batch1_1thread_ms_median']:.2f} ms at batch 1 on one thread, "
             f"{latency['int8']['batched_2threads_per_s']:,.0f} patches/s batched on 2 threads."
             if latency and latency.get("int8") else "")
    return f"""
### int8 variant
`{path.name}` ({path.stat().st_size / 1e6:.2f} MB): static QDQ quantisation of the convolutions only, per-channel
7-bit weights; the first convolution, the pooling and the dense head stay fp32; activation ranges from the
0.001..99.999th percentiles over
{report['calibration_inputs']} recipe textures (`roughness export ... --int8 FILE`; why: surrogate/quantize.py).
Its V differs from this model's by {100 * report['standard_median_rel_diff_vs_fp32']:.1f}% (median),
{100 * report['standard_max_rel_diff_vs_fp32']:.1f}% at most on the 13 standard textures, and by
{100 * report['check_median_rel_diff_vs_fp32']:.1f}% (median), {100 * report['check_p95_rel_diff_vs_fp32']:.1f}% (p95),
{100 * report['check_max_rel_diff_vs_fp32']:.1f}% at most on {report['checked_inputs']} other recipe textures
(relative to max(V, 0.002)).{speed} Its domain check reuses the fp32 model's limits.
"""


CARD_OPTIONS = ("levels", "max_label_error", "query_h_mm", "fem_weight", "log_offset", "holdout_family", "widths",
                "hidden", "max_epochs", "max_minutes", "batch_size")  # `roughness train` options the card repeats


def _option_text(value) -> str:
    """A training option's value as typed on the command line (widths: comma-separated)."""
    if isinstance(value, (list, tuple)):
        return ",".join(map(str, value))
    return f"{value:g}" if isinstance(value, float) else str(value)


def training_commands(meta: ModelMetadata, model_name: str) -> str:
    """The commands that made the model, from its training configuration (defaults left out)."""
    from .config import TrainConfig

    config, default = meta.train_config, asdict(TrainConfig("", ""))
    given = [(name, config.get(name, default[name])) for name in CARD_OPTIONS]
    options = [f"--{name.replace('_', '-')} {_option_text(value)}" for name, value in given
               if _option_text(value) != _option_text(default[name])]
    extra = [Path(p).name for p in config.get("extra_data", [])]
    train = " ".join([f"roughness train {meta.data.get('file')}", *(["--extra-data", *extra] if extra else []),
                      *options])
    if not meta.ensemble:
        return f"`{train} --out RUN`, then\n`roughness export RUN/checkpoint.pt --out {model_name}`"
    k = meta.ensemble["members"]
    data = " ".join([str(meta.data.get("file")), *extra])
    return (f"`{train} --seed K --out runK` for K = 0..{k - 1}, then\n"
            f"`roughness ensemble run*/checkpoint.pt --out {model_name} --data {data}`")


def multi_fidelity_section(meta: ModelMetadata) -> str:
    """How a multi-fidelity model's labels were made: rows per contact spacing and the spacing it answers for."""
    mf = meta.multi_fidelity
    if not mf:
        return ""
    by_level = mf["rows_by_h_mm"]  # contact spacing (mm, as text) or "spectral" -> rows
    fem = sorted(((float(h), n) for h, n in by_level.items() if h != "spectral"), reverse=True)
    rows = ", ".join([f"h = {h:g} mm: {n:,}" for h, n in fem]
                     + ([f"spectral engine: {by_level['spectral']:,}"] if "spectral" in by_level else []))
    extra = ", ".join(f"`{e.get('file')}` (inputs_sha256 `{e.get('inputs_sha256')}`)"
                      for e in mf.get("extra_data", [])) or "none"
    return f"""
### Multi-fidelity labels
Every mesh level the FEM solved for a texture is a label row, with the contact spacing h as an input
of the dense head (`roughness train ... --levels all`); the exported graph answers at
h = {mf['query_h_mm']:g} mm (`{meta.label_fidelity}`). Label rows per spacing: {rows}. Extra files of the
same textures: {extra}. Scores below are against the labels at h = {mf['query_h_mm']:g} mm.
"""


def ensemble_section(meta: ModelMetadata) -> str:
    """An ensemble graph's members, the calibration of its spread and auto's default threshold."""
    e = meta.ensemble
    if not e:
        return ""
    calibrated = e.get("max_std") is not None
    test = (f"On the test split ({e['test_inputs']} inputs) the 2-sigma interval holds the label for "
            f"{100 * e['coverage_2sigma_test']:.1f}%; the default threshold sends {100 * e['sent_to_fem_test']:.1f}% "
            f"on ({100 * e.get('out_of_domain_test', 0):.1f}% as out of domain) and catches "
            + (f"{100 * e['large_errors_caught_test']:.0f}% of the {e['large_errors_test']} predictions off by more "
               "than 15%." if e.get("large_errors_caught_test") is not None else "no prediction off by more than 15% "
                                                                                 "(there were none).")
            if calibrated and "test_inputs" in e else "")
    ood = e.get("ood_by_family") or {}
    by_family = metric_table(ood, {f: held_out_name(f, meta.holdout_family) for f in sorted(ood)}).replace(
        "| split |", "| family |")
    ood_table = f"\nFamilies never trained on, one by one:\n\n{by_family}\n" if ood else ""
    return f"""
## Ensemble and uncertainty
{e['members']} members (checkpoints `{'`, `'.join(e['member_sha256'])}`, first 16 hex digits of their sha256),
trained alike with seeds 0..{e['members'] - 1}, exported as one graph that returns their mean of log(V + offset)
and its spread (`roughness ensemble RUN*/checkpoint.pt --out MODEL.onnx --data DATA...`).
""" + (f"""The spread is scaled by {e['std_scale']:.3g} so that 95% of validation labels lie within 2 sigma
(raw coverage {100 * e['raw_coverage_2sigma_val']:.1f}%), and `--engine auto` sends inputs whose relative spread
exceeds {e['max_std']:.3g} to a physics engine (the spectral one where it holds, the FEM otherwise): the
threshold at which 10% of the validation inputs are sent on, counting the {100 * e.get('out_of_domain_val', 0):.1f}% sent as out of domain. {test}
""" if calibrated else "The spread is not calibrated (exported without `--data`): no default threshold.\n") + ood_table


ACCURACY_PNG, TRAINING_PNG = "surrogate_accuracy.png", "surrogate_training.png"  # written into the plots folder
# the run's files the card reads: column -> type (rows are kept as text, checked to convert)
PREDICTION_COLUMNS = {"family": str, "split": str, "V_fem": float, "V_predicted": float}
HISTORY_COLUMNS = {"epoch": int, "train_loss": float, "val_loss": float}
LIMITATIONS = """
## Limitations
- It imitates FEM, which is itself a model of perception (R = 0.91 with perceived roughness in the paper).
- One skin footprint: the 10 mm square at the centre of the map (or at `--centre`); larger objects
  need several calls (or `roughness predict --map`).
- Trained on the synthetic texture families listed above. Held-out numbers describe textures
  like these; the out-of-family numbers are a better guide for anything else.
"""


@dataclass
class CardInputs:
    """What a card is written from: the model, its training run's tables and (if it timed this model) the latency
    benchmark."""

    model_path: Path
    meta: ModelMetadata
    model_version: int  # the ONNX model_version (0: unversioned)
    shipped: bool  # the model is the shipped default
    predictions: list[dict]  # predictions.csv of the run, rows of text
    history: list[dict]  # history.csv of the run
    latency: dict | None  # surrogate_latency.json, or None
    plots_link: Path  # the plots folder relative to the card's folder


def write_card(run_dir: Path, model_path: Path, card: Path, plots: Path, latency_path: Path | None = None,
               overwrite: bool = False) -> None:
    """Write the card of ``model_path`` to ``card`` and its two plots into the folder ``plots``, from the training
    run folder ``run_dir``; every input is read before anything is written (``overwrite``: replace card and plots)."""
    check_outputs(card, plots, overwrite)
    inputs = read_inputs(run_dir, model_path, card, plots, latency_path)
    text = card_text(inputs)
    meta = inputs.meta
    plot_accuracy(inputs.predictions, meta.holdout_family, meta.label_fidelity, plots / ACCURACY_PNG)
    plot_history(inputs.history, plots / TRAINING_PNG)
    atomic_write(card, lambda tmp: Path(tmp).write_text(text), overwrite)


def check_outputs(card: Path, plots: Path, overwrite: bool) -> None:
    """InputError unless the card and the two plots may be written (before anything is read or computed)."""
    if not plots.is_dir():
        raise InputError(f"plots folder {plots} does not exist" if not plots.exists() else
                         f"{plots} is a file, not a folder", parameter="plots")
    check_output(card, overwrite, "card")
    for name in (ACCURACY_PNG, TRAINING_PNG):
        check_output(plots / name, overwrite, "plots")


def read_inputs(run_dir: Path, model_path: Path, card: Path, plots: Path, latency_path: Path | None) -> CardInputs:
    """The model's metadata and version, the run's predictions and history (the run checked to be the model's, by
    ``check_provenance``), and the latency if it timed this model."""
    graph = load_onnx(model_path)
    meta = read_metadata({p.key: p.value for p in graph.metadata_props}, model_path)
    shipped = model_path.resolve() == DEFAULT_MODEL.resolve() or (
        DEFAULT_MODEL.exists() and file_sha256(model_path) == file_sha256(DEFAULT_MODEL))
    predictions = read_table(run_dir / "predictions.csv", PREDICTION_COLUMNS)
    history = read_table(run_dir / "history.csv", HISTORY_COLUMNS)
    check_provenance(run_dir, model_path, meta, history)
    return CardInputs(model_path=model_path, meta=meta, model_version=graph.model_version, shipped=shipped,
                      predictions=predictions, history=history, latency=read_latency(latency_path, model_path),
                      plots_link=Path(os.path.relpath(plots.resolve(), card.resolve().parent)))


# what a run's metrics.json and the model's metadata both record of the training (an ensemble keeps member 0's)
RUN_RECORD = ("data", "train_config", "holdout_family", "test_fraction", "label_fidelity", "simulation", "widths",
              "hidden", "best_epoch", "epochs")


def check_provenance(run_dir: Path, model_path: Path, meta: ModelMetadata, history: list[dict]) -> None:
    """InputError for ``run_dir`` unless the run made the model: its metrics.json records the model's data
    checksum, training options, held-out family, network and epochs (a single network's scores too), its history
    has the model's epochs, and (an ensemble) its checkpoint is the model's member 0."""
    run = read_run_record(run_dir / "metrics.json")
    ours = json.loads(meta.to_json())
    keys = RUN_RECORD + (() if meta.ensemble else ("metrics", "test_by_family"))
    differ = [_difference(key, ours.get(key), run.get(key)) for key in keys if run.get(key) != ours.get(key)]
    if not differ and len(history) != meta.epochs:
        differ.append(f"epochs {meta.epochs} vs {len(history)} rows of history.csv")
    checkpoint = run_dir / "checkpoint.pt"
    if meta.ensemble and checkpoint.is_file() and file_sha256(checkpoint)[:16] != meta.ensemble["member_sha256"][0]:
        differ.append(f"member 0's checkpoint {meta.ensemble['member_sha256'][0]} vs {file_sha256(checkpoint)[:16]}")
    if differ:
        raise InputError(f"{model_path} was not made by the training run {run_dir} (the model's record vs the run's: "
                         f"{'; '.join(differ)}): its card would describe the model with another run's scores and "
                         "plots; give the model's own run folder (an ensemble: its member 0's)", parameter="run_dir")


def read_run_record(path: Path) -> dict:
    """A training run's metrics.json (a JSON object); InputError for ``run_dir`` otherwise."""
    try:
        record = json.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(f"{path} not found: not the folder of a training run (`roughness train` writes it)",
                         parameter="run_dir") from None
    except (OSError, ValueError) as err:  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        raise InputError(f"cannot read {path} as a training run's JSON: {err}", parameter="run_dir") from None
    if not isinstance(record, dict):
        raise InputError(f"{path}: expected a training run's JSON object", parameter="run_dir")
    return record


def _difference(key: str, ours: object, theirs: object) -> str:
    """How a recorded value differs: the values, or a record's entries that differ (their values if plain)."""
    if not (isinstance(ours, dict) and isinstance(theirs, dict)):
        return f"{key} {_brief(ours)} vs {_brief(theirs)}"
    entries = [k for k in sorted(ours.keys() | theirs.keys()) if ours.get(k) != theirs.get(k)]
    return f"{key} " + ", ".join(k if isinstance(ours.get(k), dict) else f"{k} {_brief(ours.get(k))} vs "
                                 f"{_brief(theirs.get(k))}" for k in entries)


def _brief(value: object, width: int = 40) -> str:
    """A recorded value for a message, cut to ``width`` characters."""
    text = json.dumps(value, sort_keys=True)
    return text if len(text) <= width else text[:width - 3] + "..."


def read_table(path: Path, columns: dict[str, type]) -> list[dict]:
    """The rows of a training run's CSV file (text); InputError for ``run_dir`` unless it has ``columns`` and each
    value converts to its column's type."""
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            rows, header = list(reader), reader.fieldnames or []
    except FileNotFoundError:
        raise InputError(f"{path} not found: not the folder of a training run", parameter="run_dir") from None
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise InputError(f"cannot read {path}: {err}", parameter="run_dir") from None
    missing = [column for column in columns if column not in header]
    if missing:
        raise InputError(f"{path}: no column {', '.join(missing)}: not a training run's file", parameter="run_dir")
    for number, row in enumerate(rows, 2):
        for column, kind in columns.items():
            try:
                kind(row[column])
            except (TypeError, ValueError):
                raise InputError(f"{path}, line {number}: expected a {kind.__name__} in column {column!r}, got "
                                 f"{row.get(column)!r}", parameter="run_dir") from None
    return rows


def read_latency(path: Path | None, model_path: Path) -> dict | None:
    """The latency benchmark's results if they timed this model (by file name), else None."""
    if path is None or not path.exists():
        return None
    try:
        latency = json.loads(path.read_text())
    except (OSError, ValueError) as err:  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        raise InputError(f"cannot read {path} as the latency benchmark's JSON: {err}", parameter="latency_path") from None
    if not isinstance(latency, dict):
        raise InputError(f"{path}: expected the latency benchmark's JSON object", parameter="latency_path")
    return latency if latency.get("model") == model_path.name else None


def card_text(c: CardInputs) -> str:
    """The card's Markdown."""
    return (_summary(c) + _training_data(c) + _training(c) + _accuracy(c) + _targets(c) + _speed(c)
            + int8_section(c.model_path, c.meta, c.latency) + ensemble_section(c.meta) + _input_domain(c.meta)
            + LIMITATIONS)


def _summary(c: CardInputs) -> str:
    """Title, version and what the model computes from what."""
    meta, sim = c.meta, c.meta.simulation
    version = f"model version {c.model_version}" if c.model_version else "unversioned (ONNX model_version 0)"
    pixels = round(FOOTPRINT_MM / meta.patch_pixel_mm)
    given = lambda key, unit="": f"{sim[key]}{unit}" if key in sim else "(not recorded)"  # noqa: E731
    coarse_note = (" The coarse labels sit a few %\n  below `default` FEM (studies/results/mesh_convergence.md); the "
                   "standard scale used for the\n  equivalent wavelength is computed at the same fidelity, so "
                   "equivalent wavelengths and JNDs carry over." if meta.label_fidelity == "coarse" else "")
    return f"""# Model card: {c.model_path.name}

A small CNN that predicts the FEM roughness V (strain variation at the Merkel receptor depth,
Tymms et al. 2018) of a texture from its heightmap, in about a millisecond instead of seconds.

- **Version**: {version} (the ONNX `model_version`); **model id** `{model_id(c.model_path.read_bytes())}` (the first
  16 hex digits of the file's SHA-256), as every result's `provenance` names it.

## What it computes
- **Input**: the heights under the {FOOTPRINT_MM:g} mm x {FOOTPRINT_MM:g} mm skin footprint, box-averaged to
  {meta.patch_pixel_mm} mm pixels ({pixels} x {pixels}), in mm relative to the highest point.
- **Output**: log(V + {meta.log_offset}), hence V; and a {len(meta.domain['mean'])}-number embedding for the domain score.
- **Network**: {meta.parameters:,} parameters; strided 3x3 convolutions with batch norm
  (widths {list(meta.widths)}), global mean, two dense layers. ONNX, one self-contained file of
  {c.model_path.stat().st_size / 1e6:.2f} MB, dynamic batch axis; metadata key `roughness` holds everything below.
- **Labels it imitates**: FEM at `{meta.label_fidelity}` fidelity with force {given('force_n', ' N')}, E = {given('young_mpa', ' MPa')},
  nu = {given('poisson')}, {given('contact')} contact, {given('element').upper()} elements. Other forces, materials or contact
  models are outside what it was trained on: use `--engine fem` for them.{coarse_note}
"""


def _training_data(c: CardInputs) -> str:
    """The dataset, its samples per family, checksum and splits."""
    meta = c.meta
    families = Counter(r["family"] for r in c.predictions)
    extra_files = "".join(f" with `{e['file']}`" for e in (meta.multi_fidelity or {}).get("extra_data", []))
    held = (f"Held out entirely (out-of-family score): {', '.join(f'`{f}`' for f in meta.holdout_family.split(','))}."
            if meta.holdout_family else "No family is held out.")
    spectral_rows = (meta.multi_fidelity or {}).get("rows_by_h_mm", {}).get("spectral")
    spectral = (f" (scored on; besides them, {spectral_rows:,} labelled by the spectral engine)" if spectral_rows
                else "")
    return f"""
## Training data
- Dataset `{meta.data.get('file')}`{extra_files} (recipe `{meta.data.get('recipe')}`): {len(c.predictions)} FEM samples labelled at `{meta.label_fidelity}`{spectral}; by family:
  {', '.join(f'{f} {n}' for f, n in sorted(families.items()))}.
- Data checksum (inputs_sha256): `{meta.data.get('inputs_sha256')}`
- Splits by base texture (family, parameters, seed; perturbations ignored), so no perturbed sibling of a
  test texture is trained on: test {100 * meta.test_fraction:.0f}%, validation {100 * meta.train_config['val_fraction']:.0f}%, the rest training.
  {held}
"""


def _training(c: CardInputs) -> str:
    """The commands and settings that trained the model, and what it cost."""
    meta, config = c.meta, c.meta.train_config
    cost = (f", {meta.minutes:.1f} min on {config['threads']} CPU threads.\n" if not meta.ensemble else
            f" (member 0); all {meta.ensemble['members']} members took {meta.minutes:.1f} min on {config['threads']} "
            f"CPU threads ({meta.cost_core_seconds.get('training', 0) / 3600:.2f} core-hours).\n")
    trade = ("Against FEM on the 160-texture validation set, with the other engines: "
             "benchmarks/results/trade/report.md.\n" if c.shipped else "")
    return f"""
## Training
{training_commands(meta, c.model_path.name)}:
seed {config['seed']}, AdamW (learning rate {config['learning_rate']:g}, cosine schedule over
{config['max_epochs']} epochs), batch {config['batch_size']}, a random 90-degree rotation and mirror per batch,
best validation epoch {meta.best_epoch} of {meta.epochs}{cost}{trade}
![training history]({c.plots_link / TRAINING_PNG})
"""


def _accuracy(c: CardInputs) -> str:
    """Scores against FEM per split and per family of the held-out textures."""
    meta = c.meta
    by_family = metric_table(meta.test_by_family, {f: f for f in sorted(meta.test_by_family)})
    return f"""
## Accuracy against FEM ({meta.label_fidelity} labels)
{multi_fidelity_section(meta)}
{metric_table(meta.metrics, SPLIT_NAMES)}

Held-out textures by family:

{by_family.replace('| split |', '| family |')}

Relative errors and R² leave out samples with V = 0 (exactly flat footprints), which have no
relative error; they are counted in the metadata (`n_zero`).

![surrogate vs FEM]({c.plots_link / ACCURACY_PNG})
"""


def _targets(c: CardInputs) -> str:
    """The accuracy (and, if measured, speed) targets and what the model reached."""
    test, ood, latency = c.meta.metrics.get("test", {}), c.meta.metrics.get("ood", {}), c.latency
    number = lambda m, k, pct=False: (f"{100 * m[k]:.1f}%" if pct else f"{m[k]:.3f}") if k in m else "-"  # noqa: E731
    rows = [
        ("held-out Spearman", ">= 0.97", number(test, "spearman")),
        ("held-out R² on log V", ">= 0.95", number(test, "r2_log")),
        ("held-out median relative error", "<= 7%", number(test, "median_rel_err", True)),
        ("out-of-family Spearman", ">= 0.85", number(ood, "spearman")),
    ]
    if latency:
        rows += [
            ("latency, batch 1, one thread", "<= 2 ms", f"{latency['batch1_1thread_ms_median']:.2f} ms (graph), "
                                                        f"{latency['end_to_end_1thread_ms_median']:.2f} ms (end to end)"),
            ("batched throughput, 2 threads", ">= 2,000 patches/s", f"{latency['batched_patches_per_s']['2']:,.0f}"),
        ]
    return "\n## Targets\n\n| target | wanted | reached |\n|---|---|---|\n" + "".join(
        f"| {a} | {b} | {c} |\n" for a, b, c in rows)


def _speed(c: CardInputs) -> str:
    """The latency benchmark's numbers for this model, or how to measure them."""
    latency = c.latency
    if not latency:
        return f"\n## Speed\nNot measured for this model: `python benchmarks/surrogate_latency.py --model {c.model_path}`.\n"
    return f"""
## Speed
From `python benchmarks/surrogate_latency.py --model {c.model_path.name}` ({latency['machine']}): \
{latency['batch1_1thread_ms_median']:.2f} ms per patch at batch 1 on one thread
(graph only), {latency['end_to_end_1thread_ms_median']:.2f} ms end to end (patch, descriptors, domain check);
{latency['batched_patches_per_s']['2']:,.0f} patches/s batched on 2 threads. FEM `default` takes
{latency['fem_warm_seconds']['default']:.2f} s per texture with a warm block in the same run: a speed-up of
{latency['speedup_vs_fem_default_end_to_end']:,.0f}x.
"""


def _input_domain(meta: ModelMetadata) -> str:
    """When an input is flagged out of domain, and the descriptor ranges."""
    domain = meta.domain
    return f"""
## Input domain
An input is flagged `in_domain: false` (and `--engine auto` runs the FEM for it) when a descriptor of
its footprint patch leaves the training range (0.5th to 99.5th percentile, widened by 5% of the span)
or when the Mahalanobis distance of its embedding from the training embeddings exceeds the training
set's 99.5th percentile ({domain['threshold']:.3g}).

| descriptor | low | high |
|---|---|---|
""" + "".join(f"| {n} | {lo:.3g} | {hi:.3g} |\n" for n, lo, hi in zip(DESCRIPTOR_NAMES, domain["low"], domain["high"])) + """
relief: 99.5th minus 0.5th percentile height (mm); feature: 2 pi std(h) / rms slope (mm); slopes are
dimensionless (dh/dx).
"""

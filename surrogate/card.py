"""Model card and accuracy plots of an exported surrogate, from its training run.

    python -m roughness.surrogate.card RUN_DIR MODEL.onnx --card models/MODEL_CARD.md

Reads the model's metadata, the run's ``predictions.csv`` and ``history.csv`` and the latency
benchmark (benchmarks/results/surrogate_latency.json, if present); writes the card and
``surrogate_accuracy.png`` / ``surrogate_training.png`` next to the latency results.
"""
from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np

from .patch import DESCRIPTOR_NAMES, FOOTPRINT_MM
from .predictor import SurrogateModel

RESULTS = Path(__file__).resolve().parent.parent / "benchmarks" / "results"
SPLIT_NAMES = {"train": "training", "val": "validation", "test": "held-out (unseen base textures)",
               "ood": "out-of-family"}


def read_csv(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def plot_accuracy(rows: list[dict], holdout: str | None, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.8), sharex=True, sharey=True)
    families = sorted({r["family"] for r in rows})
    colours = dict(zip(families, plt.cm.tab10.colors))
    for ax, split in zip(axes, ("test", "ood")):
        part = [r for r in rows if r["split"] == split and float(r["V_fem"]) > 0]
        for family in families:
            pts = [(float(r["V_fem"]), float(r["V_predicted"])) for r in part if r["family"] == family]
            if pts:
                x, y = np.array(pts).T
                ax.scatter(x, y, s=10, color=colours[family], label=family, alpha=0.8)
        ax.plot([1e-3, 0.4], [1e-3, 0.4], "k--", lw=0.8)
        ax.set(xscale="log", yscale="log", xlabel="FEM V", title=f"{SPLIT_NAMES[split]} (n = {len(part)})")
    axes[0].set_ylabel("surrogate V")
    axes[0].legend(fontsize=7, loc="upper left")
    fig.suptitle(f"Surrogate vs FEM (held-out family: {holdout})")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def plot_history(rows: list[dict], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    epoch = [int(r["epoch"]) for r in rows]
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.semilogy(epoch, [float(r["train_loss"]) for r in rows], label="training (augmented)")
    ax.semilogy(epoch, [float(r["val_loss"]) for r in rows], label="validation")
    ax.set(xlabel="epoch", ylabel="MSE of log(V + 0.001)", title="Training history")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def metric_table(metrics: dict, names: dict) -> str:
    lines = ["| split | n | Spearman | R² (log V) | median rel. error | p95 rel. error | flagged out of domain |",
             "|---|---|---|---|---|---|---|"]
    for key, label in names.items():
        m = metrics.get(key)
        if m and "spearman" in m:
            flagged = f"{100 * m['out_of_domain']:.1f}%" if "out_of_domain" in m else "-"
            lines.append(f"| {label} | {m['n']} | {m['spearman']:.3f} | {m['r2_log']:.3f} | "
                         f"{100 * m['median_rel_err']:.1f}% | {100 * m['p95_rel_err']:.1f}% | {flagged} |")
    return "\n".join(lines)


def int8_section(model_path: Path, latency: dict | None) -> str:
    path = model_path.with_name(model_path.stem + "-int8.onnx")
    if not path.exists():
        return ""
    report = SurrogateModel(path).meta["int8"]
    speed = (f" Graph latency {latency['int8']['batch1_1thread_ms_median']:.2f} ms at batch 1 on one thread, "
             f"{latency['int8']['batched_2threads_per_s']:,.0f} patches/s batched on 2 threads."
             if latency and latency.get("int8") else "")
    return f"""
### int8 variant
`{path.name}` ({path.stat().st_size / 1e6:.2f} MB): static QDQ quantisation with per-channel int8 weights,
activations calibrated on {report['calibration_inputs']} recipe textures (`roughness export ... --int8 FILE`). On
{report['checked_inputs']} other textures its V differs from this model's by {100 * report['median_rel_diff_vs_fp32']:.1f}% (median),
{100 * report['max_rel_diff_vs_fp32']:.1f}% at most.{speed} Its domain check reuses the fp32 model's limits.
"""


def write_card(run: Path, model_path: Path, card: Path) -> None:
    model = SurrogateModel(model_path)
    meta = model.meta
    RESULTS.mkdir(parents=True, exist_ok=True)
    plot_accuracy(read_csv(run / "predictions.csv"), meta["holdout_family"], RESULTS / "surrogate_accuracy.png")
    plot_history(read_csv(run / "history.csv"), RESULTS / "surrogate_training.png")
    latency_path = RESULTS / "surrogate_latency.json"
    latency = json.loads(latency_path.read_text()) if latency_path.exists() else None
    test, ood = meta["metrics"]["test"], meta["metrics"].get("ood", {})
    sim = meta["simulation"]
    domain = meta["domain"]
    rel = Path("../benchmarks/results")
    target_rows = [
        ("held-out Spearman", ">= 0.97", f"{test['spearman']:.3f}"),
        ("held-out R² on log V", ">= 0.95", f"{test['r2_log']:.3f}"),
        ("held-out median relative error", "<= 7%", f"{100 * test['median_rel_err']:.1f}%"),
        ("out-of-family Spearman", ">= 0.85", f"{ood.get('spearman', float('nan')):.3f}"),
    ]
    if latency:
        target_rows += [
            ("latency, batch 1, one thread", "<= 2 ms", f"{latency['batch1_1thread_ms_median']:.2f} ms (graph), "
                                                        f"{latency['end_to_end_1thread_ms_median']:.2f} ms (end to end)"),
            ("batched throughput, 2 threads", ">= 2,000 patches/s", f"{latency['batched_patches_per_s']['2']:,.0f}"),
        ]
    text = f"""# Model card: {model_path.name}

A small CNN that predicts the FEM roughness V (strain variation at the Merkel receptor depth,
Tymms et al. 2018) of a texture from its heightmap, in about a millisecond instead of seconds.

## What it computes
- **Input**: the heights under the {FOOTPRINT_MM:g} mm x {FOOTPRINT_MM:g} mm skin footprint, box-averaged to
  {meta['patch_pixel_mm']} mm pixels ({round(FOOTPRINT_MM / meta['patch_pixel_mm'])} x {round(FOOTPRINT_MM / meta['patch_pixel_mm'])}), in mm relative to the highest point.
- **Output**: log(V + {meta['log_offset']}), hence V; and a {len(domain['mean'])}-number embedding for the domain score.
- **Network**: {meta['parameters']:,} parameters; strided 3x3 convolutions with batch norm down to a 7 x 7 grid
  (widths {meta['widths']}), global mean, two dense layers. ONNX, one self-contained file of
  {model_path.stat().st_size / 1e6:.2f} MB, dynamic batch axis; metadata key `roughness` holds everything below.
- **Labels it imitates**: FEM at `{meta['label_fidelity']}` fidelity with force {sim.get('force_n')} N, E = {sim.get('young_mpa')} MPa,
  nu = {sim.get('poisson')}, {sim.get('contact')} contact, {sim.get('element', 'p1').upper()} elements. Other forces, materials or contact
  models are outside what it was trained on: use `--engine fem` for them. The coarse labels sit a few %
  below `default` FEM (benchmarks/results/mesh_convergence.md); the standard scale used for the
  equivalent wavelength is computed at the same fidelity, so equivalent wavelengths and JNDs carry over.

## Training data
- Recipe `datasets/training.json` (`{meta['data'].get('recipe')}`): bump textures (weight 4) and seven natural
  families (weight 1 each), 70% perturbed; {sum(m['n'] + m['n_zero'] for m in meta['metrics'].values())} FEM samples.
- Data checksum (inputs_sha256, see `datasets/training-v1.sha256.json`): `{meta['data']['inputs_sha256']}`
- Regenerate (about 35 min on 2 cores, resumable):
  `roughness dataset build --recipe datasets/training.json --n 3000 --fidelity coarse --workers 2 --out training-v1.h5`
- Splits by base texture (family, parameters, seed; perturbations ignored), so no perturbed sibling of a
  test texture is trained on: test {100 * meta['test_fraction']:.0f}%, validation {100 * meta['train_config']['val_fraction']:.0f}%, the rest training.
  Family `{meta['holdout_family']}` is held out entirely (out-of-family score).

## Training
`roughness train training-v1.h5 --out runs/cnn`, then
`roughness export runs/cnn/checkpoint.pt --out models/{model_path.name} --int8 models/{model_path.stem}-int8.onnx`:
seed {meta['train_config']['seed']}, AdamW (learning rate {meta['train_config']['learning_rate']:g}, cosine schedule over
{meta['train_config']['max_epochs']} epochs), batch {meta['train_config']['batch_size']}, a random 90-degree rotation and mirror per batch,
best validation epoch {meta['best_epoch']} of {meta['epochs']}, {meta['minutes']:.1f} min on 2 CPU cores.
Against FEM `fine` on the 160-texture validation set, with the other engines: benchmarks/results/trade/report.md.

![training history]({rel / 'surrogate_training.png'})

## Accuracy against FEM ({meta['label_fidelity']} labels)

{metric_table(meta['metrics'], SPLIT_NAMES)}

Held-out textures by family:

{metric_table(meta['test_by_family'], {f: f for f in sorted(meta['test_by_family'])}).replace('| split |', '| family |')}

Relative errors and R² leave out samples with V = 0 (exactly flat footprints), which have no
relative error; they are counted in the metadata (`n_zero`).

![surrogate vs FEM]({rel / 'surrogate_accuracy.png'})

## Targets

| target | wanted | reached |
|---|---|---|
""" + "".join(f"| {a} | {b} | {c} |\n" for a, b, c in target_rows) + """
## Speed
""" + (f"""From `python benchmarks/surrogate_latency.py` ({latency['machine']}; full table in
benchmarks/results/surrogate_latency.md): {latency['batch1_1thread_ms_median']:.2f} ms per patch at batch 1 on one thread
(graph only), {latency['end_to_end_1thread_ms_median']:.2f} ms end to end (patch, descriptors, domain check);
{latency['batched_patches_per_s']['2']:,.0f} patches/s batched on 2 threads. FEM `default` takes
{latency['fem_warm_seconds']['default']:.2f} s per texture with a warm block in the same run: a speed-up of
{latency['speedup_vs_fem_default_end_to_end']:,.0f}x.
""" if latency else "Run `python benchmarks/surrogate_latency.py`.\n") + int8_section(model_path, latency) + f"""
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

## Limitations
- It imitates FEM, which is itself a model of perception (R = 0.91 with perceived roughness in the paper).
- One skin footprint: the 10 mm square at the centre of the map (or at `--centre`); larger objects
  need several calls.
- Trained on synthetic textures (bumps and seven natural families). Held-out numbers describe textures
  like these; the out-of-family numbers are a better guide for anything else.
"""
    card.write_text(text)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="training output folder (predictions.csv, history.csv)")
    parser.add_argument("model", type=Path, help="exported ONNX model")
    parser.add_argument("--card", type=Path, default=Path("models/MODEL_CARD.md"))
    args = parser.parse_args(argv)
    write_card(args.run, args.model, args.card)


if __name__ == "__main__":
    main()

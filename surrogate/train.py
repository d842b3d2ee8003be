"""Train the surrogate CNN on a dataset file, on the CPU: one loop, top to bottom.

    roughness train training.h5 --out runs/cnn

Reads every ok sample as a footprint patch, splits by base texture (train / val / test, and
the held-out family as "ood"), trains with random 90-degree rotations and mirrorings (the
skin block is square and the tissue isotropic, so V changes under them only by mesh and sampling noise), keeps the checkpoint with the best
validation loss, stops early when it stops improving, and writes ``checkpoint.pt``,
``metrics.json`` (scores per split and per family), ``history.csv`` (losses per epoch) and
``predictions.csv`` (FEM and predicted V of every sample) to the output folder.

Multi-fidelity (``levels="all"``): every mesh level the FEM solved for a sample is a label row
(a ``default`` dataset holds each texture's ``coarse`` V too; ``extra_data`` adds files of the
same textures at finer fidelities, e.g. a ``fine`` build of the recipe's first N samples), the
network takes the row's contact spacing as an input, and the exported model answers at the
query spacing (default: the finest labelled). Scores are against the labels at that spacing.

    roughness train training-default.h5 --extra-data training-fine.h5 --levels all --out runs/mf

Spectral labels with FEM labels (a spectral dataset among the files, ``levels="all"``): the network
also takes the label's engine as an input (``RoughnessNet(engine_input=True)``) and answers as the FEM
at the query spacing; the files may hold other textures of the same physics, ``max_label_error`` keeps
only the FEM labels converged to that fraction, and ``fem_weight`` weighs their rows in the loss.

    roughness train training-v3.h5 --extra-data training-v2-default.h5 training-v2-fine.h5 --levels all \
        --max-label-error 0.03 --query-h-mm 0.14 --out runs/v3
"""
from __future__ import annotations

import math
import sys
import time
from contextlib import ExitStack
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
import torch

from roughness.core.errors import InputError
from roughness.core.files import check_output_folder
from roughness.dataset.digest import inputs_sha256
from roughness.dataset.reader import Dataset, open_dataset

from .config import TrainConfig
from .data import Samples, load_samples
from .evaluation import Evaluation, evaluate
from .metadata import ModelMetadata
from .network import RoughnessNet, parameter_count
from .patch import FOOTPRINT_MM, PATCH_PIXEL_MM
from .resume import RESUME_FILE, Progress, fingerprint, improves, restore, snapshot
from .run_files import save_torch, write_run
from .target import target


def augment(x: torch.Tensor, generator: torch.Generator) -> torch.Tensor:
    """A random element of the square's symmetry group (rotations, mirrors) per batch."""
    k = int(torch.randint(4, (1,), generator=generator))
    x = torch.rot90(x, k, dims=(2, 3))
    return x.flip(3) if bool(torch.randint(2, (1,), generator=generator)) else x


def format_scores(values: dict) -> str:
    """A split's scores with units: counts, Spearman and R² as numbers, errors and shares in percent."""
    percent = ("median_rel_err", "p95_rel_err", "out_of_domain")
    return "  ".join(f"{k} {100 * v:.1f}%" if k in percent else f"{k} {v}" if isinstance(v, int) else f"{k} {v:.3f}"
                     for k, v in values.items())


def train(cfg: TrainConfig, overwrite: bool = False, resume: bool = False) -> Path:
    """Train, evaluate and write the run folder ``cfg.out``; returns the checkpoint's path.

    Every finished epoch is saved to ``resume.pt`` in the folder: an interrupted run leaves it, and
    ``resume=True`` continues from it (same configuration and data; ``threads`` may differ) instead
    of starting over (without one, ``resume`` starts a new run). A finished run removes it, and a
    folder this call created is removed again if nothing was written into it.
    """
    resuming = resume and (Path(cfg.out) / RESUME_FILE).is_file()
    out = Path(cfg.out) if resuming else check_output_folder(cfg.out, overwrite)
    created = not out.exists()
    try:
        return _train(cfg, out, resuming)
    finally:
        if created and out.is_dir() and not any(out.iterdir()):
            out.rmdir()


def _train(cfg: TrainConfig, out: Path, resuming: bool) -> Path:
    torch.manual_seed(cfg.seed)
    torch.set_num_threads(cfg.threads)
    start = time.monotonic()

    # data: patches in mm (max 0) and log-V targets (one row per label level), split by base texture
    data = load_data(cfg)
    samples, query = data.samples, data.query_h_mm
    # rows of the training and validation splits; batches are gathered from the patches in place (no copy per split)
    tr, va = (torch.from_numpy(np.flatnonzero(samples.split == split)) for split in ("train", "val"))
    if len(tr) < cfg.batch_size or len(va) == 0:
        raise InputError(f"{cfg.data}: {len(tr)} training and {len(va)} validation samples are too few to train on: "
                         f"training needs at least {cfg.batch_size} training samples (the batch size) and one "
                         f"validation sample, about {cfg.minimum_samples(data.test_fraction)} ok samples in the "
                         "dataset", parameter="data")
    out.mkdir(parents=True, exist_ok=True)
    x, y = torch.from_numpy(samples.patches[:, None]), torch.from_numpy(target(samples.roughness, cfg.log_offset))
    h = torch.from_numpy(samples.h_mm.astype(np.float32)) if query is not None else None
    w = torch.from_numpy(np.where(samples.engine == "fem", cfg.fem_weight, 1.0).astype(np.float32))
    log(f"samples: {', '.join(f'{s} {int((samples.split == s).sum())}' for s in ('train', 'val', 'test', 'ood'))}")
    if query is not None:
        log(f"labels per contact spacing: {_rows_by_level(samples)}; the model answers at h = {query:g} mm")

    # model and optimiser: AdamW, linear warm-up then cosine decay to zero over max_epochs or the
    # time budget, whichever runs out first (a budget that ends the epochs early still anneals)
    model = RoughnessNet(cfg.widths, cfg.hidden, query, engine_input=len(data.engines) > 1)
    log(f"model: {parameter_count(model):,} parameters")
    optimizer = torch.optim.AdamW(model.parameters(), lr=cfg.learning_rate, weight_decay=cfg.weight_decay)
    steps_per_epoch = math.ceil(len(tr) / cfg.batch_size)
    total_steps, warmup = cfg.max_epochs * steps_per_epoch, 3 * steps_per_epoch
    progress, key = Progress(), fingerprint(cfg, data.data_sha256)
    epochs_start = time.monotonic()
    schedule = torch.optim.lr_scheduler.LambdaLR(optimizer, lambda s: lr_factor(
        s, total_steps, warmup, (time.monotonic() - epochs_start) / (60 * cfg.max_minutes)))
    generator = torch.Generator().manual_seed(cfg.seed)
    if resuming:
        progress = restore(out / RESUME_FILE, key, model, optimizer, schedule, generator, steps_per_epoch)
        epochs_start = time.monotonic() - progress.epochs_seconds  # the budget's clock goes on where it stopped
        log(f"resuming at epoch {progress.epoch} ({progress.epochs_seconds / 60:.1f} min of the budget used)")

    for epoch in range(progress.epoch, cfg.max_epochs):
        model.train()
        order, train_loss = torch.randperm(len(tr), generator=generator), 0.0
        for i in range(0, len(tr), cfg.batch_size):
            idx = tr[order[i:i + cfg.batch_size]]
            pred, _ = model(augment(x[idx], generator), None if h is None else h[idx])
            loss = weighted_mse(pred, y[idx], w[idx])
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            optimizer.step()
            schedule.step()
            train_loss += loss.item() * len(idx) / len(tr)

        val_loss = validation_loss(model, x, y, h, w, va)
        progress.epoch, progress.epochs_seconds = epoch + 1, time.monotonic() - epochs_start
        minutes = (progress.seconds + time.monotonic() - start) / 60
        progress.history.append((epoch, train_loss, val_loss, schedule.get_last_lr()[0], minutes))
        improved = improves(val_loss, progress.best_val)
        if improved:
            progress.best_val, progress.best_epoch = val_loss, epoch
            progress.best_state = {k: v.clone() for k, v in model.state_dict().items()}
        session = time.monotonic() - start  # this session's share of the totals, saved with them
        totals = replace(progress, seconds=progress.seconds + session,
                         core_seconds=progress.core_seconds + session * cfg.threads)
        save_torch(snapshot(key, totals, model, optimizer, schedule, generator), out / RESUME_FILE)
        log(f"epoch {epoch:3d}  train {train_loss:.4f}  val {val_loss:.4f}  lr {progress.history[-1][3]:.2e}  "
            f"{minutes:5.1f} min{'  *' if improved else ''}")
        if epoch - progress.best_epoch >= cfg.patience:
            log(f"early stop: no better validation loss for {cfg.patience} epochs")
            break
        if progress.epochs_seconds > 60 * cfg.max_minutes:
            log(f"time budget of {cfg.max_minutes} min reached")
            break

    # the best epoch's network, scored on every split (multi-fidelity: against the labels at the query spacing)
    model.load_state_dict(progress.best_state)
    evaluation = evaluate(model, samples, query, cfg.log_offset)
    for split, values in evaluation.metrics.items():
        log(f"{split:5s} {format_scores(values)}")
    meta = run_metadata(cfg, data, evaluation, progress, parameter_count(model), time.monotonic() - start)
    checkpoint = write_run(out, model, meta, progress.history, evaluation)
    (out / RESUME_FILE).unlink(missing_ok=True)
    log(f"wrote {checkpoint} (best epoch {progress.best_epoch}, {meta.minutes:.1f} min)")
    return checkpoint


@dataclass
class TrainingData:
    """The label rows of a run's dataset files, and what the model's metadata records of them."""

    samples: Samples
    simulation: dict  # the physics of the labels the model answers as
    recipe: dict  # the primary file's recipe
    holdout: str | None  # families never trained on (comma-separated), or None
    test_fraction: float
    data_sha256: list[str]  # inputs checksum of each file, the primary first
    fem_seconds: float  # core-seconds the labels' simulations took
    engines: list[str]  # engines of the labels ("fem", "spectral")
    query_h_mm: float | None  # contact spacing (mm) the model answers for; None: single-level labels


def load_data(cfg: TrainConfig) -> TrainingData:
    """The label rows of ``cfg.data`` and ``cfg.extra_data``, split by base texture; InputError if the files
    label under other physics or the labels cannot teach the model asked for."""
    data_sha256 = [inputs_sha256(path) for path in (cfg.data, *cfg.extra_data)]
    with ExitStack() as stack:
        data = stack.enter_context(open_dataset(cfg.data))
        extras = [stack.enter_context(open_dataset(path)) for path in cfg.extra_data]
        recipe = data.config.recipe
        # the physics of the labels the model answers as: the first FEM file's (the spectral engine's records no mesh)
        simulation = next((ds.config.simulation for ds in [data, *extras] if ds.config.simulation.get(
            "engine", "fem") == "fem"), data.config.simulation)
        for extra in extras:
            _require_same_physics(data, extra)
        fem_seconds = float(sum(np.nansum(ds.table()["seconds"]) for ds in [data, *extras]))  # one core each
        holdout = recipe.get("holdout_family") if cfg.holdout_family is None else cfg.holdout_family
        holdout = None if holdout == "none" else holdout
        test_fraction = recipe.get("test_fraction", 0.1) if cfg.test_fraction is None else cfg.test_fraction
        samples = load_samples([data, *extras], test_fraction, cfg.val_fraction, holdout, levels=cfg.levels,
                               max_label_error=cfg.max_label_error)
    multi = cfg.levels == "all"
    engines = sorted(set(samples.engine))
    if len(engines) > 1 and not multi:
        raise InputError("spectral and FEM labels are learned together only with levels='all' (the engine is an "
                         "input then)", parameter="levels")
    if multi and np.isnan(samples.h_mm).all():
        raise InputError("levels='all' needs FEM labels at the query spacing; these files hold spectral labels "
                         "only", parameter="levels")
    query = (cfg.query_h_mm or float(np.nanmin(samples.h_mm))) if multi else None
    if multi and not np.isclose(samples.h_mm, query).any():
        raise InputError(f"no label at the query spacing {query} mm (labels at "
                         f"{', '.join(f'{h:g}' for h in np.unique(samples.h_mm))} mm)", parameter="query_h_mm")
    return TrainingData(samples, simulation, recipe, holdout, test_fraction, data_sha256, fem_seconds, engines, query)


def run_metadata(cfg: TrainConfig, data: TrainingData, evaluation: Evaluation, progress: Progress, parameters: int,
                 session_seconds: float) -> ModelMetadata:
    """The finished run's metadata: network, labels, scores, input domain, epochs and cost (``session_seconds``:
    this session's wall clock; earlier sessions' are in ``progress``)."""
    query = data.query_h_mm
    extra_data = [{"file": Path(p).name, "inputs_sha256": sha} for p, sha in zip(cfg.extra_data, data.data_sha256[1:])]
    return ModelMetadata(
        widths=tuple(cfg.widths), hidden=cfg.hidden, patch_pixel_mm=PATCH_PIXEL_MM, footprint_mm=FOOTPRINT_MM,
        log_offset=cfg.log_offset, simulation=data.simulation,
        label_fidelity=_fidelity_name(query) if query is not None else data.simulation.get("fidelity", "default"),
        domain=evaluation.domain.to_dict(), metrics=evaluation.metrics, test_by_family=evaluation.by_family,
        holdout_family=data.holdout, test_fraction=data.test_fraction,
        data={"file": Path(cfg.data).name, "recipe": data.recipe.get("name"), "inputs_sha256": data.data_sha256[0]},
        train_config=asdict(cfg) | {"widths": list(cfg.widths), "extra_data": list(cfg.extra_data)},
        best_epoch=progress.best_epoch, epochs=len(progress.history),
        minutes=(progress.seconds + session_seconds) / 60, parameters=parameters,
        cost_core_seconds={"data_fem": data.fem_seconds,
                           "training": progress.core_seconds + session_seconds * cfg.threads},
        multi_fidelity={"query_h_mm": query, "rows_by_h_mm": _rows_by_level(data.samples), "engines": data.engines,
                        "extra_data": extra_data} if query is not None else None)


@torch.no_grad()
def validation_loss(model: RoughnessNet, x: torch.Tensor, y: torch.Tensor, h: torch.Tensor | None, w: torch.Tensor,
                    rows: torch.Tensor, batch: int = 512) -> float:
    """``weighted_mse`` over ``rows``, in batches (a whole validation split at once is gigabytes of activations)."""
    model.eval()
    total = 0.0
    for i in range(0, len(rows), batch):
        idx = rows[i:i + batch]
        pred, _ = model(x[idx], None if h is None else h[idx])
        total += float((w[idx] * (pred - y[idx]) ** 2).sum())
    return total / float(w[rows].sum())


def weighted_mse(predicted: torch.Tensor, target_: torch.Tensor, weight: torch.Tensor) -> torch.Tensor:
    """Mean of weight x squared error over the rows, normalised by the weights."""
    return (weight * (predicted - target_) ** 2).sum() / weight.sum()


def lr_factor(step: int, total_steps: int, warmup: int, elapsed_fraction: float) -> float:
    """The learning rate's factor at optimiser ``step``: a linear warm-up over ``warmup`` steps, then a cosine
    from 1 to 0 over the steps or the time budget (``elapsed_fraction`` of it used), whichever runs out first."""
    progress = min(max(step / total_steps, elapsed_fraction), 1.0)
    return min((step + 1) / warmup, 0.5 * (1 + math.cos(math.pi * progress)))


def _require_same_physics(data: Dataset, extra: Dataset) -> None:
    """``extra`` labels textures under the same physics as ``data``: other textures (recipes), mesh fidelities
    and engines are allowed, other forces, tissues or strain statistics are not."""
    from roughness.dataset.build import MESH_FIELDS

    allowed = ("recipe.", *(f"simulation.{k}:" for k in (*MESH_FIELDS, "engine", "engine_version")))
    differences = [d for d in data.config.differences(extra.config).split("; ") if d and not d.startswith(allowed)]
    if differences:
        raise InputError(f"{extra.path} does not label textures under the physics of {data.path}: "
                         f"{'; '.join(differences)}", parameter="extra_data")


def _rows_by_level(samples) -> dict[str, int]:
    """Number of label rows per contact spacing (mm, as text; "spectral" for the spectral engine's)."""
    names = np.array(["spectral" if np.isnan(h) else f"{h:g}" for h in samples.h_mm])
    values, counts = np.unique(names, return_counts=True)
    return {str(h): int(c) for h, c in zip(values, counts)}


def _fidelity_name(h_mm: float) -> str:
    """The fidelity whose contact spacing is ``h_mm``, else ``h=<h> mm``."""
    from roughness.simulate.config import FIDELITY_SPACING_MM

    return next((name for name, h in FIDELITY_SPACING_MM.items() if np.isclose(h, h_mm)), f"h={h_mm:g} mm")


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)

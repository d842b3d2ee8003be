"""A trained network against its labels: its input domain, fitted on the training inputs, and its scores per
split and per family of the held-out textures (what a training run's metrics.json and predictions.csv hold)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from .data import Samples
from .domain import Domain
from .metrics import scores
from .network import RoughnessNet
from .target import LOG_OFFSET, roughness_from_log

SPLITS = ("train", "val", "test", "ood")


@dataclass
class Evaluation:
    """The network's answers on the scored rows (multi-fidelity: the labels at the query spacing)."""

    scored: Samples  # the label rows scored
    predicted: np.ndarray  # V per scored row
    flagged: np.ndarray  # per scored row: outside the input domain
    domain: Domain  # fitted on the training split's inputs
    metrics: dict[str, dict]  # split -> scores (with the share flagged out of domain)
    by_family: dict[str, dict]  # family -> scores on the test split


@torch.no_grad()
def infer(model: RoughnessNet, patches: np.ndarray, log_offset: float = LOG_OFFSET,
          batch: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """Predicted V and embeddings for patches (n, P, P) of a network that predicts log(V + log_offset)."""
    model.eval()
    logs, embeddings = [], []
    for i in range(0, len(patches), batch):
        log_v, emb = model(torch.from_numpy(patches[i:i + batch, None]))
        logs.append(log_v.numpy())
        embeddings.append(emb.numpy())
    return roughness_from_log(np.concatenate(logs), log_offset), np.concatenate(embeddings)


def evaluate(model: RoughnessNet, samples: Samples, query_h_mm: float | None, log_offset: float) -> Evaluation:
    """Fit the network's input domain on the training inputs (each texture once) and score its answers (at the
    query spacing ``query_h_mm`` in mm, None: a single-level model) on every split."""
    ids, first = np.unique(samples.ids, return_index=True)  # rows of one texture share its patch
    answers, codes = infer(model, samples.patches[first], log_offset)  # at the query spacing
    trained = samples.split[first] == "train"
    domain = Domain.fit(samples.descriptors[first][trained], codes[trained])
    scored = samples if query_h_mm is None else samples.at_level(query_h_mm)
    row = np.searchsorted(ids, scored.ids)
    predicted, embeddings = answers[row], codes[row]
    flagged = np.array([bool(r) for r in domain.check(scored.descriptors, embeddings)])
    metrics = {}
    for split in SPLITS:
        part = scored.split == split
        if part.any():
            metrics[split] = scores(scored.roughness[part], predicted[part]) | {"out_of_domain": float(flagged[part].mean())}
    test = scored.split == "test"
    by_family = {f: scores(scored.roughness[test & (scored.family == f)], predicted[test & (scored.family == f)])
                 for f in np.unique(scored.family[test])}
    return Evaluation(scored, predicted, flagged, domain, metrics, by_family)

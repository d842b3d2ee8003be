"""Accuracy of predicted V against FEM V: rank correlation, R^2 on log V, relative errors."""
from __future__ import annotations

import numpy as np
from scipy.stats import spearmanr


def scores(reference: np.ndarray, predicted: np.ndarray) -> dict:
    """Spearman, R^2 of log V and median / p95 relative error over samples with reference V > 0.

    Samples with reference V = 0 (flat textures) have no relative error or log; they are counted
    in ``n_zero`` and left out of the other numbers.
    """
    ref, pred = np.asarray(reference, float), np.asarray(predicted, float)
    if ref.shape != pred.shape or ref.ndim != 1:
        raise ValueError(f"reference and predicted must be equal-length 1-D arrays, got {ref.shape} and {pred.shape}")
    keep = ref > 0
    ref, pred = ref[keep], pred[keep]
    out = {"n": int(keep.sum()), "n_zero": int((~keep).sum())}
    if len(ref) < 3:
        return out
    rel = np.abs(pred - ref) / ref
    log_ref, log_pred = np.log(ref), np.log(np.maximum(pred, 1e-12))
    r2 = 1 - np.sum((log_pred - log_ref) ** 2) / np.sum((log_ref - log_ref.mean()) ** 2)
    return out | {"spearman": float(spearmanr(ref, pred).statistic), "r2_log": float(r2),
                  "median_rel_err": float(np.median(rel)), "p95_rel_err": float(np.percentile(rel, 95))}

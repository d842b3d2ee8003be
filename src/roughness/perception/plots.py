"""Figures in the style of the paper's Figs. 9, 10, 17 and 18.

Each function returns a ``matplotlib.figure.Figure`` (made without pyplot: a notebook's backend is left as
it was) and writes it as PNG to ``path`` if one is given.
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.figures import new_figure, save_figure

from .analysis import EmbeddingAnalysis
from .fit import Fit, r_text

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _figure(width: float = 6.4, height: float = 4.0, cols: int = 1):
    fig = new_figure(figsize=(width, height))
    return fig, fig.subplots(1, cols)


def _save(fig: Figure, path: str | Path | None) -> Figure:
    fig.tight_layout()
    return save_figure(fig, path, 110)


def plot_embedding(analysis: EmbeddingAnalysis, path: str | Path | None = None) -> Figure:
    """Fig. 9: every stimulus on the 1-D perceptual axis with its bootstrap 5-95% interval."""
    fig, ax = _figure(6.4, max(3.0, 0.17 * len(analysis.stimuli) + 1.0))
    order = np.argsort(analysis.coordinate)
    y = np.arange(len(order))
    x = analysis.coordinate[order]
    if analysis.low is not None:  # a percentile interval need not contain the full-data estimate
        ax.hlines(y, analysis.low[order], analysis.high[order], color="C0", lw=1.5, label="5-95% bootstrap interval")
    ax.plot(x, y, "o", ms=3, color="k", label="embedding of all trials")
    ax.legend(loc="lower right", fontsize=8)
    ax.set_yticks(y, [analysis.stimuli[i] for i in order], fontsize=7)
    units = "noise SDs" if analysis.scale == "thurstone" else "embedding units"
    ax.set_xlabel(f"perceptual coordinate ({units}; rough to the right)")
    ax.set_ylabel("stimulus")
    ax.set_title(f"1-D Thurstone scale (start: SDP at lambda = {analysis.fit.lam:.3g})" if analysis.scale == "thurstone"
                 else f"1-D embedding, lambda = {analysis.fit.lam:.3g}")
    return _save(fig, path)


def plot_cross_validation(analysis: EmbeddingAnalysis, path: str | Path | None = None) -> Figure:
    """Fig. 10: train and held-out triplet error against lambda (left), eigenvalue spectrum (right)."""
    fig, (left, right) = _figure(9.0, 3.6, cols=2)
    if analysis.cv is not None:
        cv = analysis.cv
        sem = cv.test_error.std(axis=1, ddof=1) / np.sqrt(cv.test_error.shape[1])
        left.plot(cv.lambdas, cv.train_error.mean(axis=1), "o-", label="training")
        left.errorbar(cv.lambdas, cv.test_error.mean(axis=1), yerr=sem, fmt="s-", capsize=2, label="held out")
        left.axvline(cv.best_lambda, color="grey", ls="--", lw=1, label=f"chosen {cv.best_lambda:.3g}")
        left.set_xscale("log")
        left.legend(fontsize=8)
    left.set_xlabel("regulariser lambda (trace weight)")
    left.set_ylabel("triplet error (fraction wrong)")
    left.set_title(f"{analysis.cv.test_error.shape[1]}-fold cross-validation" if analysis.cv else "no cross-validation")
    spectrum = analysis.fit.eigenvalues
    shown = spectrum[: min(10, len(spectrum))]
    right.bar(np.arange(1, len(shown) + 1), shown / max(spectrum.sum(), 1e-300))
    right.set_xlabel("dimension")
    right.set_ylabel("eigenvalue / trace")
    right.set_title("spectrum of the embedding")
    return _save(fig, path)


def plot_fit(fit: Fit, path: str | Path | None = None) -> Figure:
    """Fig. 17: V of every stimulus against its perceptual coordinate (excluded stimuli hollow)."""
    fig, ax = _figure(6.0, 4.5)
    v = fit.roughness
    se = np.array([s.roughness_stderr for s in fit.values])
    if np.all(np.isfinite(fit.low)):
        ax.hlines(v, fit.low, fit.high, color="0.6", lw=0.8)
    if np.all(np.isfinite(se)):
        ax.vlines(fit.coordinate, v - se, v + se, color="0.6", lw=0.8)
    keep = fit.included
    ax.plot(fit.coordinate[keep], v[keep], "o", color="C0", label="included")
    if not np.all(keep):
        ax.plot(fit.coordinate[~keep], v[~keep], "o", mfc="none", color="C3", label="excluded")
    for i, name in enumerate(fit.stimuli):
        ax.annotate(name, (fit.coordinate[i], v[i]), fontsize=6, xytext=(3, 2), textcoords="offset points")
    c = fit.correlations()["V"]
    title = f"R = {r_text(c['all']['pearson'])} (all)"
    if not np.all(keep):
        title += f", {r_text(c['included']['pearson'])} (included)"
    ax.set_title(title)
    ax.set_xlabel("perceptual coordinate (embedding units)")
    ax.set_ylabel(f"strain variation V ({fit.values[0].engine}; dimensionless)")
    ax.legend(fontsize=8)
    return _save(fig, path)


def plot_sampling(fit: Fit, path: str | Path | None = None) -> Figure:
    """Fig. 18: Pearson R over the pair sampling (d, r), and over force if re-fitted."""
    cols = 2 if fit.forces else 1
    fig, axes = _figure(5.2 * cols, 4.0, cols=cols)
    axes = np.atleast_1d(axes)
    s = fit.sampling
    ax = axes[0]
    finite = s.pearson[np.isfinite(s.pearson)]
    image = ax.imshow(s.pearson.T, origin="lower", aspect="auto", vmin=min(0.5, *finite), vmax=1.0,
                      cmap="viridis")  # one cell per grid value (the grid need not be evenly spaced)
    for i in range(len(s.distances_mm)):
        for j in range(len(s.radii_mm)):
            if np.isfinite(s.pearson[i, j]):
                ax.text(i, j, f"{s.pearson[i, j]:.2f}", ha="center", va="center", fontsize=7, color="w")
    ax.set_xticks(range(len(s.distances_mm)), [f"{d:g}" for d in s.distances_mm])
    ax.set_yticks(range(len(s.radii_mm)), [f"{r:g}" for r in s.radii_mm])
    fig.colorbar(image, ax=ax, label="Pearson R of V with the embedding")
    ax.set_xlabel("pair distance d (mm)")
    ax.set_ylabel("disk radius r (mm)")
    ax.set_title("R over the sampling (blank: disks do not fit)")
    if fit.forces:
        corr = fit.force_correlations()
        forces = sorted(fit.forces)
        r = [corr[f"{f:g}"]["pearson"] for f in forces]
        defined = [x for x in r if x is not None]
        axes[1].plot(forces, [np.nan if x is None else x for x in r], "o-")
        axes[1].set_ylim(min(0.5, *(x - 0.05 for x in defined)), 1.0)
        axes[1].set_xlabel("normal force (N)")
        axes[1].set_ylabel("Pearson R of V with the embedding")
        axes[1].set_title("R over force")
    return _save(fig, path)

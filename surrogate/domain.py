"""Input domain of a trained surrogate: descriptor ranges and a learned (Mahalanobis) score.

An input is in domain when each hand-made descriptor (``patch.DESCRIPTOR_NAMES``) lies within
the range seen in training (widened by a margin) and the Mahalanobis distance of its network
embedding from the training embeddings is below the training set's ``quantile``. Numpy only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .patch import DESCRIPTOR_NAMES


@dataclass(frozen=True)
class Domain:
    low: np.ndarray  # descriptor lower bounds
    high: np.ndarray  # descriptor upper bounds
    mean: np.ndarray  # embedding mean
    precision: np.ndarray  # inverse (shrunk) embedding covariance
    threshold: float  # Mahalanobis distance limit

    @classmethod
    def fit(cls, descriptors: np.ndarray, embeddings: np.ndarray, quantile: float = 0.995,
            margin: float = 0.05) -> Domain:
        """Domain of training inputs: descriptor quantiles widened by ``margin`` of their span (not below 0)."""
        from sklearn.covariance import LedoitWolf

        lo, hi = np.quantile(descriptors, [1 - quantile, quantile], axis=0)
        pad = margin * (hi - lo)
        cov = LedoitWolf().fit(embeddings)
        domain = cls(np.maximum(lo - pad, 0.0), hi + pad, cov.location_, cov.precision_, np.inf)  # descriptors >= 0
        threshold = float(np.quantile(domain.distance(embeddings), quantile))
        return cls(domain.low, domain.high, domain.mean, domain.precision, threshold)

    def distance(self, embeddings: np.ndarray) -> np.ndarray:
        """Mahalanobis distance of each embedding row from the training embeddings."""
        d = np.asarray(embeddings, float) - self.mean
        return np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", d, self.precision, d), 0.0))

    def check(self, descriptors: np.ndarray, embeddings: np.ndarray) -> list[list[str]]:
        """Per input, the reasons it is out of domain (empty list: in domain)."""
        reasons: list[list[str]] = []
        for desc, dist in zip(np.atleast_2d(descriptors), self.distance(np.atleast_2d(embeddings))):
            why = [f"{name} {v:.3g} outside the training range {lo:.3g}..{hi:.3g}"
                   for name, v, lo, hi in zip(DESCRIPTOR_NAMES, desc, self.low, self.high) if not lo <= v <= hi]
            if not dist <= self.threshold:
                why.append(f"shape score {dist:.3g} above the training limit {self.threshold:.3g}")
            reasons.append(why)
        return reasons

    def to_dict(self) -> dict:
        return {"descriptors": list(DESCRIPTOR_NAMES), "low": self.low.tolist(), "high": self.high.tolist(),
                "mean": self.mean.tolist(), "precision": self.precision.tolist(), "threshold": self.threshold}

    @classmethod
    def from_dict(cls, data: dict) -> Domain:
        if tuple(data["descriptors"]) != DESCRIPTOR_NAMES:
            raise ValueError(f"model domain has descriptors {data['descriptors']}, this code {DESCRIPTOR_NAMES}")
        return cls(*(np.asarray(data[k], float) for k in ("low", "high", "mean", "precision")),
                   float(data["threshold"]))

"""The network's target: log(V + LOG_OFFSET), and its inverse (the only place V is recovered from it)."""
from __future__ import annotations

import numpy as np

LOG_OFFSET = 1e-3  # the network predicts log(V + LOG_OFFSET): finite for flat textures (V = 0)


def target(roughness: np.ndarray, log_offset: float = LOG_OFFSET) -> np.ndarray:
    """Network target (float32) log(V + log_offset) from V."""
    return np.log(np.asarray(roughness, dtype=np.float64) + log_offset).astype(np.float32)


def roughness_from_log(log_v: np.ndarray, log_offset: float = LOG_OFFSET) -> np.ndarray:
    """V (float64, >= 0) from the network's output log(V + log_offset)."""
    return np.maximum(np.exp(np.asarray(log_v, dtype=np.float64)) - log_offset, 0.0)

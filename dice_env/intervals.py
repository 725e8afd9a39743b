"""Confidence intervals of proportions, shared by the studies, the agents and the benchmarks."""

from __future__ import annotations

import numpy as np

Z95 = 1.959964  # two-sided 95% normal quantile


def wilson(count: np.ndarray | float, total: np.ndarray | float, z: float = Z95) -> np.ndarray:
    """Wilson score intervals of ``count / total``, shape (..., 2); (0, 1) where total is 0.

    ``total`` may be an effective sample size (not an integer). Each interval holds the
    proportion itself (rounding never puts an end a hair inside it) and lies in [0, 1].
    """
    count, total = np.broadcast_arrays(np.asarray(count, float), np.asarray(total, float))
    n = np.where(total > 0, total, 1.0)
    p = np.where(total > 0, count / n, 0.5)
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    low = np.where(total > 0, np.clip(np.minimum(p, centre - half), 0.0, 1.0), 0.0)
    high = np.where(total > 0, np.clip(np.maximum(p, centre + half), 0.0, 1.0), 1.0)
    return np.stack([low, high], axis=-1)


def wilson_bounds(count: float, total: float, z: float = Z95) -> tuple[float, float]:
    """One Wilson interval as two floats (for JSON and tables)."""
    low, high = wilson(count, total, z).tolist()
    return low, high

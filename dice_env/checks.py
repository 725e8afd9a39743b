"""Input checks that fail with a message naming the parameter and the allowed range."""

from __future__ import annotations

import math

import numpy as np


def check_finite(name: str, value: float | np.ndarray) -> None:
    """Raise ``ValueError`` unless every entry of ``value`` is finite."""
    if not np.all(np.isfinite(np.asarray(value, dtype=np.float64))):
        raise ValueError(f"{name} must be finite (no NaN or inf), got {value!r}")


def check_positive(name: str, value: float) -> None:
    """Raise ``ValueError`` unless ``value`` is a finite number > 0."""
    if not _is_real(value) or not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


def check_nonnegative(name: str, value: float) -> None:
    """Raise ``ValueError`` unless ``value`` is a finite number >= 0."""
    if not _is_real(value) or not math.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")


def check_range(
    name: str, value: float, low: float, high: float, *, high_open: bool = False
) -> None:
    """Raise ``ValueError`` unless ``low <= value <= high`` (``< high`` if ``high_open``)."""
    ok = _is_real(value) and math.isfinite(value) and low <= value
    ok = ok and (value < high if high_open else value <= high)
    if not ok:
        bracket = ")" if high_open else "]"
        raise ValueError(f"{name} must be in [{low}, {high}{bracket}, got {value!r}")


def as_floats(name: str, value: object) -> np.ndarray:
    """``value`` as a float64 array, or ``ValueError`` naming ``name`` if it holds no numbers."""
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be an array of numbers, got {value!r}") from error


def as_batch(name: str, value: np.ndarray, tail: tuple[int, ...]) -> np.ndarray:
    """Return ``value`` as a finite float64 array of shape ``(B, *tail)`` (adds a batch axis)."""
    array = as_floats(name, value)
    if array.shape == tail:
        array = array[None]
    if array.ndim != len(tail) + 1 or array.shape[1:] != tail:
        raise ValueError(f"{name} must have shape {tail} or (B, {', '.join(map(str, tail))}), "
                         f"got {array.shape}")
    check_finite(name, array)
    return np.ascontiguousarray(array)


def _is_real(value: object) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)

"""Input checks that fail with a message naming the parameter and the allowed range."""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Iterable
from enum import Enum, IntEnum

import numpy as np


def check_finite(name: str, value: float | np.ndarray) -> None:
    """Raise ``ValueError`` unless every entry of ``value`` is finite."""
    if not np.all(np.isfinite(np.asarray(value, dtype=np.float64))):
        raise ValueError(f"{name} must be finite (no NaN or inf), got {value!r}")


def check_positive(name: str, value: float) -> None:
    """Raise ``ValueError`` unless ``value`` is a finite number > 0."""
    _check_number(name, value, lambda v: v > 0, "a finite number > 0")


def check_nonnegative(name: str, value: float) -> None:
    """Raise ``ValueError`` unless ``value`` is a finite number >= 0."""
    _check_number(name, value, lambda v: v >= 0, "a finite number >= 0")


def check_range(name: str, value: float, low: float, high: float, *, low_open: bool = False,
                high_open: bool = False) -> None:
    """Raise ``ValueError`` unless ``low <= value <= high`` (``<`` at an open end)."""
    interval = f"{'(' if low_open else '['}{low}, {high}{')' if high_open else ']'}"
    _check_number(name, value, lambda v: (low < v if low_open else low <= v)
                  and (v < high if high_open else v <= high), f"in {interval}")


def check_int(name: str, value: object, low: int, high: int | None = None, *,
              also: str = "") -> int:
    """``value`` as an int (not a bool) in ``[low, high]``, else a ``ValueError`` naming ``name``.

    No ``high``: ``>= low``; ``also`` is added to the allowed range in the message.
    """
    if (not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < low
            or (high is not None and value > high)):
        allowed = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ValueError(f"{name} must be an int {allowed}{also}, got {value!r}")
    return int(value)


def check_bool(name: str, value: object) -> None:
    """Raise ``TypeError`` unless ``value`` is a bool (Python's or numpy's)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be a bool, got {value!r}")


def check_type(name: str, value: object, kind: type) -> None:
    """Raise ``TypeError`` unless ``value`` is a ``kind``."""
    if not isinstance(value, kind):
        raise TypeError(f"{name} must be a {kind.__name__}, got {type(value).__name__}")


def check_choice(name: str, value: object, choices: Iterable[object], *, also: str = "") -> None:
    """Raise ``ValueError`` unless ``value`` is one of ``choices`` (``also``: what else is)."""
    choices = tuple(choices)
    if not isinstance(value, Hashable) or value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}{also}, got "
                         f"{value!r}")


def as_enum(name: str, kind: type[IntEnum], value: object) -> IntEnum:
    """``value`` as a member of ``kind``: a member, its name (any case) or its int value.

    A member of another enum is refused, whatever its value (``ValueError``).
    """
    if isinstance(value, kind):
        return value
    if isinstance(value, str) and value.upper() in kind.__members__:
        return kind[value.upper()]
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, Enum)) \
            and value in kind._value2member_map_:
        return kind(value)
    names = ", ".join(repr(m.name.lower()) for m in kind)
    raise ValueError(f"{name} must be a {kind.__name__} or one of {names}, got {value!r}")


def as_floats(name: str, value: object) -> np.ndarray:
    """``value`` as a float64 array, or ``ValueError`` naming ``name`` if it holds no numbers."""
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be an array of numbers, got {value!r}") from error


def as_shaped(name: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a finite float64 array of ``shape``, or ``ValueError`` naming ``name``."""
    array = as_floats(name, value)
    if array.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {array.shape}")
    check_finite(name, array)
    return array


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


def _check_number(name: str, value: object, ok: Callable[[float], bool], allowed: str) -> None:
    real = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
    if not (real and math.isfinite(value) and ok(value)):
        raise ValueError(f"{name} must be {allowed}, got {value!r}")

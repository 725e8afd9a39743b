"""Scenes, dice and die contacts as JSON data, and back, exactly.

:func:`to_data` writes one of :data:`TYPES` as ``{"type": name, field: value, ...}`` (floats
exact, enums by name); :func:`from_data` builds it again through its own checks, so
``from_data(to_data(x)) == x`` and edited nonsense is refused as the constructor refuses it.
"""

from __future__ import annotations

import dataclasses
from enum import Enum
from typing import Any

from dice_env.model.checks import check_choice
from dice_env.model.die import Die
from dice_env.model.scene import Ground, Rest, Scene, Wall
from dice_env.simulation.group import DieContact

TYPES: dict[str, type] = {kind.__name__: kind
                          for kind in (Scene, Die, Ground, Wall, Rest, DieContact)}


def to_data(value: Any) -> Any:
    """``value`` (one of :data:`TYPES`, or a tuple, enum or number of theirs) as JSON data."""
    if type(value).__name__ in TYPES and dataclasses.is_dataclass(value):
        fields = {f.name: to_data(getattr(value, f.name)) for f in dataclasses.fields(value)}
        return {"type": type(value).__name__, **fields}
    if isinstance(value, Enum):
        return value.name
    if isinstance(value, (tuple, list)):
        return [to_data(v) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"value must be one of {', '.join(TYPES)} or their fields' values, got "
                    f"{type(value).__name__}")


def from_data(data: Any) -> Any:
    """The object :func:`to_data` wrote as ``data``, lists as tuples; ``ValueError`` if unknown."""
    if isinstance(data, dict):
        fields = dict(data)
        name = fields.pop("type", None)
        check_choice("data's type", name, TYPES)
        kind = TYPES[name]
        known = {f.name for f in dataclasses.fields(kind)}
        if set(fields) != known:
            raise ValueError(f"a {name}'s data must hold the fields {sorted(known)}, got "
                             f"{sorted(fields)}")
        values = {key: from_data(value) for key, value in fields.items()}
        return kind.from_fields(**values) if kind is Die else kind(**values)
    if isinstance(data, list):
        return tuple(from_data(v) for v in data)
    return data

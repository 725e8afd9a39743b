"""Named tasks: DiceThrow-v0 and the ids beside it, each the same env with a few keywords fixed.

``gym.make(task.id)`` is ``gym.make("DiceThrow-v0", **task.keywords)`` (the keywords are the
registered ``kwargs``; keywords given to ``gym.make`` override them). In :data:`TASKS`, easiest
first (by the oracle's margin over chance, ``docs/environment.md``):

- ``DiceThrow-v0``: no keyword (a d6 from 1.5 cm, 5 % hand noise).
- ``DiceThrowHigh-v0``: ``release_height=0.15``, ``hand_noise=0.01``,
  ``orientation_noise=0.01``, ``until="decided"``.
- ``DiceThrowD20-v0``: ``die="d20"``, ``until="decided"``.
- ``DiceThrowTray2d6Sum-v0``: ``num_dice=2``, ``target="sum"``, ``walls="tray"``,
  ``until="decided"``.
- ``DiceThrowCraps-v0``: ``num_dice=2``, ``set_dice=True``, ``target="avoid_sum"``,
  ``target_sum=7``, ``walls="craps"``, ``release_height=0.12``, ``max_speed=4.0``,
  ``t_max=10.0``, ``hand_noise=0.001``, ``orientation_noise=0.001``, ``until="decided"`` and
  the craps layout's table (:data:`CRAPS_TABLE`: ``stiffness``, ``damping``, ``friction``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from dice_env.model import materials

_LAYOUT = materials.ground("craps")
# The craps layout's cloth over padding (materials.MATERIALS["craps"]) for the default die.
CRAPS_TABLE = MappingProxyType({"stiffness": _LAYOUT.stiffness, "damping": _LAYOUT.damping,
                                "friction": _LAYOUT.friction})


@dataclass(frozen=True)
class NamedTask:
    """A registered id: DiceThrow-v0 with ``keywords`` fixed; ``description``: one line."""

    id: str
    keywords: Mapping[str, Any]
    description: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "keywords", MappingProxyType(dict(self.keywords)))


TASKS = (
    NamedTask("DiceThrow-v0", {},
              "a d6 placed from 1.5 cm above the table for a drawn face: the easiest"),
    NamedTask("DiceThrowHigh-v0",
              {"release_height": 0.15, "hand_noise": 0.01, "orientation_noise": 0.01,
               "until": "decided"},
              "a d6 from 15 cm with a steady hand: it bounces and tumbles before it rests"),
    NamedTask("DiceThrowD20-v0", {"die": "d20", "until": "decided"},
              "a d20 from just above the table for one of 20 faces: rounder, it rolls on"),
    NamedTask("DiceThrowTray2d6Sum-v0",
              {"num_dice": 2, "target": "sum", "walls": "tray", "until": "decided"},
              "two d6 from one hand into a 30 x 20 cm tray for a drawn total 2 … 12"),
    NamedTask("DiceThrowCraps-v0",
              {"num_dice": 2, "set_dice": True, "target": "avoid_sum", "target_sum": 7,
               "walls": "craps", "release_height": 0.12, "max_speed": 4.0, "t_max": 10.0,
               "hand_noise": 0.001, "orientation_noise": 0.001, "until": "decided", **CRAPS_TABLE},
              "two d6, set in the hand, thrown 1 m into the craps table's back wall, "
              "avoiding a seven, with a dice setter's steadiness"),
)

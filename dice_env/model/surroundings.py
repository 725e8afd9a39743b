"""Preset surroundings: the walls of a dice tray and of a craps table, around the origin.

Each returns a tuple of :class:`~dice_env.model.scene.Wall` for ``Scene(walls=...)``; the
``material`` keywords (``stiffness``, ``damping``, ...) default to the table's.
"""

from __future__ import annotations

from dice_env.model.checks import check_choice, check_positive
from dice_env.model.scene import Wall

TRAY = (0.30, 0.20)  # a common felt-lined dice tray, inside (m)
CRAPS = (1.0, 0.6)  # a craps table's throw, scaled: 1 m to the back wall, sides 0.6 m apart


def tray(length: float = TRAY[0], width: float = TRAY[1], **material: float) -> tuple[Wall, ...]:
    """Four walls around the origin: ``length`` (m) along x by ``width`` (m) along y."""
    check_positive("length", length)
    back, *sides = craps(length / 2, width, **material)
    return back, Wall.through((-length / 2, 0, 0), (1, 0, 0), **material), *sides


def craps(distance: float = CRAPS[0], width: float = CRAPS[1],
          **material: float) -> tuple[Wall, ...]:
    """A craps table: a back wall ``distance`` (m) ahead along +x, side walls ``width`` (m) apart.

    Open behind the thrower.
    """
    check_positive("distance", distance)
    check_positive("width", width)
    y = width / 2
    return (Wall.through((distance, 0, 0), (-1, 0, 0), **material),
            Wall.through((0, y, 0), (0, -1, 0), **material),
            Wall.through((0, -y, 0), (0, 1, 0), **material))


WALLS = {"none": lambda **material: (), "tray": tray, "craps": craps}


def walls(name: str, **material: float) -> tuple[Wall, ...]:
    """The preset ``name`` (``"none"``, ``"tray"`` or ``"craps"``) with its default sizes."""
    check_choice("walls", name, WALLS)
    return WALLS[name](**material)

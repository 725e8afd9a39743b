"""Preset surroundings: the walls of a dice tray and of a craps table.

Every preset returns a tuple of :class:`~dice_env.model.scene.Wall` for ``Scene(walls=...)``,
around the release point above the origin (the floor is the scene's ``ground``). Walls take
the table's material unless given other ``stiffness``, ``damping``, ``friction``.
"""

from __future__ import annotations

from dice_env.model.checks import check_choice, check_positive
from dice_env.model.scene import Wall

# A common felt-lined dice tray: 30 cm x 20 cm inside.
TRAY = (0.30, 0.20)
# A craps table's throwing area, scaled: the dice travel 1 m along +x to the back wall,
# between side walls 0.6 m apart.
CRAPS = (1.0, 0.6)


def tray(length: float = TRAY[0], width: float = TRAY[1], **material: float) -> tuple[Wall, ...]:
    """Four walls around the origin: ``length`` (m) along x by ``width`` (m) along y."""
    check_positive("length", length)
    check_positive("width", width)
    x, y = length / 2, width / 2
    return (Wall.through((x, 0, 0), (-1, 0, 0), **material),
            Wall.through((-x, 0, 0), (1, 0, 0), **material),
            Wall.through((0, y, 0), (0, -1, 0), **material),
            Wall.through((0, -y, 0), (0, 1, 0), **material))


def craps(distance: float = CRAPS[0], width: float = CRAPS[1],
          **material: float) -> tuple[Wall, ...]:
    """A craps table: a back wall the dice must hit, side walls, open behind the thrower.

    The back wall stands ``distance`` (m) ahead along +x; the side walls are ``width`` (m)
    apart.
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

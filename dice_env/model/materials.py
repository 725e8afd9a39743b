"""Table materials: felt, wood, glass and the craps table as grounds for a plastic die.

Each preset gives the restitution ``e`` of a flat landing, the sliding friction ``mu`` of a
plastic die on that surface and a ground stiffness ``S`` per vertex; :func:`ground` turns them
into S, D, mu for a die's mass (``ground("wood") == Ground()``). The values, their sources and
which are estimates: ``docs/materials.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

from dice_env.model import defaults
from dice_env.model.checks import check_choice, check_positive, check_range
from dice_env.model.defaults import damping_for_restitution
from dice_env.model.die import Die
from dice_env.model.scene import Ground, Scene


@dataclass(frozen=True)
class Material:
    """A table surface for a plastic die.

    ``restitution`` e of a flat landing, sliding ``friction`` mu, ``stiffness`` S (N/m per
    vertex), and ``source``: where the values come from.
    """

    restitution: float
    friction: float
    stiffness: float
    source: str

    def __post_init__(self) -> None:
        check_range("restitution", self.restitution, 0.0, 1.0)
        check_positive("friction", self.friction)
        check_positive("stiffness", self.stiffness)


MATERIALS: dict[str, Material] = {
    "felt": Material(0.30, 0.30, 2e4, "e estimate (fibre layer deadens); mu billiard cloth "
                     "0.2 plus the nap ploughed (estimate); S: ~1 mm sink"),
    "wood": Material(defaults.RESTITUTION, defaults.FRICTION, defaults.STIFFNESS,
                     "the default table: e 0.4-0.5 (Kapitaniak 2012), mu 0.3-0.5 (Murase "
                     "1984; Blau 2001)"),
    "glass": Material(0.60, 0.45, 1e5, "e estimate between wood 0.45 and acetate spheres "
                      "0.87 (Foerster 1994); mu steel-Plexiglas 0.4-0.5 (Roloff/Matek)"),
    "craps": Material(0.40, 0.20, 1e4, "cloth over padding; e estimate (resilient padding, "
                      "bouncy layouts); mu billiard cloth 0.2 (Alciatore); S: ~1.5 mm sink"),
}


def ground(name: str, die: Die | None = None) -> Ground:
    """The ground of preset ``name``, damped to its restitution for ``die`` (default: ``Die()``)."""
    check_choice("name", name, MATERIALS)
    material = MATERIALS[name]
    mass = (Die() if die is None else die).mass
    return Ground(stiffness=material.stiffness, friction=material.friction,
                  damping=damping_for_restitution(material.restitution, material.stiffness,
                                                  mass))


def scene(name: str, die: Die | None = None, **options: object) -> Scene:
    """A :class:`Scene` with ``die`` (default: ``Die()``) on preset ``name``, plus ``options``."""
    die = Die() if die is None else die
    return Scene(die=die, ground=ground(name, die), **options)


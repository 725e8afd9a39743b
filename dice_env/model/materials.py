"""Table materials: felt, wood, glass and the craps table as grounds for a plastic die.

Each preset gives the normal restitution ``e`` of a flat landing and the sliding friction
``mu`` of a plastic (acrylic or cellulose acetate) die on that surface, and a ground stiffness
``S`` per vertex; :func:`ground` turns them into S, D, mu as :mod:`dice_env.model.table` does for
the default table (``D = damping_for_restitution(e, S, m)`` for the die's mass ``m``; the
step follows S through the scene's automatic step). ``wood`` is the default table exactly:
``ground("wood") == Ground()``.

No study has measured a die's restitution or friction on felt, glass or a craps layout; the
values below come from the nearest published measurement, and the table says where a value is
an estimate and why.

=======  =====  =====  =======  ==============================================================
preset   e      mu     S (N/m)  source / reason
=======  =====  =====  =======  ==============================================================
wood     0.45   0.40   1e5      the default table: dice on wooden tables e = 0.4-0.5
                                (Kapitaniak et al. 2012; Strzalko et al. 2008); plastics on
                                dry wood mu = 0.3-0.5 (Murase 1984; Blau 2001)
glass    0.60   0.45   1e5      e: estimate. Glass (E = 70 GPa) barely deforms, so the loss
                                is the die's own: between wood's 0.45 and the 0.87 measured
                                for cellulose acetate spheres (Foerster et al. 1994), which
                                a die's flat or edge landing, rocking onto several corners,
                                does not reach. mu: steel-Plexiglas 0.4-0.5 (dry; the
                                friction table of Roloff/Matek as reproduced in Autodesk
                                Inventor's help), a hard smooth counterface like glass.
                                S: the die's corner compliance dominates, as on wood
felt      0.30   0.30   2e4      e: estimate: the fibre layer is what dice trays are lined
                                with to deaden the bounce. mu: phenolic balls on billiard
                                cloth slide at 0.15-0.4, typically 0.2 (Alciatore, pool
                                physics data); a die's edges plough the looser felt nap,
                                so 0.3 (estimate). S: a corner sinks about 1 mm into a
                                2-3 mm felt in a vigorous landing (0.5 mm on wood)
craps    0.40   0.20   1e4      a cloth layout over a padded bed (Haltom, "Table
                                conditions"); e: estimate: the rubber or foam padding
                                returns much of the indentation, and synthetic layouts are
                                "very bouncy" (Scoblete, "Get yourself a table"), so just
                                under wood. mu: the tight layout cloth is billiard cloth,
                                0.2 (Alciatore). S: the padding lets a corner sink about
                                1.5 mm
=======  =====  =====  =======  ==============================================================

References: M. Kapitaniak, J. Strzalko, J. Grabski, T. Kapitaniak, Chaos 22, 047504 (2012);
J. Strzalko et al., Physics Reports 469, 59-92 (2008); Y. Murase, J. Fac. Agr. Kyushu Univ.
28, 147-160 (1984); P. J. Blau, Tribology International 34, 585-591 (2001); S. F. Foerster,
M. Y. Louge, H. Chang, K. Allia, Physics of Fluids 6, 1108-1115 (1994); D. G. Alciatore, "The
amazing world of billiards physics" and billiards.colostate.edu; S. Haltom, "Table conditions",
dicecoach.com; F. Scoblete, "Get yourself a table", goldentouchcraps.com.
:func:`dice_env.simulation.calibration.measured_restitution` of :func:`scene` gives the
restitution the simulator produces for each preset (``docs/materials.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

from dice_env.model import table
from dice_env.model.checks import check_choice, check_positive, check_range
from dice_env.model.die import Die
from dice_env.model.scene import Ground, Scene
from dice_env.model.table import damping_for_restitution


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
    "wood": Material(table.RESTITUTION, table.FRICTION, table.STIFFNESS,
                     "the default table: e 0.4-0.5 (Kapitaniak 2012), mu 0.3-0.5 (Murase "
                     "1984; Blau 2001)"),
    "glass": Material(0.60, 0.45, 1e5, "e estimate between wood 0.45 and acetate spheres "
                      "0.87 (Foerster 1994); mu steel-Plexiglas 0.4-0.5 (Roloff/Matek)"),
    "craps": Material(0.40, 0.20, 1e4, "cloth over padding; e estimate (resilient padding, "
                      "bouncy layouts); mu billiard cloth 0.2 (Alciatore); S: ~1.5 mm sink"),
}


def preset(name: str) -> Material:
    """The :class:`Material` called ``name`` (a key of :data:`MATERIALS`)."""
    check_choice("name", name, MATERIALS)
    return MATERIALS[name]


def ground(name: str, die: Die | None = None) -> Ground:
    """The ground of preset ``name`` for ``die`` (default: the default die).

    The damping gives the preset's restitution for the die's mass.
    """
    material = preset(name)
    mass = (Die() if die is None else die).mass
    return Ground(stiffness=material.stiffness, friction=material.friction,
                  damping=damping_for_restitution(material.restitution, material.stiffness,
                                                  mass))


def scene(name: str, die: Die | None = None, **options: object) -> Scene:
    """A :class:`Scene` with ``die`` (default: the default die) on preset ``name``.

    ``options`` go to :class:`Scene` (``t_max``, ``safety``, ...).
    """
    die = Die() if die is None else die
    return Scene(die=die, ground=ground(name, die), **options)


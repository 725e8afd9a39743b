"""The pips page: the drilled-pip model, its presets and their mass properties.

``python -m studies pips`` writes the tables of ``docs/pips.md`` (closed form, instant) into
``docs/generated/``; the page around them is hand-written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dice_env.markdown import markdown_table
from dice_env.model.die import Die
from dice_env.model.pips import DRILLINGS, Pips, cap_properties
from studies.common import DOCS
from studies.docs_numbers import generated
from studies.templates import write_study

COMMAND = "python -m studies pips"
# The sources of the pips layout and of the presets of dice_env.model.pips.DRILLINGS.
SOURCES = (
    "dice-play.com, \"Casino Dice\": http://dice-play.com/DiceCasino.htm (the 2 and 3 "
    "diagonals)",
    "Michigan Admin. Code R 432.1814, Dice specifications: "
    "https://www.law.cornell.edu/regulations/michigan/Mich-Admin-Code-R-432-1814",
    "Maryland COMAR 36.05.02.12, Dice: https://casetext.com/regulation/maryland-administrative-"
    "code/title-36-maryland-state-lottery-and-gaming-control-agency/subtitle-05-table-games/"
    "chapter-360502-table-game-equipment/section-36050212-dice",
    "AZoM, \"Cellulose Acetate\" (Plascams): https://www.azom.com/article.aspx?ArticleID=383",
    "Thingiverse thing 3493901, dice-v4.scad (as archived in github.com/uwplse/szalinski, "
    "inputs/thingiverse/thing-3493901/files/dice-v4.scad)",
    "irasohn.blogspot.com, \"Initial die calculation results\" (2010): "
    "http://irasohn.blogspot.com/2010/04/initial-die-calculation-results.html",
)
FILES = ("pips-presets", "pips-masses", "pips-sources")  # docs/generated/, included by pips.md


def run(out: Path = DOCS, quick: bool = False) -> dict[str, float]:
    """Write ``out/generated/pips-*.md``; the drilled d6's com offset / edge.

    Outside docs/ also the page ``out/pips.md``; ``quick`` changes nothing.
    """
    write_study(out, "pips", list(FILES))
    drilled = _rows()[0][1]
    return {"drilled16_com_over_edge": float(np.linalg.norm(drilled.com) / drilled.size)}


def _rows() -> list[tuple[str, Die, Pips]]:
    """The presets, then the casino die with its spots left empty and with paint 10 % light."""
    rows = [(f"`{name}`", Die.standard("d6", pips=name), preset.pips)
            for name, preset in DRILLINGS.items()]
    casino = DRILLINGS["casino19"]
    for label, paint in (("empty spots", None), ("paint 10 % lighter", 0.9 * casino.density)):
        pips = Pips(casino.pips.radius, casino.pips.depth, casino.pips.offset, paint)
        die = Die.standard("d6", casino.size, casino.density * casino.size**3, pips=pips)
        rows.append((f"`casino19`, {label}", die, pips))
    return rows


@generated("pips-presets", COMMAND)
def presets_table() -> str:
    """Each preset's size, mass, pips and paint, and its source."""
    return markdown_table(
        "preset | edge (mm) | mass (g) | pip opening (mm) | depth (mm) | offset | paint "
        "(g/cm³) | source",
        ((f"`{name}`", f"{die.size * 1e3:.2f}", f"{die.mass * 1e3:.3f}",
          f"{2e3 * pips.radius:g}", f"{1e3 * pips.depth:g}", f"{pips.offset:g}",
          "empty" if pips.paint_density is None else f"{pips.paint_density / 1e3:g}",
          preset.source)
         for (name, preset), (_, die, pips) in zip(DRILLINGS.items(), _rows(), strict=False)))


@generated("pips-masses", COMMAND)
def masses_table() -> str:
    """Each die's cavities, centre of mass and inertia against the uniform cube's."""
    return markdown_table(
        "die | cavities (% of the cube) | com x, y, z (µm) | \\|com\\| (µm) | "
        "\\|com\\| / edge | principal moments / (m s²/6) − 1 (10⁻³) | "
        "products yz, xz, xy / (m s²/6) (10⁻³)",
        (_mass_row(label, die, pips) for label, die, pips in _rows()))


@generated("pips-sources", COMMAND)
def sources_list() -> str:
    """The presets' sources (:data:`SOURCES`)."""
    return "\n".join(f"- {source}" for source in SOURCES)


def _mass_row(label: str, die: Die, pips: Pips) -> tuple:
    """The mass-properties table's row of one die."""
    volume = cap_properties(pips.radius, pips.depth)[0]
    com = np.asarray(die.com)
    inertia = die.inertia_body / (die.mass * die.size**2 / 6)
    moments = np.linalg.eigvalsh(inertia) - 1
    products = inertia[[1, 0, 0], [2, 2, 1]]
    return (label, f"{100 * 21 * volume / die.size**3:.2f}",
            ", ".join(f"{1e6 * c:.2f}" for c in com), f"{1e6 * np.linalg.norm(com):.2f}",
            f"{np.linalg.norm(com) / die.size:.2e}", ", ".join(f"{1e3 * m:+.3f}" for m in moments),
            ", ".join(f"{1e3 * m:+.3f}" for m in products))

"""Studies that regenerate ``docs/``: ``python -m dice_env.studies NAME [--quick] [--out DIR]``.

Each entry of :data:`STUDIES` names a module with ``run(out: Path, quick: bool) -> dict``
that writes its markdown and figures under ``out`` and returns its headline numbers. Those in
:data:`SIZED` also take ``throws`` (the sample size per die or per point).
"""

from __future__ import annotations

from importlib import import_module
from pathlib import Path

STUDIES = {
    "paper": "dice_env.studies.paper_figures",
    "stability": "dice_env.studies.stability",
    "fairness": "dice_env.studies.fairness",
    "error": "dice_env.studies.convergence",
    "shapes": "dice_env.studies.shapes",
    "cuboids": "dice_env.studies.cuboids",
    "pips": "dice_env.studies.pips",
    "materials": "dice_env.studies.materials",
    "pairs": "dice_env.studies.pairs",
    "collisions": "dice_env.studies.collisions",
    "craps": "dice_env.studies.craps",
    "weldon": "dice_env.studies.weldon",
    "validation": "dice_env.studies.validation",
}
SIZED = ("shapes", "cuboids", "materials", "pairs", "weldon", "collisions", "craps")


def run(name: str, out: Path, quick: bool = False,
        throws: int | None = None) -> dict[str, float]:
    """Run study ``name`` (a key of :data:`STUDIES`) into ``out``.

    ``throws`` (studies in :data:`SIZED` only) replaces the study's sample size.
    """
    if name not in STUDIES:
        raise ValueError(f"name must be one of {sorted(STUDIES)}, got {name!r}")
    if throws is None:
        return import_module(STUDIES[name]).run(out, quick)
    if name not in SIZED:
        raise ValueError(f"throws is taken by the studies {', '.join(SIZED)} only, not {name!r}")
    return import_module(STUDIES[name]).run(out, quick, throws=throws)

"""Studies that regenerate ``docs/``: ``python -m dice_env.studies NAME [--quick] [--out DIR]``.

Each entry of :data:`STUDIES` names a module with ``run(out: Path, quick: bool) -> dict``
that writes its markdown and figures under ``out`` and returns its headline numbers. Those in
:data:`SIZED` also take ``throws`` (the sample size per die or per point), those in
:data:`CHUNKED` ``faces_of`` (their throws run elsewhere: ``--ray ADDRESS``), those in
:data:`KEPT` ``keep`` (a folder keeping their throws' chunks: ``--chunks DIR``).
"""

from __future__ import annotations

from collections.abc import Callable
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
CHUNKED = ("shapes",)
KEPT = ("pairs", "weldon")


def run(name: str, out: Path, quick: bool = False, throws: int | None = None,
        faces_of: Callable | None = None, keep: Path | None = None) -> dict[str, float]:
    """Run study ``name`` (a key of :data:`STUDIES`) into ``out`` (options: see the module)."""
    if name not in STUDIES:
        raise ValueError(f"name must be one of {sorted(STUDIES)}, got {name!r}")
    options = {}
    for key, value, takers in (("throws", throws, SIZED), ("faces_of", faces_of, CHUNKED),
                               ("keep", keep, KEPT)):
        if value is not None:
            if name not in takers:
                raise ValueError(f"{key} is taken by the studies {', '.join(takers)} only, "
                                 f"not {name!r}")
            options[key] = value
    return import_module(STUDIES[name]).run(out, quick, **options)

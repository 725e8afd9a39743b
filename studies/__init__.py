"""Studies that regenerate ``docs/``: ``python -m studies NAME [--quick] [--out DIR]``.

Each entry of :data:`STUDIES` names a module with ``run(out: Path, quick: bool) -> dict``
that writes its markdown and figures under ``out`` and returns its headline numbers; a module's
``FIGURES`` (name: ``draw(numbers, path)``) draws its figures from the numbers its page keeps
(:mod:`studies.figures` draws them again from the JSON alone). Those in
:data:`SIZED` also take ``throws`` (the sample size per die or per point), those in
:data:`CHUNKED` ``faces_of`` (their throws run elsewhere: ``--ray ADDRESS``), those in
:data:`KEPT` ``keep`` (a folder keeping their throws' chunks: ``--chunks DIR``).
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import import_module
from pathlib import Path

# The checkout: the studies are not installed with dice_env; they run from a clone of the
# repository, beside the docs/ and benchmarks/results/ they read and write.
ROOT = Path(__file__).resolve().parents[1]

STUDIES = {
    "paper": "studies.paper_figures",
    "stability": "studies.stability",
    "fairness": "studies.fairness",
    "error": "studies.convergence",
    "shapes": "studies.shapes",
    "cuboids": "studies.cuboids",
    "pips": "studies.pips",
    "materials": "studies.materials",
    "pairs": "studies.pairs",
    "collisions": "studies.collisions",
    "craps": "studies.craps",
    "weldon": "studies.weldon",
    "validation": "studies.validation",
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

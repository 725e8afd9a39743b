"""Studies that regenerate ``docs/``: ``python -m dice_env.studies NAME [--quick] [--out DIR]``.

Each entry of :data:`STUDIES` names a module with ``run(out: Path, quick: bool) -> dict``
that writes its markdown and figures under ``out`` and returns its headline numbers.
"""

from __future__ import annotations

from importlib import import_module
from pathlib import Path

STUDIES = {
    "paper": "dice_env.studies.paper_figures",
    "stability": "dice_env.studies.stability",
    "fairness": "dice_env.studies.fairness",
    "error": "dice_env.studies.convergence",
}


def run(name: str, out: Path, quick: bool = False) -> dict[str, float]:
    """Run study ``name`` (a key of :data:`STUDIES`) into ``out``."""
    if name not in STUDIES:
        raise ValueError(f"name must be one of {sorted(STUDIES)}, got {name!r}")
    return import_module(STUDIES[name]).run(out, quick)

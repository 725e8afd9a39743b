"""The studies' figures, redrawn from the numbers their pages keep.

``python -m studies.figures NAME --out PATH`` draws ``docs/figures/NAME.png`` again from the
study's JSON (``docs/<study>.json``) without throwing a die: the full study (``python -m studies
<study>``) measures, writes that JSON, and draws its figures from it with the same functions.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from importlib import import_module
from pathlib import Path
from typing import NamedTuple

from studies import ROOT, STUDIES


class Figure(NamedTuple):
    """One study figure: the study's key, its JSON (from the root) and its drawing function."""

    study: str
    json: str
    draw: Callable[[dict, Path], None]

    def redraw(self, path: Path) -> None:
        """Draw the figure into ``path`` from the committed JSON."""
        self.draw(json.loads((ROOT / self.json).read_text()), path)


def figures() -> dict[str, Figure]:
    """Every study figure by name (the PNG's stem under ``docs/figures/``)."""
    found = {}
    for study, module_name in STUDIES.items():
        module = import_module(module_name)
        for name, draw in getattr(module, "FIGURES", {}).items():
            found[name] = Figure(study, module.JSON, draw)
    return found


def main(argv: list[str] | None = None) -> None:
    """Redraw one study figure from its study's JSON."""
    known = figures()
    parser = argparse.ArgumentParser(prog="python -m studies.figures",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("name", choices=sorted(known))
    parser.add_argument("--out", type=Path, required=True, help="PNG file to write")
    args = parser.parse_args(argv)
    known[args.name].redraw(args.out)


if __name__ == "__main__":
    main()

"""``python -m dice_env.studies {all,<study>} [--quick] [--out DIR]``."""

from __future__ import annotations

import argparse
from pathlib import Path

from dice_env.studies import STUDIES, run


def main(argv: list[str] | None = None) -> None:
    """Parse the command line and run the chosen studies."""
    parser = argparse.ArgumentParser(prog="python -m dice_env.studies", description=__doc__)
    parser.add_argument("study", choices=[*STUDIES, "all"])
    parser.add_argument("--quick", action="store_true", help="reduced sizes (for the tests)")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[2] / "docs",
                        help="folder for the markdown; figures go to OUT/figures")
    args = parser.parse_args(argv)
    for name in STUDIES if args.study == "all" else [args.study]:
        numbers = run(name, args.out, args.quick)
        print(f"{name}: " + ", ".join(f"{k}={v:.4g}" for k, v in numbers.items()))


if __name__ == "__main__":
    main()

"""``python -m dice_env.studies {all,<study>} [--quick] [--throws N] [--out DIR]``."""

from __future__ import annotations

import argparse
from pathlib import Path

from dice_env.studies import SIZED, STUDIES, run


def main(argv: list[str] | None = None) -> None:
    """Parse the command line and run the chosen studies."""
    parser = argparse.ArgumentParser(prog="python -m dice_env.studies", description=__doc__)
    parser.add_argument("study", choices=[*STUDIES, "all"])
    parser.add_argument("--quick", action="store_true", help="reduced sizes (for the tests)")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[2] / "docs",
                        help="folder for the markdown; figures go to OUT/figures")
    parser.add_argument("--throws", type=int, default=None,
                        help=f"sample size per die or per point ({', '.join(SIZED)} only; "
                        "default: the study's full size)")
    args = parser.parse_args(argv)
    if args.throws is not None and args.study not in SIZED:
        parser.error(f"--throws is taken by {', '.join(SIZED)} only, not {args.study!r}")
    for name in STUDIES if args.study == "all" else [args.study]:
        numbers = run(name, args.out, args.quick, args.throws)
        print(f"{name}: " + ", ".join(f"{k}={v:.4g}" for k, v in numbers.items()))


if __name__ == "__main__":
    main()

"""The studies' command line.

``python -m studies {all,<study>} [--quick] [--throws N] [--ray ADDR] [--chunks DIR]
[--out DIR]``. A full run writes its page's numbers (``docs/generated/``, included by the
hand-written ``docs/NAME.md``) and figures into the repository's docs/; a ``--quick`` run writes
them, and the page with them included, into ./studies-quick unless ``--out`` is given, and never
into docs/, so that a reduced run cannot replace a full page. The studies are not installed
with ``dice_env``: they run from a checkout, from its root folder (``docs/`` is the checkout's).
"""

from __future__ import annotations

import argparse
import contextlib
import functools
from pathlib import Path

from dice_env.simulation.runner import connected
from studies import CHUNKED, KEPT, SIZED, STUDIES, run
from studies.common import DOCS
from studies.many_throws import at_least, hand_faces, ray_address

QUICK = Path("studies-quick")


def main(argv: list[str] | None = None) -> None:
    """Parse the command line and run the chosen studies."""
    parser = argparse.ArgumentParser(prog="python -m studies", description=__doc__)
    parser.add_argument("study", choices=[*STUDIES, "all"])
    parser.add_argument("--quick", action="store_true",
                        help=f"reduced sizes (for the tests), written to ./{QUICK} by default "
                        "and never into docs/")
    parser.add_argument("--out", type=Path, default=None,
                        help=f"folder for the markdown; figures go to OUT/figures (default: "
                        f"{DOCS}, or ./{QUICK} with --quick)")
    parser.add_argument("--throws", type=at_least(1), default=None,
                        help=f"sample size per die or per point ({', '.join(SIZED)} only; "
                        "default: the study's full size)")
    parser.add_argument("--ray", metavar="ADDRESS", type=ray_address, default=None,
                        help=f"throw in seeded chunks on Ray ({', '.join(CHUNKED)} only): "
                        "auto, ray://host:10001, or local (a fresh local instance)")
    parser.add_argument("--chunks", metavar="DIR", type=Path, default=None,
                        help=f"throw in seeded chunks ({', '.join(CHUNKED + KEPT)} only), each "
                        "kept under DIR: run again, the study continues from the chunks done")
    args = parser.parse_args(argv)
    if args.out is None:
        args.out = QUICK if args.quick else DOCS
    elif args.quick and args.out.resolve() == DOCS:
        parser.error(f"--quick writes reduced pages: it may not write into {DOCS}, where the "
                     "full pages are; give another --out")
    for flag, value, takers in (("--throws", args.throws, SIZED), ("--ray", args.ray, CHUNKED),
                                ("--chunks", args.chunks, CHUNKED + KEPT)):
        if value is not None and args.study not in takers:
            parser.error(f"{flag} is taken by {', '.join(takers)} only, not {args.study!r}")
    chunked = args.ray is not None or (args.chunks is not None and args.study in CHUNKED)
    faces_of = functools.partial(hand_faces, ray=args.ray, keep=args.chunks) if chunked \
        else None
    with contextlib.nullcontext() if args.ray is None else connected(args.ray):
        for name in STUDIES if args.study == "all" else [args.study]:
            keep = args.chunks if name in KEPT else None
            try:
                numbers = run(name, args.out, args.quick, args.throws, faces_of, keep)
            except ValueError as error:  # a bad value or a folder not this run's
                parser.error(f"{name}: {error}")
            print(f"{name}: " + ", ".join(f"{k}={v:.4g}" for k, v in numbers.items()))


if __name__ == "__main__":
    main()

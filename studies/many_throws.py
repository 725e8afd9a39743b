"""Many hand throws of a standard die in seeded chunks, here or on Ray, and their summary.

    python -m studies.many_throws --die d20 --throws 1000000 --ray auto --out runs/d20

A checkout's command (the studies are not installed with ``dice_env``) over the library's
runner, :func:`dice_env.simulation.runner.run_throws`; it draws the runner's progress as a
tqdm bar. Ray is an optional extra (``pip install 'dice_env[ray]'``).
"""

from __future__ import annotations

import argparse
import contextlib
import time
from collections.abc import Callable
from pathlib import Path

from tqdm import tqdm

from dice_env.markdown import bracket, markdown_table
from dice_env.model.die import STANDARD_SIZES
from dice_env.model.scene import Scene
from dice_env.simulation.chunks import FolderError
from dice_env.simulation.runner import CHUNK, Tally, run_throws
from dice_env.throws import Faces


def hand_faces(scene: Scene, n: int, seed: int, *, ray: str | None = None,
               chunk: int = CHUNK, keep: Path | str | None = None) -> Faces:
    """The faces of ``n`` hand throws of ``scene`` from ``seed`` by :func:`run_throws`, no bar.

    A study's ``faces_of``; ``keep``: a folder holding one run folder per seed (``seed-N``).
    """
    out = None if keep is None else Path(keep) / f"seed-{seed}"
    return run_throws(scene, n, chunk=chunk, seed=seed, ray=ray, out=out).faces


def summary(tally: Tally, title: str) -> str:
    """A markdown summary of ``tally``: faces, chi-square, the other outcomes' moments."""
    faces = tally.faces
    table = markdown_table("face | count | share | 95% interval", (
        (label, c, f"{s:.5f}", bracket(interval, 5)) for label, (c, s, interval)
        in enumerate(zip(faces.counts, faces.shares, faces.intervals, strict=True), 1)))
    return f"""{title}

{table}

Counted {faces.ended} of {tally.throws} throws (not counted: {tally.unfinished} unfinished, \
{tally.unstable} unstable, {tally.sunk} sunk). Chi-square of uniformity: \
chi2 = {faces.chi2:.2f} ({len(faces.counts) - 1} degrees of freedom), p = {faces.p_value:.4g}.
Steps {tally.mean('steps'):.0f} ± {tally.std('steps'):.0f}; time to the decided face \
{tally.mean('time'):.3f} ± {tally.std('time'):.3f} s; impacts {tally.mean('impacts'):.2f} \
± {tally.std('impacts'):.2f} (mean ± standard deviation)."""


def at_least(low: int) -> Callable[[str], int]:
    """An argparse type: an int >= ``low``."""
    def parse(text: str) -> int:
        with contextlib.suppress(ValueError):
            if int(text) >= low:
                return int(text)
        raise argparse.ArgumentTypeError(f"must be an int >= {low}, got {text!r}")
    return parse


def ray_address(text: str) -> str:
    """An argparse type: a Ray address, not empty."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"must be a Ray address (auto, local, "
                                         f"ray://host:port), got {text!r}")
    return text


def main(argv: list[str] | None = None) -> None:
    """Throw a standard die many times (optionally on Ray) and print the summary."""
    parser = argparse.ArgumentParser(
        prog="python -m studies.many_throws",
        description="Many vigorous hand throws of a standard die to a decided face, in seeded "
        "chunks, in this process or on a Ray cluster; prints the faces and their chi-square.")
    parser.add_argument("--die", choices=tuple(STANDARD_SIZES), default="d6")
    parser.add_argument("--throws", type=at_least(1), default=100_000)
    parser.add_argument("--chunk", type=at_least(1), default=CHUNK, help="throws per chunk")
    parser.add_argument("--seed", type=at_least(0), default=0)
    parser.add_argument("--ray", metavar="ADDRESS", type=ray_address, default=None,
                        help="run on Ray: auto, ray://host:10001, or local (a fresh local "
                        "instance); default: in this process")
    parser.add_argument("--workers", type=at_least(1), default=None,
                        help="chunks at once on Ray (default: the cluster's CPUs)")
    parser.add_argument("--out", type=Path, default=None,
                        help="run folder: per-chunk outcomes, resumed when run again")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    try:
        # delay: a run refused at once (its --out another run's) shows no bar before the error
        with tqdm(total=args.throws, unit="throw", unit_scale=True, desc="throws",
                  dynamic_ncols=True, delay=0.5) as bar:
            tally = run_throws(args.die, args.throws, chunk=args.chunk, seed=args.seed,
                               ray=args.ray, out=args.out, workers=args.workers,
                               progress=bar.update)
    except FolderError as error:
        parser.error(f"argument --out: {error}")
    seconds = time.perf_counter() - start
    where = f"on Ray ({args.ray})" if args.ray else "in this process"
    print(summary(tally, f"## {args.die}: {args.throws} throws in chunks of {args.chunk}, seed "
                  f"{args.seed}, {where}: {seconds:.1f} s"))


if __name__ == "__main__":
    main()

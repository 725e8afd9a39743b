r"""The search behind the benchmark's hyperparameters: a few variants per algorithm, one task.

    python -m agents.tune                 # every variant of agents.hyperparams.SEARCH
    python -m agents.tune --algos ppo a2c # two commands on different algorithms share 2 cores
    python -m agents.tune --quick --out DIR

Each variant of :data:`agents.hyperparams.SEARCH` (changes to an algorithm's benchmark
keywords) is trained once on :data:`TASK` for :data:`TUNE_BUDGET` throws, seed
:data:`TUNE_SEED` (not one of the benchmark's seeds), and scored by its policy's mean action on
:data:`TUNE_THROWS` throws of seed :data:`TUNE_THROWS_SEED`, not the throws the benchmark reports.
Runs resume and are kept as :mod:`agents.benchmark`'s are (``tuning/<task>/tune-<algo>-<i>.json``
under ``--out``, refused by name when made with other settings or code: ``--fresh`` trains them
again); the end of each command gathers them into ``tuning.json``, the best variant per
algorithm first (not for ``--quick``, whose runs are never taken as the search's).
:data:`agents.hyperparams.TUNED` names the best by hand, and a test checks it against the file.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.benchmark import (
    CURVE_THROWS,
    QUICK_BUDGET,
    QUICK_THROWS,
    RESULTS,
    Run,
    keep,
    out_problem,
)
from agents.hyperparams import ALGOS, SEARCH, benchmark_entry
from agents.kept import RunError, interrupted, write_json

TASK = "DiceThrow-v0"
TUNE_BUDGET = 40_000
TUNE_SEED = 100
TUNE_THROWS, TUNE_THROWS_SEED = 400, 2


def runs(algo: str, out: Path, quick: bool) -> list[tuple[str, Run]]:
    """One run per variant of ``algo``, with its name."""
    return [(variant, Run(TASK, algo, TUNE_SEED, out, QUICK_BUDGET if quick else TUNE_BUDGET,
                          QUICK_THROWS if quick else CURVE_THROWS,
                          (QUICK_THROWS if quick else TUNE_THROWS, TUNE_THROWS_SEED),
                          params=benchmark_entry(algo, TASK, variant),
                          kept_as=("tuning", f"tune-{algo}-{i}"), quick=quick))
            for i, variant in enumerate(SEARCH[algo])]


def gather(out: Path) -> dict[str, Any]:
    """Every kept variant's success, per algorithm, best first.

    :class:`agents.kept.RunError` if a kept variant is not of the search's settings.
    """
    found: dict[str, Any] = {}
    for algo in ALGOS:
        kept = [(variant, r) for variant, run in runs(algo, out, False)
                if (r := run.kept()) is not None]
        if kept:
            found[algo] = sorted(({"variant": variant, "changes": SEARCH[algo][variant],
                                   "rate": r["final"]["rate"], "ci": r["final"]["ci"],
                                   "train_seconds": r["train_seconds"], "commit": r["commit"]}
                                  for variant, r in kept), key=lambda v: -v["rate"])
    return {"task": TASK, "budget": TUNE_BUDGET, "seed": TUNE_SEED, "throws": TUNE_THROWS,
            "throws_seed": TUNE_THROWS_SEED, "algos": found, "command": "python -m agents.tune",
            "train_seconds": sum(v["train_seconds"] for a in found.values() for v in a),
            "commit": " ".join(sorted({v["commit"] for a in found.values() for v in a}))}


def main(argv: Sequence[str] | None = None) -> int:
    """Train the variants not yet kept, then write ``tuning.json`` (not for ``--quick``).

    Every argument and every kept result and checkpoint it would use is checked first: exit 2
    with one line naming what cannot be used and how to go on.
    """
    parser = argparse.ArgumentParser(prog="python -m agents.tune",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--algos", nargs="+", default=list(ALGOS), choices=ALGOS)
    parser.add_argument("--quick", action="store_true", help="a smoke run: tiny budgets")
    parser.add_argument("--fresh", action="store_true",
                        help="train afresh the variants whose kept result or checkpoint was "
                        "made with other settings or code, or is unreadable (refused without it)")
    parser.add_argument("--out", type=Path, default=RESULTS, help="results folder")
    args = parser.parse_args(argv)
    if args.quick and args.out.resolve() == RESULTS.resolve():
        parser.error("--quick needs --out: its numbers must not replace the kept results")
    problem = out_problem(args.out)
    if problem:
        parser.error(f"argument --out: {problem}")
    import torch

    torch.set_num_threads(1)
    start = time.perf_counter()
    try:
        for algo in ALGOS:
            for _, run in runs(algo, args.out, args.quick):
                if algo in args.algos:
                    run.check(args.fresh)
                elif not args.quick:  # tuning.json gathers every algorithm's kept variants
                    _kept(run)
        for algo in args.algos:
            for variant, run in runs(algo, args.out, args.quick):
                if run.kept() is None:
                    print(f"{algo} {variant}: {keep(run)['final']['rate']:.3f}", flush=True)
        if not args.quick:
            write_json(args.out / "tuning.json", gather(args.out))
    except RunError as error:
        parser.error(str(error))
    except KeyboardInterrupt:
        return interrupted("every finished variant and the last curve point of the one in "
                           "training are kept; the same command continues")
    print(f"done in {(time.perf_counter() - start) / 60:.1f} min")
    return 0


def _kept(run: Run) -> None:
    """Refuse a kept variant of an algorithm this command does not train, if not the search's."""
    try:
        run.kept()
    except RunError as error:
        raise RunError(f"{error} (with --algos {run.algo})") from None


if __name__ == "__main__":
    sys.exit(main())

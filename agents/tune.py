r"""The search behind the benchmark's hyperparameters: a few variants per algorithm, one task.

    python -m agents.tune                 # every variant of agents.hyperparams.SEARCH
    python -m agents.tune --algos ppo a2c # two commands on different algorithms share 2 cores
    python -m agents.tune --quick --out DIR

Each variant of :data:`agents.hyperparams.SEARCH` (changes to an algorithm's benchmark
keywords) is trained once on :data:`TASK` for :data:`TUNE_BUDGET` throws, seed
:data:`TUNE_SEED` (not one of the benchmark's seeds), and scored by its policy's mean action on
:data:`TUNE_THROWS` throws of seed :data:`TUNE_THROWS_SEED`, not the throws the benchmark reports.
Runs resume and are kept as :mod:`agents.benchmark`'s are (``tuning/<task>/tune-<algo>-<i>.json``
under ``--out``); the end of each command gathers them into ``tuning.json``, the best variant per
algorithm first. :data:`agents.hyperparams.TUNED` names the best by hand, and a test checks it
against the file.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.benchmark import CURVE_THROWS, QUICK_BUDGET, QUICK_THROWS, RESULTS, Run, train
from agents.hyperparams import ALGOS, SEARCH, benchmark_entry

TASK = "DiceThrow-v0"
TUNE_BUDGET = 40_000
TUNE_SEED = 100
TUNE_THROWS, TUNE_THROWS_SEED = 400, 2


def runs(algo: str, out: Path, quick: bool) -> list[tuple[str, Run]]:
    """One run per variant of ``algo``, with its name."""
    return [(variant, Run(TASK, algo, TUNE_SEED, out, QUICK_BUDGET if quick else TUNE_BUDGET,
                          QUICK_THROWS if quick else CURVE_THROWS,
                          (QUICK_THROWS if quick else TUNE_THROWS, TUNE_THROWS_SEED),
                          params=benchmark_entry(algo, TASK, variant), name=f"tune-{algo}-{i}",
                          folder="tuning"))
            for i, variant in enumerate(SEARCH[algo])]


def gather(out: Path) -> dict[str, Any]:
    """Every kept variant's success, per algorithm, best first."""
    found: dict[str, Any] = {}
    for algo in ALGOS:
        kept = []
        for variant, run in runs(algo, out, False):
            if run.result.exists():
                r = json.loads(run.result.read_text())
                kept.append({"variant": variant, "changes": SEARCH[algo][variant],
                             "rate": r["final"]["rate"], "ci": r["final"]["ci"],
                             "train_seconds": r["train_seconds"], "commit": r["commit"]})
        if kept:
            found[algo] = sorted(kept, key=lambda v: -v["rate"])
    return {"task": TASK, "budget": TUNE_BUDGET, "seed": TUNE_SEED, "throws": TUNE_THROWS,
            "throws_seed": TUNE_THROWS_SEED, "algos": found, "command": "python -m agents.tune",
            "train_seconds": sum(v["train_seconds"] for a in found.values() for v in a),
            "commit": " ".join(sorted({v["commit"] for a in found.values() for v in a}))}


def main(argv: Sequence[str] | None = None) -> int:
    """Train the variants not yet kept, then write ``tuning.json``."""
    parser = argparse.ArgumentParser(prog="python -m agents.tune",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--algos", nargs="+", default=list(ALGOS), choices=ALGOS)
    parser.add_argument("--quick", action="store_true", help="a smoke run: tiny budgets")
    parser.add_argument("--out", type=Path, default=RESULTS, help="results folder")
    args = parser.parse_args(argv)
    if args.quick and args.out.resolve() == RESULTS.resolve():
        parser.error("--quick needs --out: its numbers must not replace the kept results")
    import torch

    torch.set_num_threads(1)
    start = time.perf_counter()
    for algo in args.algos:
        for variant, run in runs(algo, args.out, args.quick):
            if not run.result.exists():
                result = train(run)
                run.result.parent.mkdir(parents=True, exist_ok=True)
                run.result.write_text(json.dumps(result, indent=1) + "\n")
                print(f"{algo} {variant}: {result['final']['rate']:.3f}", flush=True)
    if not args.quick:
        (args.out / "tuning.json").write_text(json.dumps(gather(args.out), indent=1) + "\n")
    print(f"done in {(time.perf_counter() - start) / 60:.1f} min")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Cost of a throw against the number of dice thrown together: groups of 1, 2, 5 and 12 d6.

    python benchmarks/dice_together.py                  # 1, 2, 5, 12 dice, about 3 minutes
    python benchmarks/dice_together.py --dice 1 2 --throws 256 --repeats 3

Each group is thrown from the pairs study's hand (``dice_env.studies.pairs.hand_throws``: the
dice side by side 3 cm apart in rows of four, one hand velocity plus each die's noise) into
the tray (``Scene(walls=tray())``), seeded, each throw until every face is decided
(``simulate_group(..., stop_when_decided=True)``, 10 s at most). Timed on one thread as this
process's CPU time (other processes on the shared cores inflate it less than wall-clock
time), best of ``--repeats`` (default 1), after a warm-up that compiles the kernels.
``--throws`` is the number of throws of the single die; a group of N dice gets
``ceil(throws / N)`` (at least 4), so a few throws of the large groups set their rate. Beside the
group of one, the same throws through the single-die path (``simulate``) with its free-flight
shortcut (flights between contacts in one step) and without it (every step, as the group
kernel steps each die), for reference; die-steps count a shortcut flight's steps as taken.
Prints a table and writes ``benchmarks/results/dice_together.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from pathlib import Path

import numba
import numpy as np

from dice_env import Scene, simulate
from dice_env.die import Die
from dice_env.group import group_step, simulate_group
from dice_env.studies.pairs import hand_throws
from dice_env.surroundings import tray

ROOT = Path(__file__).resolve().parents[1]
T_MAX = 10.0


def cpu_best(fn: object, repeats: int) -> tuple[float, object]:
    """Least CPU time of ``repeats`` calls of ``fn`` and the last call's result."""
    best, result = math.inf, None
    for _ in range(repeats):
        start = time.process_time()
        result = fn()
        best = min(best, time.process_time() - start)
    return best, result


def measure(n_dice: int, throws: int, repeats: int, seed: int) -> list[dict]:
    """The rows of a group of ``n_dice`` d6 (and of the single-die path when ``n_dice`` = 1)."""
    scene = Scene(walls=tray(), t_max=T_MAX)
    dice = (Die(),) * n_dice
    state = hand_throws(scene, dice, throws, np.random.default_rng(seed))
    seconds, res = cpu_best(lambda: simulate_group(scene, dice, state, stop_when_decided=True,
                                                   num_threads=1), repeats)
    steps = float(res.steps.sum())
    row = {"path": "simulate_group", "dice": n_dice, "throws": throws, "cpu_s": seconds,
           "throws_per_s": throws / seconds, "die_steps_per_s": steps * n_dice / seconds,
           "decided": float((res.decided | res.settled).mean()),
           "all_read": float(res.read.all(axis=1).mean()),
           "met": float((res.overlap > 0).mean()),
           "sim_s": float(res.steps.mean() * group_step(scene, dice))}
    rows = [row]
    if n_dice == 1:
        alone = state.die(0)
        for flight in (True, False):
            seconds, one = cpu_best(lambda f=flight: simulate(
                scene, alone, stop_when_decided=True, free_flight=f, num_threads=1), repeats)
            rows.append({"path": f"simulate(free_flight={flight})", "dice": 1, "throws": throws,
                         "cpu_s": seconds, "throws_per_s": throws / seconds,
                         "die_steps_per_s": float(one.steps.sum()) / seconds,
                         "decided": float((one.decided | one.settled).mean()),
                         "all_read": 1.0, "met": 0.0,
                         "sim_s": float(one.steps.mean() * scene.step)})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--dice", type=int, nargs="+", default=[1, 2, 5, 12])
    parser.add_argument("--throws", type=int, default=96,
                        help="throws of the single die (a group of N gets throws / N)")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks/results/dice_together.json")
    args = parser.parse_args()
    for name in ("throws", "repeats"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be >= 1, got {getattr(args, name)}")
    if min(args.dice) < 1 or max(args.dice) > 64:
        parser.error(f"--dice must be 1 to 64 dice, got {args.dice}")
    for n_dice in (1, 2):
        measure(n_dice, 2, 1, args.seed)  # compile both paths' kernels, untimed
    rows = []
    for n_dice in args.dice:
        rows += measure(n_dice, max(4, math.ceil(args.throws / n_dice)), args.repeats, args.seed)
        print(f"{n_dice} dice done", flush=True)
    base = next(r for r in rows if r["path"] == "simulate_group" and r["dice"] == min(args.dice))
    print(f"\nOne thread, CPU time, best of {args.repeats}; load average "
          f"{os.getloadavg()[0]:.2f} on {os.cpu_count()} cores.\n")
    print("| path | dice | throws | throws/s | cost per throw / smallest group | "
          "die-steps/s | decided | all dice read | dice met | simulated s per throw |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| `{r['path']}` | {r['dice']} | {r['throws']} | {r['throws_per_s']:.2f} | "
              f"{base['throws_per_s'] / r['throws_per_s']:.2f} | {r['die_steps_per_s']:,.0f} | "
              f"{r['decided']:.0%} | {r['all_read']:.0%} | {r['met']:.0%} | "
              f"{r['sim_s']:.2f} |")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({
        "command": "python benchmarks/dice_together.py " + " ".join(
            f"--{k} {' '.join(map(str, v)) if isinstance(v, list) else v}"
            for k, v in vars(args).items() if k != "out"),
        "threads": 1, "timer": "process CPU time", "repeats": args.repeats,
        "load_average": os.getloadavg()[0], "cpu_count": os.cpu_count(),
        "numba": numba.__version__, "python": platform.python_version(), "rows": rows},
        indent=1))


if __name__ == "__main__":
    main()

"""How sharp the oracle's throws are: whether the best action varies smoothly with the hand.

    python -m agents.sharpness                    # the one-die tasks; about 2 min on 2 cores
    python -m agents.sharpness --tasks DiceThrowHigh-v0 --observations 32

For each task the oracle (:func:`agents.oracle.search`, its default search) finds an action
for each of ``observations`` drawn observations; each action is then scored
(:func:`agents.oracle.score`, the same 16 noise draws per observation throughout) on its own
observation, on the observation with the hand turned by each of :data:`ANGLES` about a random
axis (the target kept), and moved by each of :data:`STEPS` (every action component by ± that
step, in action units). A policy is one smooth function of the observation: where the oracle's
success falls to the rule's within a few degrees of the hand, or within a few hundredths of the
action, a policy must resolve that fine a structure over every target and orientation to match
it. Writes the rows as ``sharpness`` in ``benchmarks/results/learned.json``, the other keys
kept.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.benchmark import RESULTS, evaluation
from agents.evaluate import clustered
from agents.kept import RunError, read_json, write_json
from agents.oracle import score, score_noise, search
from dice_env.model.rotations import axis_angle
from dice_env.provenance import code_version

ANGLES = (0.0, 2.0, 5.0, 10.0, 20.0)  # degrees the hand turns
STEPS = (0.01, 0.03, 0.1)  # action units each component moves
ONE_DIE = ("DiceThrow-v0", "DiceThrowHigh-v0", "DiceThrowD20-v0")
SAMPLES = 16  # noise draws per observation


def sharpness(task_id: str, observations: int, seed: int = 0) -> dict[str, Any]:
    """The oracle's success as the hand turns and as its action moves (module docstring)."""
    task, batch = evaluation(task_id, observations, seed)
    rng = np.random.default_rng(seed + 1)
    start = time.process_time()
    actions = search(task, batch.observations, rng)
    noise = score_noise(task, rng, observations, SAMPLES)

    def row(key: str, value: float, obs: np.ndarray, acts: np.ndarray) -> dict[str, Any]:
        s = score(task, obs, acts, noise)
        return {key: value, "rate": float(s.mean()), "ci": clustered(s)}

    turned = []
    for angle in ANGLES:
        axes = rng.normal(size=(observations, 3))
        hands = np.stack([axis_angle(a, np.radians(angle)) @ h
                          for a, h in zip(axes, batch.hands, strict=True)])
        turned.append(row("degrees", angle, task.observe(batch.targets, hands), actions))
    moved = [row("step", step, batch.observations, np.clip(
        actions + step * rng.choice([-1.0, 1.0], size=actions.shape), -1.0, 1.0))
        for step in STEPS]
    return {"task": task_id, "observations": observations, "samples": SAMPLES,
            "turned": turned, "moved": moved, "cpu_seconds": time.process_time() - start,
            "command": f"python -m agents.sharpness --observations {observations}",
            "commit": code_version()}


def main(argv: Sequence[str] | None = None) -> int:
    """Measure the tasks into ``sharpness`` of ``--out`` (learned.json)."""
    parser = argparse.ArgumentParser(prog="python -m agents.sharpness",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--tasks", nargs="+", default=list(ONE_DIE), choices=ONE_DIE,
                        help="one-die task ids (the hand's turn is one die's)")
    parser.add_argument("--observations", type=int, default=32,
                        help="observations the oracle searches per task (>= 2)")
    parser.add_argument("--out", type=Path, default=RESULTS / "learned.json",
                        help="the JSON whose 'sharpness' the rows replace")
    args = parser.parse_args(argv)
    if args.observations < 2:
        parser.error(f"argument --observations: must be an integer >= 2, got {args.observations}")
    try:
        kept = read_json(args.out, "delete it") if args.out.exists() else {}
    except RunError as error:
        parser.error(str(error))
    rows = []
    for task_id in args.tasks:
        r = sharpness(task_id, args.observations)
        rows.append(r)
        print(f"{task_id:<18} " + ", ".join(f"{t['degrees']:g}° {t['rate']:.2f}"
                                            for t in r["turned"])
              + "; moved " + ", ".join(f"{m['step']:g} {m['rate']:.2f}" for m in r["moved"]),
              flush=True)
    write_json(args.out, {**kept, "sharpness": rows})
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

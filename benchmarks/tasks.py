"""How hard each named task is: random, a rule and the oracle on every registered id.

    python benchmarks/tasks.py            # about 7 minutes on 2 cores
    python benchmarks/tasks.py --quick    # a smoke run: few throws, a tiny search

For each id of :data:`dice_env.envs.tasks.TASKS`, made with ``gym.make``, every thrower faces
the same seeded throws (targets, hands, hand noise: ``agents.evaluate.compare``): uniform random
actions and a rule (the hand-written thrower for one die, and for two dice for a total; for the
set dice of the craps task the craps study's throw, ``dice_env.throws.SET_THROW``: the crossed
set, against the seven, 2 m/s at the back wall with backspin) on ``throws`` throws each, Wilson
95 % intervals; the oracle (``agents.oracle``, started from their actions) on the first of
those observations, each scored on 16 fresh noise draws, its interval Wilson's divided by the
observations' design effect (``agents.evaluate.clustered``). The oracle's budget is
``agents.oracle.task_budget``'s.
Prints a table and writes ``benchmarks/results/tasks.json``.
"""

from __future__ import annotations

import dataclasses
import os
import time

import gymnasium as gym
from harness import benchmark_parser, command_line, write_json

from agents.baselines import rule_throwers
from agents.episodes import EPISODE_KEYWORDS
from agents.evaluate import ORACLE_SCORE_SAMPLES, compare, fair_totals
from agents.oracle import CEM, task_budget
from dice_env.envs.tasks import TASKS, NamedTask
from dice_env.envs.throw_task import ThrowTask
from dice_env.provenance import code_version

SEED = 0
THROWS = 400  # evaluation throws per thrower and task
QUICK = {"throws": 16, "observations": 2,
         "cem": CEM(global_candidates=4, restarts=1, iterations=1, population=4,
                    noise_samples=2, finalists=1, validation_samples=4)}


def chance(task: ThrowTask, episode: dict[str, object]) -> float:
    """Success of fair dice: 1 / faces for one die, else P(the total) over the targets.

    One minus that where the task avoids the total.
    """
    if task.n_dice == 1:
        return 1.0 / task.n_faces
    totals = fair_totals(task)
    fixed = episode.get("target_sum")
    hit = float(totals[fixed - task.n_dice]) if fixed is not None else 1.0 / len(totals)
    return 1.0 - hit if task.target == "avoid_sum" else hit


def measure(named: NamedTask, throws: int, observations: int | None,
            cem: CEM | None) -> dict[str, object]:
    """Every thrower's success on the task's seeded throws, the oracle's on the first ones."""
    start = time.perf_counter()
    env = gym.make(named.id)
    task = env.unwrapped.task
    episode = {k: v for k, v in named.keywords.items() if k in EPISODE_KEYWORDS}
    default_observations, default_cem = task_budget(task)
    observations = default_observations if observations is None else observations
    cem = default_cem if cem is None else cem
    result = compare(task, rule_throwers(task, SEED), throws, observations, SEED, cem, episode)
    rates = {name: {key: s[key] for key in ("rate", "ci", "n")}
             for name, s in result["summary"].items()}
    common = result["common"]
    rates["oracle"] = {key: common["oracle"][key] for key in ("rate", "ci", "n", "observations")}
    return {
        "id": named.id, "keywords": dict(named.keywords), "description": named.description,
        "chance": chance(task, episode), "throws": throws, "oracle_observations": observations,
        "oracle_score_samples": ORACLE_SCORE_SAMPLES, "cem": dataclasses.asdict(cem),
        "oracle_throws_searched": observations * cem.throws_per_observation(
            len(result["summary"])),
        "rates": rates,
        "on_oracle_throws": {name: {key: s[key] for key in ("rate", "ci")}
                             for name, s in common.items()},
        "seconds": time.perf_counter() - start,
    }


def shown(rate: dict[str, object]) -> str:
    """``rate [low, high]``."""
    low, high = rate["ci"]
    return f"{rate['rate']:.3f} [{low:.3f}, {high:.3f}]"


def main() -> None:
    args = benchmark_parser(__doc__, "tasks", "a smoke run, numbers meaningless").parse_args()
    quick = QUICK if args.quick else {"throws": THROWS, "observations": None, "cem": None}
    start = time.perf_counter()
    rows = []
    for named in TASKS:
        rows.append(measure(named, **quick))
        row = rows[-1]
        rule = [f"{name} {shown(r)}" for name, r in row["rates"].items()
                if name not in ("random", "oracle")]
        print(f"{row['id']:<24} chance {row['chance']:.3f}  random {shown(row['rates']['random'])}"
              f"  {' '.join(rule) or 'no rule':<36}  oracle {shown(row['rates']['oracle'])}"
              f"  ({row['seconds']:.0f} s)", flush=True)
    report = {"tasks": rows, "seed": SEED, "threads": os.cpu_count(),
              "seconds": time.perf_counter() - start, "load_average": os.getloadavg()[0],
              "command": command_line(), "commit": code_version()}
    write_json(args.out, report)
    print(f"wrote {args.out} in {report['seconds'] / 60:.1f} min")


if __name__ == "__main__":
    main()

"""The project's recipe on the named tasks: train.py's evaluated runs, kept for the benchmark page.

    python train.py --env-id DiceThrowD20-v0 --seed 0 --runs runs --name d20_s0   # and more
    python -m agents.recipe runs/d20_s0 runs/d20_s1 ...   # into benchmarks/results/learned.json

The recipe is train.py's ``quick`` or ``best`` preset of a task (:mod:`agents.hyperparams`): PPO
warm-started from the task's rule (one die: the hand-written thrower, with the target's
direction as a feature). Each run's evaluation (``evaluation.json``, :mod:`agents.evaluate`)
gives its success on its ``eval_throws`` throws and, on the oracle's observations, PPO's and the
oracle's success on the same throws with their paired difference. Runs of one task, preset and
budget make one row: per seed and their mean ± sd, the training's CPU time
(``training.jsonl``). Writes the rows as ``recipe`` in ``learned.json``, the other keys kept.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.benchmark import RESULTS
from agents.config import Config, is_run_folder
from agents.kept import RunError, read_json, write_json
from dice_env.provenance import code_version


def run_entry(run: Path) -> dict[str, Any]:
    """One evaluated run: task, preset, seed, throws, CPU seconds and its success rates.

    :class:`RunError` for a folder that is not an evaluated train.py run with the oracle.
    """
    if not is_run_folder(run):
        raise RunError(f"{run} is not a train.py run (no config.json)")
    config = Config.load(run / "config.json")
    evaluation = read_json(run / "evaluation.json", f"evaluate it: python -m agents.evaluate {run}")
    if not evaluation.get("common"):
        raise RunError(f"{run} was evaluated without the oracle: python -m agents.evaluate {run} "
                       "--oracle-observations 64")
    sessions = [json.loads(line) for line in
                (run / "training.jsonl").read_text().splitlines() if line.strip()]
    common = evaluation["common"]
    return {
        "run": run.name, "task": config.env_id, "preset": config.preset, "seed": config.seed,
        "env": config.env, "throws": sessions[-1]["throws"],
        "cpu_seconds": sum(s.get("cpu_seconds", float("nan")) for s in sessions),
        "seconds": sum(s["seconds"] for s in sessions),
        "learned": {k: evaluation["summary"]["PPO"][k] for k in ("rate", "ci", "n")},
        "on_oracle_throws": {name: {k: common[name][k] for k in ("rate", "ci")}
                             for name in ("PPO", "oracle")},
        "ratio": common["PPO"]["rate"] / common["oracle"]["rate"],
        "learned_minus_oracle": evaluation["differences"]["oracle"],
        "observations": evaluation["oracle_observations"],
    }


def spread(values: list[float]) -> dict[str, float]:
    """Mean and sample standard deviation (0 for one value)."""
    return {"mean": float(np.mean(values)),
            "sd": float(np.std(values, ddof=1)) if len(values) > 1 else 0.0}


def rows(entries: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Entries grouped by task, preset, env keywords and throws: per seed and mean ± sd."""
    groups: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for e in entries:
        groups.setdefault((e["task"], e["preset"], tuple(e["env"]), e["throws"]), []).append(e)
    out = []
    for (task, preset, env, throws), runs in groups.items():
        runs = sorted(runs, key=lambda r: r["seed"])
        seeds = [r["seed"] for r in runs]
        options = "".join(f" --env {e}" for e in env)
        out.append({
            "task": task, "preset": preset, "env": list(env), "throws": throws, "seeds": seeds,
            "command": f"python train.py --env-id {task} --preset {preset}{options} --seed S",
            "learned": spread([r["learned"]["rate"] for r in runs]),
            "ppo_on_oracle_throws": spread([r["on_oracle_throws"]["PPO"]["rate"] for r in runs]),
            "oracle": spread([r["on_oracle_throws"]["oracle"]["rate"] for r in runs]),
            "ratio": spread([r["ratio"] for r in runs]),
            "cpu_seconds": float(np.sum([r["cpu_seconds"] for r in runs])),
            "runs": runs, "summarised_by": "python -m agents.recipe", "commit": code_version(),
        })
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Summarise the runs into ``recipe`` of ``--out`` (learned.json); exit 2 on a bad run."""
    parser = argparse.ArgumentParser(prog="python -m agents.recipe",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="evaluated train.py run folders")
    parser.add_argument("--out", type=Path, default=RESULTS / "learned.json",
                        help="the JSON whose 'recipe' the rows replace")
    args = parser.parse_args(argv)
    try:
        entries = [run_entry(run) for run in args.runs]
        kept = read_json(args.out, "delete it") if args.out.exists() else {}
    except RunError as error:
        parser.error(str(error))
    write_json(args.out, {**kept, "recipe": rows(entries)})
    for row in rows(entries):
        print(f"{row['task']:<24} {row['preset']} {row['throws']:,} throws, seeds {row['seeds']}: "
              f"PPO / oracle {row['ratio']['mean']:.2f} ± {row['ratio']['sd']:.2f}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

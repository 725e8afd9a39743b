"""The project's recipe on the named tasks: train.py's evaluated runs, kept for the benchmark page.

    python train.py --env-id DiceThrowD20-v0 --seed 0 --runs runs --name d20_s0   # and more
    python -m agents.recipe runs/d20_s0 runs/d20_s1 ...   # into benchmarks/results/learned.json

The recipe is train.py's ``quick`` or ``best`` preset of a task (:mod:`agents.hyperparams`): PPO
warm-started from the task's rule (one die: the hand-written thrower, with the target's
direction as a feature). Each run's evaluation (``evaluation.json``, :mod:`agents.evaluate`)
gives its success on its ``eval_throws`` throws and, on the oracle's observations, PPO's and the
oracle's success on the same throws with their paired difference. Runs of one task, preset and
budget make one row: per seed and their mean ± sd, the training's CPU time
(``training.jsonl``). Runs of :mod:`agents.expert` (expert iteration from a recipe run) make
rows of their own. Writes the rows into ``recipe`` of ``learned.json``: a new row replaces the
kept one of the same task, preset, method, env keywords and throws; the others and the other
keys are kept.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.benchmark import RESULTS
from agents.config import Config, is_run_folder
from agents.kept import RunError, read_json, read_sessions, write_json
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
    sessions = read_sessions(run)
    common = evaluation["common"]
    expert = read_json(run / "expert.json", "") if (run / "expert.json").exists() else None
    defaults = Config()
    evaluation_options = "".join(
        f" --{key.replace('_', '-')} {getattr(config, key)}" for key in EVALUATION_OPTIONS
        if getattr(config, key) != getattr(defaults, key))
    return {
        "run": run.name, "task": config.env_id, "preset": config.preset, "seed": config.seed,
        "method": "recipe" if expert is None else "expert iteration" + (
            " (the oracle's search)" if "--search oracle" in expert["command"] else ""),
        "evaluation_options": evaluation_options, "expert": expert,
        "env": config.env, "throws": sessions[-1]["throws"],
        "cpu_seconds": sum(s.get("cpu_seconds", float("nan")) for s in sessions),
        "seconds": sum(s["seconds"] for s in sessions),
        "learned": {k: evaluation["summary"]["PPO"][k] for k in ("rate", "ci", "n")},
        "on_oracle_throws": {name: {k: common[name][k] for k in ("rate", "ci")}
                             for name in ("PPO", "oracle")},
        "ratio": common["PPO"]["rate"] / common["oracle"]["rate"],
        # The task's rule and random actions on the same throws, as fractions of the oracle.
        "baseline_ratios": {("rule" if name == evaluation.get("rule") else name):
                            common[name]["rate"] / common["oracle"]["rate"]
                            for name in common if name not in ("PPO", "oracle")},
        "learned_minus_oracle": evaluation["differences"]["oracle"],
        "observations": evaluation["oracle_observations"],
    }


# Evaluation options a row's command names where a run's differ from train.py's defaults.
EVALUATION_OPTIONS = ("eval_throws", "oracle_observations", "robustness_throws")


def spread(values: list[float]) -> dict[str, float]:
    """Mean and sample standard deviation (0 for one value)."""
    return {"mean": float(np.mean(values)),
            "sd": float(np.std(values, ddof=1)) if len(values) > 1 else 0.0}


def rows(entries: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Entries grouped by task, preset, method, env keywords, evaluation options and throws.

    Per seed and mean ± sd. An expert-iteration run's command is train.py's for its source
    followed by ``python -m agents.expert``'s.
    """
    groups: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for e in entries:
        key = (e["task"], e["preset"], e.get("method", "recipe"), tuple(e["env"]),
               e.get("evaluation_options", ""), e["throws"])
        groups.setdefault(key, []).append(e)
    out = []
    for (task, preset, method, env, evaluation, throws), runs in groups.items():
        runs = sorted(runs, key=lambda r: r["seed"])
        seeds = [r["seed"] for r in runs]
        options = "".join(f" --env {e}" for e in env)
        command = f"python train.py --env-id {task} --preset {preset}{options} --seed S"
        if method.startswith("expert iteration"):
            command = (command.replace(" --seed S", " --seed S --no-evaluate") + "; "
                       + runs[0]["expert"]["command"].replace("SOURCE", "RUN") + evaluation)
        else:
            command += evaluation
        out.append({
            "task": task, "preset": preset, "method": method, "env": list(env),
            "throws": throws, "seeds": seeds, "command": command,
            "learned": spread([r["learned"]["rate"] for r in runs]),
            "ppo_on_oracle_throws": spread([r["on_oracle_throws"]["PPO"]["rate"] for r in runs]),
            "oracle": spread([r["on_oracle_throws"]["oracle"]["rate"] for r in runs]),
            "ratio": spread([r["ratio"] for r in runs]),
            "baseline_ratios": {name: spread([r["baseline_ratios"][name] for r in runs])
                                for name in runs[0].get("baseline_ratios", {})
                                if all(name in r.get("baseline_ratios", {}) for r in runs)},
            "cpu_seconds": float(np.sum([r["cpu_seconds"] for r in runs])),
            "runs": runs, "summarised_by": "python -m agents.recipe", "commit": code_version(),
        })
    return out


def row_key(row: dict[str, Any]) -> tuple[Any, ...]:
    """What makes a row: task, preset, method, env keywords, throws."""
    return (row["task"], row["preset"], row.get("method", "recipe"), tuple(row["env"]),
            row["throws"])


def merged(kept: Sequence[dict[str, Any]], new: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """``kept`` rows with ``new`` ones replacing those of the same :func:`row_key`, added else.

    The rows stay in the order of the named tasks (:data:`agents.hyperparams.BUDGETS`), recipe
    before expert iteration, quick before best.
    """
    from agents.hyperparams import BUDGETS

    replaced = {row_key(r) for r in new}
    rows_ = [r for r in kept if row_key(r) not in replaced] + list(new)
    tasks = list(BUDGETS)
    return sorted(rows_, key=lambda r: (tasks.index(r["task"]) if r["task"] in tasks else 99,
                                        r.get("method", "recipe") != "recipe",
                                        r["preset"] != "quick", r["throws"]))


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
    write_json(args.out, {**kept, "recipe": merged(kept.get("recipe", []), rows(entries))})
    for row in rows(entries):
        print(f"{row['task']:<24} {row['preset']} {row['throws']:,} throws, seeds {row['seeds']}: "
              f"PPO / oracle {row['ratio']['mean']:.2f} ± {row['ratio']['sd']:.2f}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

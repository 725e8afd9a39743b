r"""What the benchmark's learned throwers do: each task's best run against the oracle.

    python -m agents.learned          # after python -m agents.benchmark; about 10 min on 2 cores

For each named task the best seed of the best algorithm (highest mean final success over its seeds)
is loaded from its last checkpoint (checked to be the one its JSON was made with) and compared on
``benchmarks/tasks.py``'s throws (:func:`agents.evaluate.compare`) with the oracle searched from
its actions (:func:`agents.oracle.task_budget`), both scored on the same fresh throws: their
success with intervals and the paired difference; what each does on those observations (medians of
the intended release speed, its vertical part and the spin; for one die, per class of how far the
target must turn, the push along the roll direction and the spin axis against the target's tilt,
:func:`agents.evaluate.strategy`); the learned thrower's failures on all the throws (success per
turn class or per target, void reasons). For the craps task (avoid a seven), P(seven) of the
learned throw and of the set throw against the hand's noise (:data:`AVOID_NOISES`), Wilson 95 %
intervals, and the largest noise at which the interval is still wholly below 1/6. Writes
``benchmarks/results/learned.json`` after each task.
"""

from __future__ import annotations

import argparse
import collections
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.baselines import rule_throwers
from agents.benchmark import (
    ALGOS,
    FINAL_THROWS,
    RESULTS,
    algorithm,
    benchmark_run,
    episode,
    evaluation,
    kept_runs,
)
from agents.episodes import Batch, PolicyThrower
from agents.evaluate import (
    AVOID_NOISES,
    by_turn,
    compare,
    paired_difference,
    release,
    strategy,
    strategy_table,
    tilt,
    total_hits,
)
from agents.kept import RunError, interrupted, read_json, write_json
from agents.oracle import CEM, task_budget

SEED = 0  # benchmarks/tasks.py's: the same throws
CRAPS = "DiceThrowCraps-v0"
CRAPS_THROWS = 400  # per noise and thrower
QUICK = {"throws": 16, "observations": 2, "cem": CEM(
    global_candidates=4, restarts=1, iterations=1, population=4, noise_samples=2, finalists=1,
    validation_samples=4)}


def best_run(task_id: str, out: Path = RESULTS, quick: bool = False) -> dict[str, Any]:
    """The kept result of the task's best algorithm's best seed.

    :class:`RunError` if the task has no kept run or one that is not the benchmark's
    (``quick``: the smoke run's).
    """
    by_algo = {algo: runs for algo in ALGOS if (runs := kept_runs(out, task_id, algo, quick))}
    if not by_algo:
        raise RunError(f"no kept run of {task_id} in {out}: run python -m agents.benchmark "
                       f"--tasks {task_id} first")
    algo = max(by_algo, key=lambda a: np.mean([r["final"]["rate"] for r in by_algo[a]]))
    return max(by_algo[algo], key=lambda r: r["final"]["rate"])


def model_path(run: dict[str, Any], out: Path = RESULTS) -> Path:
    """The final model of a kept run (saved at its last curve point), checked to be its.

    :class:`RunError` naming the command that rebuilds it when it is missing, unreadable or of
    another run.
    """
    rebuild = (f"rerun python -m agents.benchmark --tasks {run['task']} --algos {run['algo']} "
               f"--seeds {run['seed']} --fresh" + (" --quick" if run.get("quick") else "")
               + f" --out {out}")
    kept = benchmark_run(run["task"], run["algo"], run["seed"], out, bool(run.get("quick")))
    kept.identity = {key: run.get(key) for key in kept.identity}
    try:
        progress = kept.progress()
    except RunError as error:
        raise RunError(f"{error} (its model is not the one {kept.result} was made with): "
                       f"{rebuild}") from None
    if progress is None:
        raise RunError(f"{kept.work} holds no model: {rebuild}")
    return kept.work / progress["checkpoint"] / "model.zip"


def analyse(task_id: str, out: Path = RESULTS, quick: bool = False) -> dict[str, Any]:
    """The best learned thrower of ``task_id`` against the oracle (see the module docstring).

    ``quick``: a smoke run (:data:`QUICK`: few throws, a tiny search).
    """
    run = best_run(task_id, out, quick)
    model = algorithm(run["algo"]).load(model_path(run, out), device="cpu")
    task, _ = evaluation(task_id, 1, SEED)
    observations, cem = task_budget(task)
    throws = FINAL_THROWS
    if quick:
        throws, observations, cem = QUICK["throws"], QUICK["observations"], QUICK["cem"]
    throwers = {"learned": PolicyThrower(model), **rule_throwers(task, SEED)}
    result = compare(task, throwers, throws, observations, SEED, cem, episode(task_id))
    m = len(result["oracle_actions"])
    learned = np.asarray(result["throws"]["learned"]["action"])
    batch: Batch = result["batch"]
    first = Batch(batch.targets[:m], batch.hands[:m], batch.observations[:m], batch.noise[:m])
    success = np.asarray(result["throws"]["learned"]["is_success"], bool)
    reasons = collections.Counter(str(r) for r in result["throws"]["learned"]["void_reason"])
    report: dict[str, Any] = {
        "task": task_id, "algo": run["algo"], "seed": run["seed"], "budget": run["budget"],
        "learned": result["summary"]["learned"]["rate"],
        "learned_ci": result["summary"]["learned"]["ci"],
        "on_oracle_throws": {name: {"rate": s["rate"], "ci": s["ci"]}
                             for name, s in result["common"].items()},
        "oracle_minus_learned": paired_difference(result["common_success"]["oracle"],
                                                  result["common_success"]["learned"]),
        "release": {"learned": release(learned[:m], task),
                    "oracle": release(result["oracle_actions"], task)},
        "void_reasons": {k or "not void": v for k, v in reasons.items()},
        "observations": m,
    }
    if task.n_dice == 1:
        report["strategy"] = {
            "learned": strategy_table(strategy(first, learned[:m], task)),
            "oracle": strategy_table(strategy(first, result["oracle_actions"], task))}
        report["by_turn"] = by_turn(success, tilt(batch.observations, task)[0])
    else:
        report["per_target"] = {str(k): v for k, v in
                                result["summary"]["learned"]["per_target"].items()}
    if task_id == CRAPS:
        report["sevens"] = sevens(model, QUICK["throws"] if quick else CRAPS_THROWS)
    return report


def sevens(model: Any, throws: int = CRAPS_THROWS) -> dict[str, Any]:
    """P(seven) of the learned and the set throw at each of :data:`AVOID_NOISES`."""
    out: dict[str, Any] = {"noises": list(AVOID_NOISES), "throws": throws}
    for name in ("learned", "set"):
        rows = []
        for noise in AVOID_NOISES:
            task, batch = evaluation(CRAPS, throws, SEED, hand_noise=noise,
                                     orientation_noise=noise)
            thrower = PolicyThrower(model) if name == "learned" else rule_throwers(task)["set"]
            hits = total_hits(task, batch, thrower)
            rows.append({"noise": noise, "counted": hits["counted"], "sevens": hits["hits"],
                         "p": hits["p"], "ci": hits["ci"], "below": bool(hits["ci"][1] < 1 / 6)})
        below = [r["noise"] for r in rows if r["below"]]
        out[name] = {"rows": rows, "largest_noise_below": max(below, default=None)}
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Analyse the tasks (default: every task with kept runs) into ``learned.json``.

    Each task's entry (with its own time and commit) replaces that task's in the file, which is
    written after each task; the other tasks' are kept, and so are the file's other keys (the
    ``sharpness`` and ``recipe`` rows of their own commands). Every argument, kept run and model is
    checked first: exit 2 with one line naming what cannot be used and how to go on.
    """
    from dice_env.envs.tasks import TASKS
    from dice_env.provenance import code_version

    parser = argparse.ArgumentParser(prog="python -m agents.learned",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--tasks", nargs="+", default=None, choices=[t.id for t in TASKS],
                        help="task ids (default: all kept)")
    parser.add_argument("--out", type=Path, default=RESULTS, help="the benchmark's results folder")
    parser.add_argument("--quick", action="store_true",
                        help="a smoke run: few throws, a tiny search, numbers meaningless")
    args = parser.parse_args(argv)
    if args.quick and args.out.resolve() == RESULTS.resolve():
        parser.error("--quick needs --out: its numbers must not replace the kept results")
    if not (args.out / "baselines").is_dir():
        parser.error(f"argument --out: {args.out} holds no baselines/ folder: pass the folder "
                     "python -m agents.benchmark --out wrote")
    kept = [t.id for t in TASKS if (args.out / "baselines" / t.id).is_dir()]
    if not (args.tasks or kept):
        parser.error(f"argument --out: {args.out} holds no kept run: run python -m "
                     "agents.benchmark first")
    path = args.out / "learned.json"
    try:
        stored = read_json(path, "delete it") if path.exists() else {}  # sharpness, recipe too
        reports = {r["task"]: r for r in stored.get("tasks", [])}
        for task_id in args.tasks or kept:  # before any work: each task's best model is there
            model_path(best_run(task_id, args.out, args.quick), args.out)
    except RunError as error:
        parser.error(str(error))
    for task_id in args.tasks or kept:
        start = time.perf_counter()
        try:
            r = analyse(task_id, args.out, args.quick)
        except KeyboardInterrupt:
            return interrupted(f"{path} keeps the tasks analysed before {task_id}; --tasks "
                               "analyses the others")
        reports[task_id] = {**r, "seconds": time.perf_counter() - start, "commit": code_version()}
        oracle = r["on_oracle_throws"]["oracle"]["rate"]
        print(f"{task_id:<24} {r['algo'].upper()} seed {r['seed']}: {r['learned']:.3f}; on the "
              f"oracle's throws {r['on_oracle_throws']['learned']['rate']:.3f} against the "
              f"oracle's {oracle:.3f}", flush=True)
        ordered = [reports[t.id] for t in TASKS if t.id in reports]
        commits = " ".join(sorted({r["commit"] for r in ordered}))  # the entries' own
        write_json(path, {**stored, "tasks": ordered, "command": "python -m agents.learned",
                          "commit": commits})
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

r"""The standard algorithms on every named task: one resumable command, one small JSON per run.

    python -m agents.benchmark                    # every task x PPO, A2C, SAC, TD3 x 3 seeds
    python -m agents.benchmark --tasks DiceThrow-v0 --algos sac --seeds 0
    python -m agents.benchmark --table            # the summary from the kept JSONs only
    python -m agents.benchmark --quick --out DIR  # a smoke run: tiny budgets, numbers meaningless

Each run (task, algorithm, seed) trains Stable-Baselines3's algorithm with its ``"benchmark"``
entry of :data:`agents.hyperparams.HYPERPARAMS` for the task's budget in throws
(:data:`agents.hyperparams.BUDGETS`: the same for every algorithm of a task), and at
``CURVE_POINTS`` evenly spaced points evaluates the policy's mean action on ``CURVE_THROWS``
fixed throws (success against throws and against training time: the process's CPU time, the
evaluations left out). At the end it scores the policy on the :data:`FINAL_THROWS` throws
``benchmarks/tasks.py`` scores random and the rule on (seed 0: the same targets, hands and hand
noise) and writes ``benchmarks/results/baselines/<task>/<algo>-<seed>.json``.

An interrupted run continues from its last curve point: at each point the model (and an
off-policy algorithm's replay buffer) is saved in a new checkpoint folder, then
``progress.json`` (the curve so far) names it, so a run stopped between the two resumes from the
point before and computes the lost one again. Checkpoints live in ``--out``'s ``runs/``
(``runs/benchmark/results/`` for the kept results). A resumed run is not bit-identical to an
uninterrupted one (the environment's and the algorithm's random streams restart), which its
JSON records (``resumed``). Every run takes one PyTorch thread and one kernel thread, so two
commands on different tasks share a 2-core machine.

Every result JSON and checkpoint records what it was made with (task, algorithm, seed, budget,
hyperparameters, evaluation throws and seeds, ``--quick``, the commit): a run whose JSON is kept
with the same is skipped; one made otherwise, or an unreadable file, is refused by name before
any training (exit 2), and ``--fresh`` trains it afresh. Every file is written whole (a
temporary name renamed into place).

``--table`` (and the end of every command) gathers the kept JSONs with ``--out``'s
``tasks.json`` (random, rule and oracle) into ``baselines.json`` and ``baselines.png``
(``docs/figures/`` for the kept results); a JSON of another budget or evaluation size, or a
curve of other points, is refused by name.
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.hyperparams import ALGOS, BUDGETS, algorithm_kwargs, entry
from agents.kept import RunError, differences, interrupted, read_json, readable_zip, write_json

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
RUNS = ROOT / "runs" / "benchmark"
SEEDS = (0, 1, 2)
CURVE_POINTS = 5  # evaluations along a run (the last at its budget)
CURVE_THROWS = 128  # fixed throws per curve evaluation
CURVE_SEED = 1  # their draw (the final evaluation's is benchmarks/tasks.py's seed 0)
FINAL_THROWS = 400  # as benchmarks/tasks.py
QUICK_BUDGET, QUICK_THROWS = 320, 16


def algorithm(name: str) -> type:
    """The Stable-Baselines3 class of ``name`` (one of :data:`ALGOS`)."""
    import stable_baselines3

    return getattr(stable_baselines3, name.upper())


def episode(task_id: str) -> dict[str, Any]:
    """The named task's episode keywords (a fixed target or total), as ``Batch.sample`` takes."""
    from agents.episodes import EPISODE_KEYWORDS
    from dice_env.envs.tasks import TASKS

    named = {t.id: t for t in TASKS}[task_id]
    return {k: v for k, v in named.keywords.items() if k in EPISODE_KEYWORDS}


def evaluation(task_id: str, throws: int, seed: int, **keywords: Any) -> tuple[Any, Any]:
    """The task (``keywords`` overriding its own) and the fixed throws policies are scored on."""
    import gymnasium as gym

    from agents.episodes import Batch

    task = gym.make(task_id, **{"num_threads": 1, **keywords}).unwrapped.task
    return task, Batch.sample(task, throws, np.random.default_rng(seed), num_threads=1,
                              **episode(task_id))


def success(model: Any, task: Any, batch: Any) -> dict[str, Any]:
    """The policy's mean action on ``batch``: rate, Wilson 95 % interval, throws."""
    from agents.episodes import PolicyThrower
    from agents.evaluate import rate

    return rate(np.asarray(batch.throw(task, PolicyThrower(model))["is_success"], bool))


FRESH = "pass --fresh to train it afresh"


def work_root(out: Path) -> Path:
    """Where the runs kept in results folder ``out`` keep their checkpoints.

    Inside ``out`` (``out/runs``); the kept results' (:data:`RESULTS`) in ``runs/benchmark/``.
    """
    return RUNS / "results" if out.resolve() == RESULTS.resolve() else out / "runs"


@functools.cache
def commit() -> str:
    """The code version results and checkpoints record (``git describe`` of the checkout)."""
    from dice_env.provenance import code_version

    return code_version()


class Run:
    """One (task, algorithm, seed): its files, its budget and its curve so far.

    ``final``: the final evaluation's throws and the seed that draws them. ``params``
    (default: the benchmark's entry) and ``kept_as`` (the results' subfolder and the run's name;
    default: ``baselines`` and ``algo-seed``) let the search (:mod:`agents.tune`) train other
    keywords into files of their own; ``quick``: a smoke run. ``identity`` is what the run is
    made with; a kept result or checkpoint is used only when it records the same.
    """

    def __init__(self, task_id: str, algo: str, seed: int, out: Path, budget: int,
                 curve_throws: int, final: tuple[int, int], *,
                 params: dict[str, Any] | None = None,
                 kept_as: tuple[str, str] | None = None, quick: bool = False) -> None:
        self.task_id, self.algo, self.seed, self.budget = task_id, algo, seed, budget
        self.curve_throws, (self.final_throws, self.final_seed) = curve_throws, final
        self.params = entry(task_id, algo) if params is None else params
        folder, name = ("baselines", f"{algo}-{seed}") if kept_as is None else kept_as
        self.result = out / folder / task_id / f"{name}.json"
        self.work = work_root(out) / task_id / name
        step = self.params["n_envs"]  # throws per env step
        self.points = sorted({-(-budget * (i + 1) // (CURVE_POINTS * step)) * step
                              for i in range(CURVE_POINTS)})
        self.identity = {
            "task": task_id, "algo": algo, "seed": seed, "budget": budget,
            "hyperparams": json.loads(json.dumps(self.params)), "quick": quick,
            "curve_points": CURVE_POINTS, "curve_throws": curve_throws, "curve_seed": CURVE_SEED,
            "final_throws": self.final_throws, "final_seed": self.final_seed, "commit": commit()}

    def kept(self) -> dict[str, Any] | None:
        """The kept result (None if there is none); :class:`RunError` if it is not this run's."""
        if not self.result.exists():
            return None
        result = read_json(self.result, f"delete it, or {FRESH}")
        differ = differences(result, self.identity)
        if differ:
            raise RunError(f"{self.result} was made with other settings ({differ}): {FRESH}")
        return result

    def progress(self) -> dict[str, Any] | None:
        """The last checkpoint's record (None if there is none).

        :class:`RunError` if it is not this run's or not whole.
        """
        path = self.work / "progress.json"
        if not path.exists():
            return None
        progress = read_json(path, FRESH)
        if "identity" not in progress:
            raise RunError(f"{self.work} holds a checkpoint that records no settings: {FRESH}")
        differ = differences(progress["identity"], self.identity)
        if differ:
            raise RunError(f"{self.work} holds a checkpoint of other settings ({differ}): {FRESH}")
        folder = self.work / str(progress.get("checkpoint"))
        for name in self.files():
            if not (folder / name).is_file():
                raise RunError(f"{folder / name} is missing: {FRESH}")
        readable_zip(folder / "model.zip", FRESH)
        return progress

    def files(self) -> tuple[str, ...]:
        """The files of a checkpoint: the model, and an off-policy algorithm's replay buffer."""
        from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm

        off_policy = issubclass(algorithm(self.algo), OffPolicyAlgorithm)
        return ("model.zip", "buffer.pkl") if off_policy else ("model.zip",)

    def check(self, fresh: bool) -> None:
        """Refuse (:class:`RunError`) a kept result or checkpoint that is not this run's.

        ``fresh``: remove them instead, so the run starts afresh.
        """
        for step in (self.kept, self.progress):
            try:
                step()
            except RunError:
                if not fresh:
                    raise
                self.result.unlink(missing_ok=True)
                shutil.rmtree(self.work, ignore_errors=True)

    def model(self, env: Any, progress: dict[str, Any] | None) -> Any:
        """A new model, or the one of the last checkpoint with its replay buffer."""
        cls = algorithm(self.algo)
        if progress is None:
            return cls(self.params["policy"], env, seed=self.seed, device="cpu",
                       **algorithm_kwargs(self.params, env.action_space.shape[0]))
        folder = self.work / progress["checkpoint"]
        try:
            model = cls.load(folder / "model.zip", env=env, device="cpu")
            if "buffer.pkl" in self.files():
                model.load_replay_buffer(folder / "buffer.pkl")
        except Exception as error:  # a foreign or corrupt file fails in many ways
            raise RunError(f"the checkpoint {folder} is unreadable ({type(error).__name__}: "
                           f"{error}): {FRESH}") from None
        if model.num_timesteps != progress["throws"]:
            raise RunError(f"the checkpoint {folder} holds a model of {model.num_timesteps} "
                           f"throws, its progress.json says {progress['throws']}: {FRESH}")
        return model

    def save(self, model: Any, state: dict[str, Any]) -> None:
        """A checkpoint as one unit: its files in a new folder, then ``progress.json`` naming it.

        The model and an off-policy buffer go in the folder, the curve so far in the progress;
        the older checkpoints are removed.

        A checkpoint stopped part-way is never named, so the run resumes from the one before.
        """
        self.work.mkdir(parents=True, exist_ok=True)
        name = f"checkpoint-{model.num_timesteps}"
        partial = Path(tempfile.mkdtemp(dir=self.work, prefix=f"{name}-", suffix=".partial"))
        model.save(partial / "model.zip")
        if "buffer.pkl" in self.files():
            model.save_replay_buffer(partial / "buffer.pkl")
        folder = partial.with_suffix("")
        os.replace(partial, folder)
        write_json(self.work / "progress.json", {
            **state, "throws": int(model.num_timesteps), "checkpoint": folder.name,
            "identity": self.identity})
        for old in self.work.glob("checkpoint-*"):
            if old != folder:
                shutil.rmtree(old, ignore_errors=True)


def train(run: Run, log: Any = print) -> dict[str, Any]:
    """Train (or continue) ``run`` to its budget, evaluating along the way; its result.

    :class:`RunError` if its checkpoint is not this run's or unreadable.
    """
    from stable_baselines3.common.callbacks import BaseCallback

    from dice_env.envs.sb3 import make_sb3_env

    params = run.params
    progress = run.progress()
    state = {"curve": [], "train_seconds": 0.0, "resumed": 0}
    if progress is not None:
        state = {key: progress[key] for key in state}
        state["resumed"] += 1
    env = make_sb3_env(params["n_envs"], seed=1000 * run.seed + len(state["curve"]),
                       env_id=run.task_id, num_threads=1, **params["env_kwargs"])
    model = run.model(env, progress)
    task, curve_batch = evaluation(run.task_id, run.curve_throws, CURVE_SEED)
    pending = [p for p in run.points if p > model.num_timesteps]

    class Checkpoints(BaseCallback):
        """At each curve point: evaluate, checkpoint; the evaluations' time left out.

        Training time is the process's CPU time: one PyTorch and one kernel thread taking
        turns, so other processes on the machine inflate it little.
        """

        def _on_training_start(self) -> None:
            self.started = time.process_time()

        def _on_step(self) -> bool:
            if pending and self.model.num_timesteps >= pending[0]:
                state["train_seconds"] += time.process_time() - self.started
                while pending and self.model.num_timesteps >= pending[0]:
                    pending.pop(0)
                point = {"throws": int(self.model.num_timesteps),
                         "train_seconds": state["train_seconds"],
                         **success(self.model, task, curve_batch)}
                state["curve"].append(point)
                run.save(self.model, state)
                log(f"{run.task_id} {run.algo} seed {run.seed}: {point['throws']} throws, "
                    f"success {point['rate']:.3f} ({point['train_seconds']:.0f} s training)")
                self.started = time.process_time()
            return bool(pending)  # at the budget: stop, so the last checkpoint is the model

    remaining = run.budget - model.num_timesteps
    if remaining > 0:
        model.learn(remaining, callback=Checkpoints(), reset_num_timesteps=progress is None,
                    progress_bar=False)
    task, final_batch = evaluation(run.task_id, run.final_throws, run.final_seed)
    return {**run.identity, "throws": int(model.num_timesteps), "curve": state["curve"],
            "final": success(model, task, final_batch), "train_seconds": state["train_seconds"],
            "resumed": state["resumed"]}


def keep(run: Run, log: Any = print) -> dict[str, Any]:
    """Train ``run`` unless its result is kept; its result, written whole."""
    result = run.kept()
    if result is None:
        result = train(run, log)
        run.result.parent.mkdir(parents=True, exist_ok=True)
        write_json(run.result, result)
    return result


TABLE_KEYS = ("task", "algo", "budget", "hyperparams", "curve_throws", "final_throws")


def benchmark_run(task_id: str, algo: str, seed: int, out: Path, quick: bool) -> Run:
    """The benchmark's run of (task, algorithm, seed) kept in ``out``; ``quick``: a smoke run's."""
    return Run(task_id, algo, seed, out, QUICK_BUDGET if quick else BUDGETS[task_id],
               QUICK_THROWS if quick else CURVE_THROWS,
               (QUICK_THROWS if quick else FINAL_THROWS, 0), quick=quick)


def kept_runs(out: Path, task_id: str, algo: str, quick: bool) -> list[dict[str, Any]]:
    """The kept results of ``algo`` on ``task_id`` in ``out``, by seed.

    :class:`RunError` naming one that is unreadable, not of the benchmark's settings
    (``quick``: the smoke run's; its own commit may differ) or whose curve has other points.
    """
    runs = []
    for path in sorted((out / "baselines" / task_id).glob(f"{algo}-*.json")):
        result = read_json(path, "delete it, or retrain it with --fresh")
        wanted = benchmark_run(task_id, algo, result.get("seed", 0), out, quick).identity
        differ = differences(result, {key: wanted[key] for key in TABLE_KEYS})
        if differ:
            raise RunError(f"{path} is not a run of this table ({differ}): delete it, or "
                           "retrain it with --fresh")
        runs.append(result)
    curves = {tuple(p["throws"] for p in r["curve"]) for r in runs}
    if len(curves) > 1:
        raise RunError(f"the kept {algo} runs of {task_id} in {out} have curves of different "
                       f"points ({sorted(curves)}): retrain the short ones with --fresh")
    return runs


def table(out: Path, quick: bool = False) -> dict[str, Any]:
    """Tasks x throwers from the kept runs and ``out/tasks.json``: mean, sd, [min, max] over seeds.

    ``quick``: of the smoke runs. :class:`RunError` if a kept run is not of the table's settings.
    """
    tasks = read_json(out / "tasks.json", "rerun python benchmarks/tasks.py")["tasks"]
    rows = []
    for t in tasks:
        row: dict[str, Any] = {"task": t["id"], "chance": t["chance"],
                               "budget": QUICK_BUDGET if quick else BUDGETS[t["id"]],
                               "fixed": {k: v["rate"] for k, v in t["rates"].items()},
                               "fixed_ci": {k: v["ci"] for k, v in t["rates"].items()},
                               "learned": {}}
        for algo in ALGOS:
            runs = kept_runs(out, t["id"], algo, quick)
            if not runs:
                continue
            finals = np.array([r["final"]["rate"] for r in runs])
            row["learned"][algo] = {
                "mean": float(finals.mean()), "sd": float(finals.std(ddof=1)) if len(runs) > 1
                else 0.0, "min": float(finals.min()), "max": float(finals.max()),
                "seeds": [r["seed"] for r in runs],
                "train_seconds": float(sum(r["train_seconds"] for r in runs)), "best_ci": max(
                    (r["final"] for r in runs), key=lambda f: f["rate"])["ci"],
                "curve": [[p["throws"], p["train_seconds"], p["rate"]] for p in
                          _mean_curve(runs)],
            }
        rows.append(row)
    return {"rows": rows, "algos": list(ALGOS),
            "command": "python -m agents.benchmark",
            "final_throws": QUICK_THROWS if quick else FINAL_THROWS,
            "curve_throws": QUICK_THROWS if quick else CURVE_THROWS, "commit": commit()}


def _mean_curve(runs: list[dict[str, Any]]) -> list[dict[str, float]]:
    """The seeds' curves (of the same points) averaged: throws, training seconds, success."""
    return [{key: float(np.mean([r["curve"][i][key] for r in runs]))
             for key in ("throws", "train_seconds", "rate")}
            for i in range(len(runs[0]["curve"]))]


def figure(summary: dict[str, Any], path: Path) -> None:
    """Learning curves, one column per task: success against throws (top), wall time (bottom)."""
    from agents.plots import plt, save

    rows = summary["rows"]
    fig, axes = plt.subplots(2, len(rows), figsize=(3.2 * len(rows), 5.6), squeeze=False)
    for j, row in enumerate(rows):
        for i, (x, label) in enumerate(((0, "throws"), (1, "training time (s)"))):
            ax = axes[i, j]
            for algo, learned in row["learned"].items():
                c = np.array(learned["curve"])
                ax.plot(c[:, x], c[:, 2], marker="o", ms=3, label=algo.upper())
            for name, style in (("oracle", "--"), ("random", ":")):
                ax.axhline(row["fixed"][name], color="k", ls=style, lw=1, label=name)
            ax.set_xlabel(label)
            ax.set_ylim(0, 1)
            if i == 0:
                ax.set_title(row["task"].replace("DiceThrow", "").replace("-v0", "") or "default",
                             fontsize=9)
        axes[0, j].set_ylabel("success" if j == 0 else "")
    axes[0, 0].legend(fontsize=7)
    save(fig, path)


def print_table(summary: dict[str, Any]) -> None:
    """The summary as text: mean ± sd [min, max] per algorithm, random, rule and oracle."""
    for row in summary["rows"]:
        fixed = "  ".join(f"{k} {v:.3f}" for k, v in row["fixed"].items())
        learned = "  ".join(f"{a.upper()} {v['mean']:.3f}±{v['sd']:.3f} [{v['min']:.3f}, "
                            f"{v['max']:.3f}]" for a, v in row["learned"].items())
        print(f"{row['task']:<24} {row['budget']:>7} throws  {learned}  |  {fixed}")


def out_problem(out: Path) -> str | None:
    """Why ``out`` cannot be a results folder (a file, or under one), or None."""
    if out.exists() and not out.is_dir():
        return f"{out} is a file, not a folder: pass a folder"
    parent = next(p for p in out.absolute().parents if p.exists())
    if not parent.is_dir():
        return f"{out} is under {parent}, a file: pass a folder"
    if not os.access(parent if not out.exists() else out, os.W_OK):
        return f"{out} is not writable: pass a folder you can write to"
    return None


def main(argv: Sequence[str] | None = None) -> int:
    """Train the runs not yet kept, then write the summary and the figure.

    Every argument and every kept result and checkpoint of the asked runs is checked first:
    exit 2 with one line naming what cannot be used and how to go on.
    """
    parser = argparse.ArgumentParser(prog="python -m agents.benchmark",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--tasks", nargs="+", default=list(BUDGETS), choices=list(BUDGETS),
                        help="task ids (default: every named task)")
    parser.add_argument("--algos", nargs="+", default=list(ALGOS), choices=ALGOS)
    parser.add_argument("--seeds", nargs="+", type=int, default=list(SEEDS))
    parser.add_argument("--table", action="store_true",
                        help="train nothing: the summary and figure from the kept JSONs")
    parser.add_argument("--quick", action="store_true",
                        help=f"a smoke run: budgets of {QUICK_BUDGET} throws, {QUICK_THROWS} "
                        "evaluation throws")
    parser.add_argument("--fresh", action="store_true",
                        help="train afresh the asked runs whose kept result or checkpoint was "
                        "made with other settings or code, or is unreadable (refused without it)")
    parser.add_argument("--out", type=Path, default=RESULTS,
                        help="results folder (default benchmarks/results)")
    args = parser.parse_args(argv)
    if any(s < 0 for s in args.seeds):
        parser.error(f"argument --seeds: must be integers >= 0, got {args.seeds}")
    if args.quick and args.out.resolve() == RESULTS.resolve():
        parser.error("--quick needs --out: its numbers must not replace the kept results")
    problem = out_problem(args.out)
    if problem:
        parser.error(f"argument --out: {problem}")
    summarise = args.table or (args.out / "tasks.json").exists()
    if args.table and not (args.out / "tasks.json").is_file():
        parser.error(f"argument --table: {args.out} has no tasks.json (the random, rule and "
                     "oracle rates): copy benchmarks/results/tasks.json there")
    runs = [] if args.table else [benchmark_run(task_id, algo, seed, args.out, args.quick)
                                  for task_id in args.tasks for algo in args.algos
                                  for seed in args.seeds]
    try:
        check(runs, args.fresh)
        _train(runs)
        if summarise:
            _summarise(args.out, args.quick)
        else:
            print(f"no summary: {args.out} has no tasks.json (the random, rule and oracle "
                  "rates); copy benchmarks/results/tasks.json there and add --table")
    except RunError as error:
        parser.error(str(error))
    except KeyboardInterrupt:
        return interrupted("every finished run and the last curve point of the one in training "
                           "are kept; the same command continues")
    return 0


def check(runs: list[Run], fresh: bool) -> None:
    """Every run's kept files checked (:meth:`Run.check`) before any training.

    One :class:`RunError`: the first run refused, and how many more are.
    """
    refused = []
    for run in runs:
        try:
            run.check(fresh)
        except RunError as error:
            refused.append(error)
    if refused:
        more = f" ({len(refused) - 1} more refused too)" if len(refused) > 1 else ""
        raise RunError(f"{refused[0]}{more}")


def _train(runs: list[Run]) -> None:
    """Train the runs not yet kept (one PyTorch thread each)."""
    import torch

    torch.set_num_threads(1)
    for run in runs:
        if run.kept() is None:
            result = keep(run)
            print(f"{run.task_id} {run.algo} seed {run.seed}: final "
                  f"{result['final']['rate']:.3f}", flush=True)


def _summarise(out: Path, quick: bool) -> None:
    """The summary, its figure and its table of the runs kept in ``out``."""
    summary = table(out, quick)
    write_json(out / "baselines.json", summary)
    figure(summary, (ROOT / "docs" / "figures" / "baselines.png")
           if out.resolve() == RESULTS.resolve() else out / "baselines.png")
    print_table(summary)


if __name__ == "__main__":
    sys.exit(main())

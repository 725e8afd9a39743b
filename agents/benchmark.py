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

An interrupted run continues from its last curve point: the model (and an off-policy
algorithm's replay buffer) is saved under ``runs/benchmark/`` beside the curve so far; a run
whose JSON exists is skipped. A resumed run is not bit-identical to an uninterrupted one (the
environment's and the algorithm's random streams restart), which its JSON records
(``resumed``). Every run takes one PyTorch thread and one kernel thread, so two commands on
different tasks share a 2-core machine.

``--table`` (and the end of every command) gathers the kept JSONs with ``tasks.json``'s random,
rule and oracle into ``benchmarks/results/baselines.json`` and ``docs/figures/baselines.png``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.hyperparams import ALGOS, BUDGETS, algorithm_kwargs, entry

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


class Run:
    """One (task, algorithm, seed): its files, its budget and its curve so far.

    ``final``: the final evaluation's throws and the seed that draws them. ``params``
    (default: the benchmark's entry), ``name`` (default: ``algo-seed``) and ``folder`` let the
    search (:mod:`agents.tune`) train other keywords into files of their own.
    """

    def __init__(self, task_id: str, algo: str, seed: int, out: Path, budget: int,
                 curve_throws: int, final: tuple[int, int], *,
                 params: dict[str, Any] | None = None, name: str | None = None,
                 folder: str = "baselines") -> None:
        self.task_id, self.algo, self.seed, self.budget = task_id, algo, seed, budget
        self.curve_throws, (self.final_throws, self.final_seed) = curve_throws, final
        self.params = entry(task_id, algo) if params is None else params
        name = f"{algo}-{seed}" if name is None else name
        self.result = out / folder / task_id / f"{name}.json"
        self.work = RUNS / out.name / task_id / name
        step = self.params["n_envs"]  # throws per env step
        self.points = sorted({-(-budget * (i + 1) // (CURVE_POINTS * step)) * step
                              for i in range(CURVE_POINTS)})

    def state(self) -> dict[str, Any]:
        """The curve and wall time kept at the last checkpoint (empty for a new run)."""
        path = self.work / "progress.json"
        if path.exists() and (self.work / "model.zip").exists():
            return json.loads(path.read_text())
        return {"curve": [], "train_seconds": 0.0, "resumed": 0}

    def model(self, env: Any, resumed: bool) -> Any:
        """A new model, or the one saved at the last checkpoint with its replay buffer."""
        cls = algorithm(self.algo)
        if resumed:
            model = cls.load(self.work / "model.zip", env=env, device="cpu")
            if (self.work / "buffer.pkl").exists():
                model.load_replay_buffer(self.work / "buffer.pkl")
            return model
        params = self.params
        return cls(params["policy"], env, seed=self.seed, device="cpu",
                   **algorithm_kwargs(params, env.action_space.shape[0]))

    def save(self, model: Any, state: dict[str, Any]) -> None:
        """A checkpoint: the model, an off-policy buffer, and the curve so far."""
        self.work.mkdir(parents=True, exist_ok=True)
        model.save(self.work / "model.zip")
        if hasattr(model, "replay_buffer"):
            model.save_replay_buffer(self.work / "buffer.pkl")
        (self.work / "progress.json").write_text(json.dumps(state))


def train(run: Run, log: Any = print) -> dict[str, Any]:
    """Train (or continue) ``run`` to its budget, evaluating along the way; its result."""
    from stable_baselines3.common.callbacks import BaseCallback

    from dice_env.envs.sb3 import make_sb3_env
    from dice_env.provenance import code_version

    params = run.params
    state = run.state()
    resumed = bool(state["curve"])
    state["resumed"] += resumed
    env = make_sb3_env(params["n_envs"], seed=1000 * run.seed + len(state["curve"]),
                       env_id=run.task_id, num_threads=1, **params["env_kwargs"])
    model = run.model(env, resumed)
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
        model.learn(remaining, callback=Checkpoints(), reset_num_timesteps=not resumed,
                    progress_bar=False)
    task, final_batch = evaluation(run.task_id, run.final_throws, run.final_seed)
    return {
        "task": run.task_id, "algo": run.algo, "seed": run.seed, "budget": run.budget,
        "throws": int(model.num_timesteps), "hyperparams": params,
        "curve": state["curve"], "final": success(model, task, final_batch),
        "train_seconds": state["train_seconds"], "resumed": state["resumed"],
        "curve_throws": run.curve_throws, "final_throws": run.final_throws,
        "commit": code_version(),
    }


def table(out: Path) -> dict[str, Any]:
    """Tasks x throwers from the kept runs and ``tasks.json``: mean, sd, [min, max] over seeds."""
    tasks = json.loads((RESULTS / "tasks.json").read_text())["tasks"]
    rows = []
    for t in tasks:
        row: dict[str, Any] = {"task": t["id"], "chance": t["chance"], "budget": BUDGETS[t["id"]],
                               "fixed": {k: v["rate"] for k, v in t["rates"].items()},
                               "fixed_ci": {k: v["ci"] for k, v in t["rates"].items()},
                               "learned": {}}
        for algo in ALGOS:
            runs = [json.loads(p.read_text())
                    for p in sorted((out / "baselines" / t["id"]).glob(f"{algo}-*.json"))]
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
    from dice_env.provenance import code_version

    return {"rows": rows, "algos": list(ALGOS),
            "command": "python -m agents.benchmark", "final_throws": FINAL_THROWS,
            "curve_throws": CURVE_THROWS, "commit": code_version()}


def _mean_curve(runs: list[dict[str, Any]]) -> list[dict[str, float]]:
    """The seeds' curves averaged point by point (throws, training seconds, success)."""
    n = min(len(r["curve"]) for r in runs)
    return [{key: float(np.mean([r["curve"][i][key] for r in runs]))
             for key in ("throws", "train_seconds", "rate")} for i in range(n)]


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


def main(argv: Sequence[str] | None = None) -> int:
    """Train the runs not yet kept, then write the summary and the figure."""
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
    parser.add_argument("--out", type=Path, default=RESULTS,
                        help="results folder (default benchmarks/results)")
    args = parser.parse_args(argv)
    if any(s < 0 for s in args.seeds):
        parser.error(f"--seeds must be >= 0, got {args.seeds}")
    if args.quick and args.out.resolve() == RESULTS.resolve():
        parser.error("--quick needs --out: its numbers must not replace the kept results")
    import torch

    torch.set_num_threads(1)
    if not args.table:
        for task_id in args.tasks:
            for algo in args.algos:
                for seed in args.seeds:
                    run = Run(task_id, algo, seed, args.out,
                              QUICK_BUDGET if args.quick else BUDGETS[task_id],
                              QUICK_THROWS if args.quick else CURVE_THROWS,
                              (QUICK_THROWS if args.quick else FINAL_THROWS, 0))
                    if run.result.exists():
                        continue
                    result = train(run)
                    run.result.parent.mkdir(parents=True, exist_ok=True)
                    run.result.write_text(json.dumps(result, indent=1) + "\n")
                    print(f"{task_id} {algo} seed {seed}: final {result['final']['rate']:.3f}",
                          flush=True)
    if args.quick and args.table:
        return 0
    if (args.out / "tasks.json").exists() or args.out.resolve() == RESULTS.resolve():
        summary = table(args.out)
        (args.out / "baselines.json").write_text(json.dumps(summary, indent=1) + "\n")
        figure(summary, (ROOT / "docs" / "figures" / "baselines.png") if args.out.resolve()
               == RESULTS.resolve() else args.out / "baselines.png")
        print_table(summary)
    return 0


if __name__ == "__main__":
    sys.exit(main())

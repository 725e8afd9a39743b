"""Train PPO (Stable-Baselines3) on a named dice task's natively batched env, then evaluate it.

    python -m agents.train                     # quick preset: train, evaluate, write report.md
    python -m agents.train --preset best       # longer run for the best result
    python -m agents.train --env-id DiceThrowD20-v0  # any registered task (python train.py --help)
    python -m agents.train --seeds 3           # three seeds: mean and spread in one report
    python -m agents.train --sweep release_height=0.015,0.03 hand_noise=0.02,0.05
    python -m agents.train --resume runs/NAME  # continue a run (or group) from its checkpoints
    python -m agents.train --help              # every option (agents/config.py)

Each run writes to ``runs/NAME/``: ``config.json`` (with the seed), ``hyperparams.json``,
``checkpoints/``, ``training.jsonl`` (throws, wall-clock and CPU seconds per session),
``tb/`` (TensorBoard), ``eval/`` (the success rate during training:
``evaluations.npz`` and ``start.json``, the policy before PPO's first update), ``model.zip`` and
the evaluation (``report.md`` and its figures). A group (``--seeds``, ``--sweep``) holds one
such run per setting and seed and its own ``report.md`` comparing them.

Options are checked before any folder is made; an existing ``--name`` is refused unless
``--overwrite`` is given. Ctrl-C saves the model and a checkpoint, writes a ``report.md`` that
says the run was interrupted and how to resume it, and exits with status 130; ``--resume``
continues from the newest readable checkpoint (an unreadable one is reported and skipped) with
the optimizer state and the step count, appending to the same TensorBoard run.
"""

from __future__ import annotations

import os

# Idle OpenMP threads of the kernel sleep instead of spinning, so PyTorch gets the cores.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import dataclasses
import importlib.util
import json
import math
import re
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import (
    BaseCallback,
    CallbackList,
    CheckpointCallback,
    EvalCallback,
)
from stable_baselines3.common.vec_env import VecEnv

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from agents.config import Config, is_run_folder, parse_config
from agents.kept import INTERRUPTED, write_json, write_saved, write_text
from agents.progress import Bar
from dice_env.envs.sb3 import make_sb3_env

CHECKPOINT_PREFIX = "ppo"


class Interrupted(Exception):
    """Ctrl-C during a run's training or evaluation; the model is saved."""

    def __init__(self, run: Path, stage: str) -> None:
        super().__init__(f"{stage} of {run} interrupted")
        self.run = run
        self.stage = stage


def rollout_end(start: int, total: int, rollout: int) -> int:
    """The step count at which ``learn`` stops: ``total`` rounded up to whole rollouts."""
    return start + max(0, math.ceil((total - start) / rollout)) * rollout


class ProgressBar(BaseCallback):
    """A bar over the training throws, ending at the throws ``learn`` will actually make."""

    def __init__(self, total: int) -> None:
        super().__init__()
        self.total = total
        self.bar: Bar | None = None

    def _on_training_start(self) -> None:
        self.bar = Bar(self.total, "training", "throw", initial=self.model.num_timesteps)

    def _on_step(self) -> bool:
        assert self.bar is not None
        self.bar.update(self.model.num_timesteps - self.bar.n)
        return True

    def _on_training_end(self) -> None:
        assert self.bar is not None
        self.bar.close()


class ResumableEval(EvalCallback):
    """SB3's EvalCallback that keeps the evaluations of earlier sessions of the run.

    SB3's own rewrites ``evaluations.npz`` with only this session's evaluations, so a resumed
    run would lose the start of its learning curve.
    """

    def _init_callback(self) -> None:
        super()._init_callback()
        path = Path(f"{self.log_path}.npz") if self.log_path else None
        if path is not None and path.exists():
            with np.load(path) as old:
                self.evaluations_timesteps = old["timesteps"].tolist()
                self.evaluations_results = old["results"].tolist()
                self.evaluations_length = old["ep_lengths"].tolist()
                if "successes" in old:
                    self.evaluations_successes = old["successes"].tolist()


def imitate(model: PPO, config: Config, throws: int, steps: int,
            batch: int = 256) -> tuple[str, float]:
    """Warm start: fit the policy's mean action to the task's rule (MSE); its name, final loss.

    The rule is :func:`agents.baselines.task_rule`'s (the hand-written thrower for one die).
    Observations are drawn as the env draws them (no simulation is needed: the rule only reads
    the observation).
    """
    import torch

    from agents.baselines import task_rule
    from agents.episodes import Batch, make_eval_task

    task, episode = make_eval_task(config)
    rule = task_rule(task)
    if rule is None:  # agents.config.check refuses such a preset first
        raise ValueError(f"{config.env_id} with {config.env_kwargs()} has no rule to imitate")
    data = Batch.sample(task, throws, np.random.default_rng(config.seed + 3 * 10**6), **episode)
    obs = torch.as_tensor(data.observations)
    actions = torch.as_tensor(rule[1](data.observations), dtype=torch.float32)
    policy = model.policy
    # Its own optimizer: PPO's Adam must not inherit moment estimates of this regression.
    optimizer = torch.optim.Adam(policy.parameters(), lr=1e-3)
    generator = torch.Generator().manual_seed(config.seed)
    loss = torch.zeros(())
    for _ in range(steps):
        idx = torch.randint(0, throws, (batch,), generator=generator)
        mean = policy.get_distribution(obs[idx]).distribution.mean
        loss = torch.nn.functional.mse_loss(mean, actions[idx])
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
    return rule[0], loss.item()


def evaluate_start(model: PPO, eval_env: VecEnv, episodes: int, run: Path,
                   warm_start: bool) -> float:
    """Success of the policy before PPO's first update (the learning curve's first point)."""
    from stable_baselines3.common.evaluation import evaluate_policy

    rewards, _ = evaluate_policy(model, eval_env, n_eval_episodes=episodes, deterministic=True,
                                 return_episode_rewards=True)
    success = float(np.mean(rewards))  # the evaluation env has no shaping: reward = success
    (run / "eval").mkdir(exist_ok=True)
    write_json(run / "eval" / "start.json", {"timesteps": 0, "success": success,
                                             "episodes": episodes, "warm_start": warm_start},
               indent=None)
    return success


def checkpoints(run: Path) -> list[Path]:
    """The run's checkpoints, newest (most steps) first."""
    found = [(int(m.group(1)), p) for p in (run / "checkpoints").glob("*.zip")
             if (m := re.search(r"_(\d+)_steps\.zip$", p.name))]
    return [p for _, p in sorted(found, reverse=True)]


def load_checkpoint(run: Path, **kwargs: Any) -> PPO | None:
    """PPO from the newest readable checkpoint; an unreadable one is reported and skipped.

    None when the run has no readable checkpoint.
    """
    for path in checkpoints(run):
        try:
            model = PPO.load(path, device="cpu", **kwargs)
        except Exception as error:  # a truncated or corrupt zip fails in many ways
            print(f"checkpoint {path} is unreadable ({type(error).__name__}: {error}); "
                  "falling back to the previous one", file=sys.stderr)
            continue
        print(f"resuming {run} from {path.name} ({model.num_timesteps} throws)")
        return model
    return None


def new_run(config: Config) -> Path:
    """Create the run (or group) folder and write its config and hyperparameters.

    ``--overwrite`` removes an existing run folder first (checked to be one by
    :func:`agents.config.check`).
    """
    config.name = config.name or config.default_name()
    run = Path(config.runs) / config.name
    if config.overwrite and is_run_folder(run):
        shutil.rmtree(run)
        print(f"removed the earlier {run} (--overwrite)")
    run.mkdir(parents=True, exist_ok=False)
    config.save(run / "config.json")
    write_json(run / "hyperparams.json", config.hyperparams(), indent=2)
    return run


def resumed_config(given: Config) -> Config:
    """The config saved in ``given.resume``, with the options a resume may change."""
    run = Path(str(given.resume))
    config = Config.load(run / "config.json")
    config.progress, config.evaluate = given.progress, given.evaluate
    if given.total_timesteps is not None and given.total_timesteps != config.total_timesteps:
        config.total_timesteps = given.total_timesteps
        config.save(run / "config.json")
    return config


def train(config: Config, run: Path | None = None) -> Path:
    """Train a new run (``run`` None) or continue ``run`` from its checkpoint; its folder.

    Ctrl-C saves the model and a checkpoint and raises :class:`Interrupted`.
    """
    resuming = run is not None
    run = run if run is not None else new_run(config)
    params = config.hyperparams()
    n_envs = params["n_envs"]
    env_kwargs = {**config.env_kwargs(), **config.num_threads_kwargs()}
    env = make_sb3_env(n_envs, config.seed, env_id=config.env_id,
                       **{**env_kwargs, **params["env_kwargs"]})
    eval_env = make_sb3_env(min(n_envs, config.eval_episodes), config.seed + 10**6,
                            env_id=config.env_id, **env_kwargs)
    tensorboard = run / "tb" if importlib.util.find_spec("tensorboard") else None
    if tensorboard is None:
        print("tensorboard is not installed: no TensorBoard logs", file=sys.stderr)
    model = load_checkpoint(run, env=env, tensorboard_log=tensorboard) if resuming else None
    fresh = model is None
    if fresh and resuming:
        print(f"{run} has no readable checkpoint: training starts over", file=sys.stderr)
    if model is None:
        model = PPO(params["policy"], env, seed=config.seed, tensorboard_log=tensorboard,
                    device="cpu", verbose=0, **config.ppo_kwargs(env.get_attr("task")[0].scene.die))
        warm = bool(params.get("imitation_steps"))
        if warm:
            rule, loss = imitate(model, config, params["imitation_throws"],
                                 params["imitation_steps"])
            print(f"warm start: imitated the {rule} throw, MSE {loss:.2e}")
        start = evaluate_start(model, eval_env, config.eval_episodes, run, warm)
        print(f"success before PPO's first update: {start:.3f}")
    try:
        _learn(model, config, run, eval_env, fresh)
    finally:
        env.close()
        eval_env.close()
    return run


def _learn(model: PPO, config: Config, run: Path, eval_env: VecEnv, fresh: bool) -> None:
    """``model.learn`` to the config's total with checkpoints, evaluations and a bar."""
    params = config.hyperparams()
    n_envs, total = params["n_envs"], params["n_timesteps"]
    end = rollout_end(model.num_timesteps, total, model.n_steps * n_envs)
    if end == model.num_timesteps:
        print(f"{run} is already trained to {model.num_timesteps} throws")
        return
    if end != total:
        print(f"training to {end} throws ({total} rounded up to whole rollouts of "
              f"{model.n_steps} steps × {n_envs} envs)")
    callbacks: list[BaseCallback] = [
        CheckpointCallback(max(1, config.checkpoint_freq // n_envs), str(run / "checkpoints"),
                           name_prefix=CHECKPOINT_PREFIX),
        ResumableEval(eval_env, n_eval_episodes=config.eval_episodes,
                      eval_freq=max(1, config.eval_freq // n_envs), log_path=str(run / "eval"),
                      best_model_save_path=str(run / "eval"), deterministic=True, verbose=0),
    ]
    if config.progress:
        callbacks.append(ProgressBar(end))
    start, cpu = time.perf_counter(), time.process_time()
    interrupted = False
    try:
        model.learn(total - model.num_timesteps, callback=CallbackList(callbacks),
                    tb_log_name="ppo", reset_num_timesteps=fresh)
    except KeyboardInterrupt:
        interrupted = True
    except RuntimeError as error:  # Ctrl-C inside torch's zip writer, saving a checkpoint
        if not isinstance(error.__context__, KeyboardInterrupt):
            raise
        interrupted = True  # that checkpoint is rewritten whole below (the same step)
    finally:
        (run / "checkpoints").mkdir(exist_ok=True)
        write_saved(run / "checkpoints" / f"{CHECKPOINT_PREFIX}_{model.num_timesteps}_steps.zip",
                    model.save)
        write_saved(run / "model.zip", model.save)
        log = {"throws": model.num_timesteps, "seconds": time.perf_counter() - start,
               "cpu_seconds": time.process_time() - cpu, "interrupted": interrupted}
        with open(run / "training.jsonl", "a") as f:
            f.write(json.dumps(log) + "\n")
    if interrupted:
        raise Interrupted(run, "training")


def evaluated(run: Path) -> bool:
    """Whether the run's evaluation is newer than its model."""
    report, model = run / "evaluation.json", run / "model.zip"
    return (report.exists() and model.exists()
            and report.stat().st_mtime >= model.stat().st_mtime)


def evaluate(run: Path, progress: bool) -> None:
    """The run's final evaluation and report; Ctrl-C raises :class:`Interrupted`."""
    from agents.evaluate import evaluate_run

    try:
        evaluate_run(run, progress=progress)
    except KeyboardInterrupt:
        raise Interrupted(run, "evaluation") from None


def write_interrupted(error: Interrupted, resume: Path) -> Path:
    """A report.md in the interrupted run that says what is saved and how to continue."""
    run = error.run
    config = Config.load(run / "config.json")
    lines = [f"# {config.name}: interrupted", ""]
    if error.stage == "training":
        sessions = (run / "training.jsonl").read_text().splitlines()
        throws = json.loads(sessions[-1])["throws"]
        total = config.hyperparams()["n_timesteps"]
        lines += [f"**Training was interrupted (Ctrl-C) at {throws} of {total} throws; this run "
                  "is not evaluated.** The model and a checkpoint at that step are saved "
                  f"(`model.zip`, `checkpoints/{CHECKPOINT_PREFIX}_{throws}_steps.zip`).", "",
                  f"Continue training and evaluate: `python train.py --resume {resume}`"]
    else:
        lines += ["**The evaluation was interrupted (Ctrl-C); the trained model is saved "
                  "(`model.zip`).**", "",
                  f"Evaluate: `python -m agents.evaluate {run}`"
                  + (f", or `python train.py --resume {resume}`" if resume != run else "")]
    path = run / "report.md"
    write_text(path, "\n".join(lines) + "\n")
    return path


def run_one(config: Config) -> Path:
    """Train (or resume) one run and evaluate it unless it is evaluated already."""
    if config.resume is not None:
        run = Path(config.resume)
        config = resumed_config(config)
        train(config, run)
    else:
        run = train(config)
    if config.evaluate and not evaluated(run):
        evaluate(run, config.progress)
    return run


def run_group(config: Config) -> Path:
    """Train and evaluate every member of a group (seeds, sweep); write the group's report."""
    given = config
    if config.resume is not None:
        group = Path(config.resume)
        config = resumed_config(config)
    else:
        group = new_run(config)
    members = config.members()
    for k, member in enumerate(members, 1):
        run = Path(member.runs) / str(member.name)
        print(f"[{k}/{len(members)}] {run}")
        if is_run_folder(run):
            run_one(dataclasses.replace(Config(), resume=str(run), progress=config.progress,
                                        evaluate=config.evaluate,
                                        total_timesteps=given.total_timesteps))
        else:
            run_one(member)
    if config.evaluate:
        from agents.sweep_report import write_group_report

        path = write_group_report(group)
        print(f"wrote {path}")
    return group


def main(argv: list[str] | None = None) -> None:
    """Train, evaluate and report; exits with status 130 after Ctrl-C (the model saved)."""
    config = parse_config(argv, prog="train.py")
    resume = Path(config.resume) if config.resume else None
    group = Config.load(resume / "config.json").is_group() if resume else config.is_group()
    top = resume
    try:
        if group:
            run_group(config)
        else:
            run_one(config)
    except Interrupted as error:
        top = top or Path(config.runs) / str(config.name)
        path = write_interrupted(error, top)
        if top != error.run:
            write_text(top / "report.md", f"# {top.name}: interrupted\n\n**The group was "
                       f"interrupted (Ctrl-C) in {error.run.name}** ({error.stage}); see its "
                       f"report.md. Continue: `python train.py --resume {top}`\n")
        print(f"\n{error}: saved; wrote {path}; continue with: python train.py --resume {top}",
              file=sys.stderr)
        sys.exit(INTERRUPTED)
    except KeyboardInterrupt:
        top = top or (Path(config.runs) / config.name if config.name else None)
        where = (f"python train.py --resume {top} starts it over" if top and top.exists()
                 else "nothing was saved")
        print(f"\ninterrupted before the first checkpoint: {where}", file=sys.stderr)
        sys.exit(INTERRUPTED)


if __name__ == "__main__":
    main()

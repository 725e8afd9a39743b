"""Train PPO (Stable-Baselines3) on the natively batched DiceThrow env, then evaluate it.

    python -m agents.train                     # quick preset: train, evaluate, write report.md
    python -m agents.train --preset best       # longer run for the best result
    python -m agents.train --resume runs/NAME  # continue a run from its last checkpoint
    python -m agents.train --help              # every option (agents/config.py)

Each run writes to ``runs/NAME/``: ``config.json`` (with the seed), ``hyperparams.json``,
``checkpoints/``, ``tb/`` (TensorBoard), ``eval/`` (EvalCallback's success rate during training),
``model.zip`` and the evaluation (``report.md`` and its figures). Ctrl-C saves a checkpoint and
the model; ``--resume`` continues from the newest checkpoint with the optimizer state and the step
count, appending to the same TensorBoard run.
"""

from __future__ import annotations

import os

# Idle OpenMP threads of the kernel sleep instead of spinning, so PyTorch gets the cores.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import importlib.util
import json
import re
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import (
    BaseCallback,
    CallbackList,
    CheckpointCallback,
    EvalCallback,
)
from stable_baselines3.common.vec_env import VecEnv, VecMonitor

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from agents.config import Config, parse_config

CHECKPOINT_PREFIX = "ppo"


def make_vec_env(env_id: str, n_envs: int, seed: int, **env_kwargs: Any) -> VecEnv:
    """``n_envs`` envs as one SB3 VecEnv over the native batch (one kernel call per step)."""
    from dice_env.envs.sb3 import DiceThrowSB3VecEnv

    env = VecMonitor(DiceThrowSB3VecEnv(gym.make_vec(env_id, num_envs=n_envs,
                                                     vectorization_mode=None, **env_kwargs)))
    env.seed(seed)
    return env


class ProgressBar(BaseCallback):
    """A tqdm bar over the training throws."""

    def __init__(self, total: int) -> None:
        super().__init__()
        self.total = total
        self.bar: Any = None

    def _on_training_start(self) -> None:
        from tqdm.auto import tqdm

        self.bar = tqdm(total=self.total, initial=self.model.num_timesteps, unit="throw",
                        dynamic_ncols=True)

    def _on_step(self) -> bool:
        self.bar.update(self.model.num_timesteps - self.bar.n)
        return True

    def _on_training_end(self) -> None:
        self.bar.close()


def imitate(model: PPO, config: Config, throws: int, steps: int, batch: int = 256) -> float:
    """Warm start: fit the policy's mean action to the hand-written thrower's (MSE).

    Observations are drawn as the env draws them (no simulation is needed: the hand-written
    thrower only reads the observation). Returns the final loss.
    """
    import numpy as np
    import torch

    from agents.baselines import HandThrower
    from agents.evaluate import Batch, make_eval_task

    task, episode = make_eval_task(config)
    data = Batch.sample(task, throws, np.random.default_rng(config.seed + 3 * 10**6), **episode)
    obs = torch.as_tensor(data.observations)
    actions = torch.as_tensor(HandThrower(task)(data.observations), dtype=torch.float32)
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
    return loss.item()


def last_checkpoint(run: Path) -> Path | None:
    """The checkpoint with the most steps in ``run/checkpoints`` (None if there is none)."""
    found = [(int(m.group(1)), p) for p in (run / "checkpoints").glob("*.zip")
             if (m := re.search(r"_(\d+)_steps\.zip$", p.name))]
    return max(found)[1] if found else None


def new_run(config: Config) -> Path:
    """Create the run folder and write its config and hyperparameters."""
    name = config.name or (f"{config.env_id}_{config.preset}_s{config.seed}_"
                           f"{time.strftime('%Y%m%d-%H%M%S')}")
    run = Path(config.runs) / name
    run.mkdir(parents=True, exist_ok=False)
    config.name = name
    config.save(run / "config.json")
    (run / "hyperparams.json").write_text(json.dumps(config.hyperparams(), indent=2) + "\n")
    return run


def train(config: Config) -> Path:
    """Train (or resume) a run; returns its folder. Ctrl-C stops early and saves."""
    resuming = config.resume is not None
    if resuming:
        run = Path(config.resume)
        given = config
        config = Config.load(run / "config.json")
        config.progress, config.evaluate = given.progress, given.evaluate
        if given.total_timesteps is not None:
            config.total_timesteps = given.total_timesteps
            config.save(run / "config.json")
    else:
        run = new_run(config)
    params = config.hyperparams()
    n_envs, total = params["n_envs"], params["total_timesteps"]
    env_kwargs = {**config.env_kwargs(), **config.num_threads_kwargs()}
    env = make_vec_env(config.env_id, n_envs, config.seed, **{**env_kwargs, **params["train_env"]})
    eval_env = make_vec_env(config.env_id, min(n_envs, config.eval_episodes), config.seed + 10**6,
                            **env_kwargs)
    tensorboard = run / "tb" if importlib.util.find_spec("tensorboard") else None
    if tensorboard is None:
        print("tensorboard is not installed: no TensorBoard logs", file=sys.stderr)
    checkpoint = last_checkpoint(run) if resuming else None
    if checkpoint is not None:
        model = PPO.load(checkpoint, env=env, tensorboard_log=tensorboard, device="cpu")
        print(f"resuming {run} from {checkpoint.name} ({model.num_timesteps} throws)")
    else:
        model = PPO("MlpPolicy", env, seed=config.seed, tensorboard_log=tensorboard,
                    device="cpu", verbose=0, **config.ppo_kwargs())
        if params["imitation_steps"]:
            loss = imitate(model, config, params["imitation_throws"], params["imitation_steps"])
            print(f"warm start: imitated the hand-written thrower, MSE {loss:.2e}")
    callbacks: list[BaseCallback] = [
        CheckpointCallback(max(1, config.checkpoint_freq // n_envs), str(run / "checkpoints"),
                           name_prefix=CHECKPOINT_PREFIX),
        EvalCallback(eval_env, n_eval_episodes=config.eval_episodes,
                     eval_freq=max(1, config.eval_freq // n_envs), log_path=str(run / "eval"),
                     best_model_save_path=str(run / "eval"), deterministic=True, verbose=0),
    ]
    if config.progress:
        callbacks.append(ProgressBar(total))
    start = time.perf_counter()
    try:
        model.learn(max(0, total - model.num_timesteps), callback=CallbackList(callbacks),
                    tb_log_name="ppo", reset_num_timesteps=checkpoint is None)
    except KeyboardInterrupt:
        print(f"\ninterrupted at {model.num_timesteps} throws: saving; continue with "
              f"--resume {run}")
    finally:
        model.save(run / "checkpoints" / f"{CHECKPOINT_PREFIX}_{model.num_timesteps}_steps")
        model.save(run / "model")
        log = {"throws": model.num_timesteps, "seconds": time.perf_counter() - start}
        with open(run / "training.jsonl", "a") as f:
            f.write(json.dumps(log) + "\n")
        env.close()
        eval_env.close()
    return run


def main(argv: list[str] | None = None) -> None:
    """Train, then evaluate the run and write its report."""
    config = parse_config(argv, prog="train.py")
    run = train(config)
    if config.evaluate:
        from agents.evaluate import evaluate_run

        evaluate_run(run)


if __name__ == "__main__":
    main()

"""Recommended PPO hyperparameters per env id, for plain PPO from scratch (like rl-zoo3's).

    from stable_baselines3 import PPO
    from agents.hyperparams import PPO_HYPERPARAMS, ppo_kwargs
    from dice_env.envs.sb3 import make_sb3_env

    hp = PPO_HYPERPARAMS["DiceThrow-v0"]
    env = make_sb3_env(hp["n_envs"], seed=0, **hp["env_kwargs"])
    model = PPO(hp["policy"], env, seed=0, **ppo_kwargs("DiceThrow-v0"))
    model.learn(hp["n_timesteps"])

Each entry holds the policy, the number of envs stepped together (one kernel call), the training
budget in throws, the env keywords used for training (evaluate on the task without them) and
PPO's keywords. No imitation, no custom features: ``MlpPolicy`` on the raw observation (target
one-hot and hand orientation).

Where DiceThrow-v0's values come from: ``python benchmarks/learn_from_scratch.py`` (default task:
1.5 cm release, 5 % hand noise; success of the policy's mean action on fixed random throws; one
kernel thread and one PyTorch thread). Its learning curve and final success with them, against
the hand-written thrower on the same throws, are kept in
``benchmarks/results/learn_from_scratch.json`` and shown in docs/agents.md with the oracle's.
Variants, each changing one
value (``--set KEY=VALUE``), single runs on 512 fixed throws (``--eval-throws 512``; this set
reads 0.02-0.03 above larger ones near the top), their results not kept:

* Every episode is one throw, so the advantage is the reward minus the value whatever ``gamma``
  and ``gae_lambda`` are; they stay at SB3's defaults.
* ``log_std_init=-2`` (action noise 0.135): with a constant learning rate of 3e-4, after 150k
  throws 0.52 at -1, 0.84 at -2, 0.63 at -2.5 (less exploration, a later start).
* The learning rate decays linearly to 0: a constant 3e-4 peaked at 0.93 after 325k throws and
  drifted to 0.90-0.92 by 525k; a constant 1e-3 stalled at 0.84 (175k), one decaying from 1e-3
  over 400k at 0.89 (325k); 20 epochs per update instead of 10: 0.93 after 400k, no better than 10.
* ``shaping=0.5`` (``0.5 n_target . n_table`` added to the reward) and ``until="decided"`` (each
  throw ends when its face is decided: the same faces, about 3x faster) as agents/train.py
  trains; not varied here.
* ``n_envs=256`` throws per kernel call, 4 steps per rollout: 1024 throws per update in batches
  of 256.

What limits it is the mapping from the observation to the throw: the target's direction in the
world is a product of the one-hot and the orientation matrix, which the MLP has to learn; its
failures are the targets that must turn more than 120 degrees. Given that product as a feature
(``--set features_extractor_class=agents.policy:TargetNormal --throws 400000``), the same
hyperparameters reach 0.96 after 150k throws and 0.97 after 400k (0.971 on 1000 throws to rest),
as the imitation warm start does.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
from stable_baselines3.common.utils import LinearSchedule

# The keys of an entry that are not PPO keywords (as in rl-zoo3's files).
NON_PPO_KEYS = ("policy", "n_envs", "n_timesteps", "env_kwargs")

PPO_HYPERPARAMS: dict[str, dict[str, Any]] = {
    "DiceThrow-v0": {
        "policy": "MlpPolicy",
        "n_envs": 256,
        "n_timesteps": 800_000,
        "env_kwargs": {"shaping": 0.5, "until": "decided"},
        "n_steps": 4,
        "batch_size": 256,
        "n_epochs": 10,
        "learning_rate": "lin_3e-4",
        "policy_kwargs": {"net_arch": [256, 256], "log_std_init": -2.0},
    },
}


def ppo_kwargs(env_id: str = "DiceThrow-v0") -> dict[str, Any]:
    """PPO's keywords for ``env_id`` (a fresh copy): ``PPO(policy, env, **ppo_kwargs(env_id))``."""
    if env_id not in PPO_HYPERPARAMS:
        raise ValueError(f"env_id must be one of {sorted(PPO_HYPERPARAMS)}, got {env_id!r}")
    kwargs = {key: copy.deepcopy(value) for key, value in PPO_HYPERPARAMS[env_id].items()
              if key not in NON_PPO_KEYS}
    kwargs["learning_rate"] = learning_rate(kwargs["learning_rate"])
    return kwargs


def learning_rate(value: float | str) -> float | LinearSchedule:
    """A learning rate as written in the tables.

    A number, or ``"lin_X"`` for a linear decay from X to 0 over training (rl-zoo3's
    notation, which keeps the tables plain data).
    """
    if isinstance(value, str):
        if not value.startswith("lin_"):
            raise ValueError(f"learning_rate must be a number or 'lin_<number>', got {value!r}")
        return LinearSchedule(float(value[4:]), 0.0, 1.0)
    return value


# The benchmark (``python -m agents.benchmark``): one budget in throws per named task, the same
# for every algorithm. They are what two CPU cores train 3 seeds x 3 algorithms of every task
# in about an hour: the one-die tasks run 1,000-3,000 throws/s on one core, two dice in the tray
# about 100 and the craps throw about 20 (``benchmarks/env.json`` measures the default task).
BUDGETS: dict[str, int] = {
    "DiceThrow-v0": 40_000,
    "DiceThrowHigh-v0": 40_000,
    "DiceThrowD20-v0": 40_000,
    "DiceThrowTray2d6Sum-v0": 8_000,
    "DiceThrowCraps-v0": 2_000,
}
# Fewer throws per step where a throw costs more, so that a small budget still makes updates.
_N_ENVS = {"DiceThrowTray2d6Sum-v0": 16, "DiceThrowCraps-v0": 8}
# Keys of an rl-zoo3 entry that are not the algorithm's keywords (rl-zoo3 reads the noise keys
# into an ``action_noise``).
NON_ALGORITHM_KEYS = (*NON_PPO_KEYS, "noise_type", "noise_std")
# Per algorithm, the keywords for every task: untuned, no search was run. PPO is the
# DiceThrow-v0 recipe above with a rollout of ``n_envs`` x 4 throws, A2C the same rollout and
# policy with Stable-Baselines3's learning rate decaying to 0; SAC and TD3 are
# Stable-Baselines3's defaults for a one-step task (every episode one throw, so gamma does not
# matter), with one gradient step per 4 throws and TD3 with rl-zoo3's usual exploration noise.
_ALGORITHMS: dict[str, dict[str, Any]] = {
    "ppo": {"n_steps": 4, "batch_size": 64, "n_epochs": 10, "learning_rate": "lin_3e-4",
            "policy_kwargs": {"net_arch": [256, 256], "log_std_init": -2.0}},
    "a2c": {"n_steps": 4, "learning_rate": "lin_7e-4", "ent_coef": 0.0,
            "policy_kwargs": {"net_arch": [256, 256], "log_std_init": -2.0}},
    "sac": {"learning_rate": 3e-4, "batch_size": 256, "learning_starts": 1_000,
            "train_freq": 1, "gamma": 0.0, "policy_kwargs": {"net_arch": [256, 256]}},
    "td3": {"learning_rate": 1e-3, "batch_size": 256, "learning_starts": 1_000,
            "train_freq": 1, "gamma": 0.0, "noise_type": "normal", "noise_std": 0.1,
            "policy_kwargs": {"net_arch": [256, 256]}},
}


def _benchmark_entry(algo: str, env_id: str) -> dict[str, Any]:
    """One (algorithm, task) entry in rl-zoo3's schema."""
    n_envs = _N_ENVS.get(env_id, 64)
    entry = {"policy": "MlpPolicy", "n_envs": n_envs, "n_timesteps": BUDGETS[env_id],
             "env_kwargs": {}, **copy.deepcopy(_ALGORITHMS[algo])}
    if algo in ("sac", "td3"):
        entry["gradient_steps"] = max(1, n_envs // 4)
        entry["buffer_size"] = BUDGETS[env_id]
        entry["learning_starts"] = min(entry["learning_starts"], BUDGETS[env_id] // 4)
    return entry


BENCHMARK_HYPERPARAMS: dict[str, dict[str, dict[str, Any]]] = {
    algo: {env_id: _benchmark_entry(algo, env_id) for env_id in BUDGETS} for algo in _ALGORITHMS
}


def algorithm_kwargs(algo: str, env_id: str, action_dim: int) -> dict[str, Any]:
    """The SB3 keywords of ``algo`` on ``env_id`` (a fresh copy), as rl-zoo3 builds them."""
    if algo not in BENCHMARK_HYPERPARAMS:
        raise ValueError(f"algo must be one of {sorted(BENCHMARK_HYPERPARAMS)}, got {algo!r}")
    if env_id not in BUDGETS:
        raise ValueError(f"env_id must be one of {sorted(BUDGETS)}, got {env_id!r}")
    entry = BENCHMARK_HYPERPARAMS[algo][env_id]
    kwargs = {key: copy.deepcopy(value) for key, value in entry.items()
              if key not in NON_ALGORITHM_KEYS}
    kwargs["learning_rate"] = learning_rate(kwargs["learning_rate"])
    if entry.get("noise_type") == "normal":
        from stable_baselines3.common.noise import NormalActionNoise

        kwargs["action_noise"] = NormalActionNoise(np.zeros(action_dim),
                                                   entry["noise_std"] * np.ones(action_dim))
    return kwargs

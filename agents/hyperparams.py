"""Every agent's hyperparameters: one table, :data:`HYPERPARAMS` ``[env_id][algo][preset]``.

Each entry is in rl-zoo3's schema: ``policy``, ``n_envs`` (envs stepped together, one kernel
call), ``n_timesteps`` (the budget in throws), ``env_kwargs`` (env keywords for training only:
evaluation is on the task without them) and the algorithm's keywords, TD3's exploration as
``noise_type``/``noise_std``; train.py's warm start adds ``imitation_throws`` and
``imitation_steps``. The presets:

* ``"benchmark"``: every named task with PPO, A2C, SAC and TD3 at the benchmark's budgets
  (``python -m agents.benchmark``; ``python -m agents.zoo`` writes them as rl-zoo3 files).
* ``"quick"`` and ``"best"``: ``train.py``'s PPO on every named task (``--env-id``). One die:
  warm-started by imitating the hand-written thrower, with the target face's direction as a
  feature (:class:`agents.policy.TargetNormal`); two dice for a total (the tray): the same PPO
  with the direction the tray's rule spins up as a feature (:class:`agents.policy.PairNormal`),
  warm-started by imitating that rule (:class:`agents.baselines.TotalThrower`); the craps throw:
  the same PPO warm-started by imitating the set throw.
* ``"scratch"``: plain PPO from scratch, ``MlpPolicy`` on the raw observation (target one-hot
  and hand orientation), no imitation (``train.py --preset scratch``; :data:`PPO_HYPERPARAMS`):

    from stable_baselines3 import PPO
    from agents.hyperparams import PPO_HYPERPARAMS, ppo_kwargs
    from dice_env.envs.sb3 import make_sb3_env

    hp = PPO_HYPERPARAMS["DiceThrow-v0"]
    env = make_sb3_env(hp["n_envs"], seed=0, **hp["env_kwargs"])
    model = PPO(hp["policy"], env, seed=0, **ppo_kwargs("DiceThrow-v0"))
    model.learn(hp["n_timesteps"])

Where DiceThrow-v0's ``"scratch"`` values come from: ``python benchmarks/learn_from_scratch.py``
(default task: 1.5 cm release, 5 % hand noise; success of the policy's mean action on fixed
random throws; one kernel thread and one PyTorch thread), which trains them and variants that
each change one value (``--set KEY=VALUE``); its kept results
(``benchmarks/results/learn_from_scratch.json``) are shown in docs/agents.md with the oracle's.
What the values are:

* Every episode is one throw, so the advantage is the reward minus the value whatever ``gamma``
  and ``gae_lambda`` are; they stay at SB3's defaults.
* ``log_std_init=-2``: an initial action noise of e^-2 (0.135) in action units.
* The learning rate decays linearly from 3e-4 to 0 over the budget (``"lin_3e-4"``).
* ``shaping=0.5`` (``0.5 n_target . n_table`` added to the reward) and ``until="decided"`` (each
  throw ends when its face is decided: the same faces, fewer steps) as agents/train.py trains.
* ``n_envs=256`` throws per kernel call, 4 steps per rollout: 1024 throws per update in batches
  of 256.

The plain MLP has to learn the target's direction in the world, a product of the one-hot and
the orientation matrix; :class:`agents.policy.TargetNormal` hands it that product as a feature
(``--set features_extractor_class=agents.policy:TargetNormal``), as the warm start's presets do.
"""

from __future__ import annotations

import copy
import importlib
from typing import Any

import numpy as np
from stable_baselines3.common.utils import LinearSchedule

BENCHMARK = "benchmark"  # the benchmark's preset, on every named task and algorithm
# The keys of an entry that are not the algorithm's keywords (rl-zoo3 reads the noise keys into
# an ``action_noise``; train.py reads the imitation keys).
NON_ALGORITHM_KEYS = ("policy", "n_envs", "n_timesteps", "env_kwargs", "noise_type",
                      "noise_std", "imitation_throws", "imitation_steps")
NON_PPO_KEYS = NON_ALGORITHM_KEYS

# The benchmark (``python -m agents.benchmark``): one budget in throws per named task, the same
# for every algorithm; smaller where a throw costs more to simulate (two dice, the craps table's
# long roll), so that 3 seeds x 4 algorithms of every task fit one session on two CPU cores
# (docs/benchmark.md gives each run's CPU time). The two-dice tasks' budgets follow their
# throws' cost: stepped in islands, as many more throws as benchmarks/islands.py measures
# islands buying each (benchmarks/results/islands.json).
BUDGETS: dict[str, int] = {
    "DiceThrow-v0": 240_000,
    "DiceThrowHigh-v0": 40_000,
    "DiceThrowD20-v0": 40_000,
    "DiceThrowTray2d6Sum-v0": 21_000,
    "DiceThrowCraps-v0": 2_600,
}
# Fewer throws per step where a throw costs more, so that a small budget still makes updates.
_N_ENVS = {"DiceThrowTray2d6Sum-v0": 16, "DiceThrowCraps-v0": 8}
# Per algorithm, the starting point of the benchmark's keywords for every task. PPO is the
# "scratch" recipe below with a rollout of ``n_envs`` x 4 throws, A2C the same rollout and
# policy with Stable-Baselines3's learning rate decaying to 0; SAC and TD3 are
# Stable-Baselines3's defaults for a one-step task (every episode one throw, so gamma does not
# matter), with one gradient step per 4 throws and TD3 with rl-zoo3's usual exploration noise.
# The benchmark uses the variant of :data:`SEARCH` named in :data:`TUNED`.
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
ALGOS = tuple(_ALGORITHMS)
# The search (``python -m agents.tune``): per algorithm, these changes to its keywords above,
# each trained once on DiceThrow-v0 for agents.tune.TUNE_BUDGET throws (seed TUNE_SEED), scored on
# throws of their own (``benchmarks/results/tuning.json``); TUNED names the best, which the
# benchmark trains on every task.
SEARCH: dict[str, dict[str, dict[str, Any]]] = {
    "ppo": {"as above": {}, "lr 1e-3": {"learning_rate": "lin_1e-3"},
            "lr 3e-3": {"learning_rate": "lin_3e-3"},
            "log_std -1": {"policy_kwargs": {"net_arch": [256, 256], "log_std_init": -1.0}}},
    "a2c": {"as above": {}, "lr 2e-3": {"learning_rate": "lin_2e-3"},
            "lr 5e-3": {"learning_rate": "lin_5e-3"},
            "log_std -1": {"policy_kwargs": {"net_arch": [256, 256], "log_std_init": -1.0}}},
    "sac": {"as above": {}, "lr 1e-3": {"learning_rate": 1e-3},
            "lr 3e-3": {"learning_rate": 3e-3}, "entropy 0.01": {"ent_coef": 0.01},
            "lr 1e-2": {"learning_rate": 1e-2}},
    "td3": {"as above": {}, "lr 3e-3": {"learning_rate": 3e-3},
            "noise 0.05": {"noise_std": 0.05}, "noise 0.2": {"noise_std": 0.2}},
}
TUNED = {"ppo": "as above", "a2c": "lr 5e-3", "sac": "lr 1e-2", "td3": "as above"}


def benchmark_entry(algo: str, env_id: str, variant: str | None = None) -> dict[str, Any]:
    """One (algorithm, task) entry of the benchmark: :data:`SEARCH`'s ``variant`` (TUNED's)."""
    n_envs = _N_ENVS.get(env_id, 64)
    params = {"policy": "MlpPolicy", "n_envs": n_envs, "n_timesteps": BUDGETS[env_id],
              "env_kwargs": {}, **copy.deepcopy(_ALGORITHMS[algo]),
              **copy.deepcopy(SEARCH[algo][TUNED[algo] if variant is None else variant])}
    if algo in ("sac", "td3"):
        params["gradient_steps"] = max(1, n_envs // 4)
        params["buffer_size"] = BUDGETS[env_id]
        params["learning_starts"] = min(params["learning_starts"], BUDGETS[env_id] // 4)
    return params


# train.py's warm start: PPO for a one-step task (a contextual bandit): every episode ends after
# one throw, so the advantage is the reward minus the value (gamma and lambda do not matter);
# large batches of throws per update, a few epochs, a small initial action noise around the
# hand-sized throws. Training only: the dense term n_target . n_table at rest speeds learning.
# Before PPO, the policy's mean imitates the task's rule (the hand-written thrower for one die)
# on ``imitation_throws`` observations for ``imitation_steps`` gradient steps, so that PPO
# starts from the rule's throws and refines them.
_WARM_START: dict[str, Any] = {
    "policy": "MlpPolicy", "n_envs": 256, "n_timesteps": 150_000, "env_kwargs": {"shaping": 0.5},
    "n_steps": 8, "batch_size": 512, "n_epochs": 10, "gamma": 0.0, "gae_lambda": 1.0,
    "learning_rate": 1e-4, "clip_range": 0.2, "target_kl": 0.05, "ent_coef": 0.0, "vf_coef": 0.5,
    "max_grad_norm": 0.5,
    "policy_kwargs": {"net_arch": [256, 256], "log_std_init": -2.5,
                      "features_extractor_class": "agents.policy:TargetNormal"},
    "imitation_throws": 20_000, "imitation_steps": 1500,
}
# Plain MlpPolicy PPO from scratch (the module's docstring says where each value comes from).
_SCRATCH: dict[str, Any] = {
    "policy": "MlpPolicy", "n_envs": 256, "n_timesteps": 800_000,
    "env_kwargs": {"shaping": 0.5, "until": "decided"},
    "n_steps": 4, "batch_size": 256, "n_epochs": 10, "learning_rate": "lin_3e-4",
    "policy_kwargs": {"net_arch": [256, 256], "log_std_init": -2.0},
}

HYPERPARAMS: dict[str, dict[str, dict[str, dict[str, Any]]]] = {
    env_id: {algo: {BENCHMARK: benchmark_entry(algo, env_id)} for algo in ALGOS}
    for env_id in BUDGETS
}
# train.py's presets on every named task: the warm start for one die (``"best"``: 500,000
# throws); the tray's and the craps throw's below (``"best"``: five times their budget).
ONE_DIE_TASKS = ("DiceThrow-v0", "DiceThrowHigh-v0", "DiceThrowD20-v0")
for _id in ONE_DIE_TASKS:
    HYPERPARAMS[_id]["ppo"].update(quick=_WARM_START, best={**_WARM_START, "n_timesteps": 500_000},
                                   scratch=_SCRATCH)
# Two dice for a total (the tray): the one-die warm start's PPO with a rollout of 32 x 8
# throws, the policy handed the direction the tray's rule spins up (agents.policy.PairNormal,
# which the plain MLP fits poorly: imitating the rule through it kept half the rule's success,
# and the benchmark's PPO then lost the rest; docs/benchmark.md), and a budget of 16,384 throws.
_TRAY_WARM: dict[str, Any] = {
    **_WARM_START, "n_envs": 32, "n_timesteps": 16_384, "env_kwargs": {}, "batch_size": 256,
    "policy_kwargs": {**_WARM_START["policy_kwargs"],
                      "features_extractor_class": "agents.policy:PairNormal"},
}
_plain = HYPERPARAMS["DiceThrowTray2d6Sum-v0"]["ppo"][BENCHMARK]
HYPERPARAMS["DiceThrowTray2d6Sum-v0"]["ppo"].update(
    quick=_TRAY_WARM, best={**_TRAY_WARM, "n_timesteps": 5 * _TRAY_WARM["n_timesteps"]},
    scratch=_plain)
# The craps throw: the same PPO from an imitation of the set throw (no feature: the set throw
# does not depend on the target), a rollout of 16 x 8 throws and the benchmark's budget (a
# long roll: ~50 throws/s). The benchmark's PPO from the same imitation drifted to random's
# success (0.82 against the set throw's 0.84 on the oracle's throws) within 2,000 throws.
_CRAPS_WARM: dict[str, Any] = {
    **_WARM_START, "n_envs": 16, "n_timesteps": 2_048, "env_kwargs": {}, "batch_size": 128,
    "policy_kwargs": {"net_arch": [256, 256], "log_std_init": -2.5},
}
_plain = HYPERPARAMS["DiceThrowCraps-v0"]["ppo"][BENCHMARK]
HYPERPARAMS["DiceThrowCraps-v0"]["ppo"].update(
    quick=_CRAPS_WARM, best={**_CRAPS_WARM, "n_timesteps": 5 * _CRAPS_WARM["n_timesteps"]},
    scratch=_plain)
del _id, _plain

# The "scratch" entries by env id: plain PPO as an SB3 user writes it (the README's snippet).
PPO_HYPERPARAMS: dict[str, dict[str, Any]] = {
    env_id: algos["ppo"]["scratch"] for env_id, algos in HYPERPARAMS.items()
    if "scratch" in algos["ppo"]
}


def entry(env_id: str, algo: str = "ppo", preset: str = BENCHMARK) -> dict[str, Any]:
    """The table's entry (not a copy) of ``algo`` on ``env_id`` in ``preset``."""
    if env_id not in HYPERPARAMS:
        raise ValueError(f"env_id must be one of {sorted(HYPERPARAMS)}, got {env_id!r}")
    if algo not in HYPERPARAMS[env_id]:
        raise ValueError(f"algo must be one of {sorted(HYPERPARAMS[env_id])}, got {algo!r}")
    presets = HYPERPARAMS[env_id][algo]
    if preset not in presets:
        raise ValueError(f"preset must be one of {sorted(presets)}, got {preset!r}")
    return presets[preset]


def algorithm_kwargs(params: dict[str, Any], action_dim: int | None = None) -> dict[str, Any]:
    """The SB3 keywords of an entry (a fresh copy), as rl-zoo3 builds them.

    ``"lin_X"`` learning rates become schedules, ``"module:Name"`` classes in ``policy_kwargs``
    are imported, and a ``noise_type`` becomes an ``action_noise`` over ``action_dim`` actions.
    """
    kwargs = {key: copy.deepcopy(value) for key, value in params.items()
              if key not in NON_ALGORITHM_KEYS}
    if "learning_rate" in kwargs:
        kwargs["learning_rate"] = learning_rate(kwargs["learning_rate"])
    policy = kwargs.get("policy_kwargs", {})
    for key, value in policy.items():
        if key.endswith("_class") and isinstance(value, str):
            module, _, name = value.partition(":")
            policy[key] = getattr(importlib.import_module(module), name)
    if params.get("noise_type") == "normal":
        from stable_baselines3.common.noise import NormalActionNoise

        if action_dim is None:
            raise ValueError("an entry with noise_type needs action_dim")
        kwargs["action_noise"] = NormalActionNoise(np.zeros(action_dim),
                                                   params["noise_std"] * np.ones(action_dim))
    return kwargs


def ppo_kwargs(env_id: str = "DiceThrow-v0") -> dict[str, Any]:
    """PPO's keywords for ``env_id`` (a fresh copy): ``PPO(policy, env, **ppo_kwargs(env_id))``."""
    if env_id not in PPO_HYPERPARAMS:
        raise ValueError(f"env_id must be one of {sorted(PPO_HYPERPARAMS)}, got {env_id!r}")
    return algorithm_kwargs(PPO_HYPERPARAMS[env_id])


def learning_rate(value: float | str) -> float | LinearSchedule:
    """A learning rate as written in the table.

    A number, or ``"lin_X"`` for a linear decay from X to 0 over training (rl-zoo3's
    notation, which keeps the table plain data).
    """
    if isinstance(value, str):
        if not value.startswith("lin_"):
            raise ValueError(f"learning_rate must be a number or 'lin_<number>', got {value!r}")
        return LinearSchedule(float(value[4:]), 0.0, 1.0)
    return value

"""Plain PPO from scratch on DiceThrow-v0 with agents/hyperparams.py: the learning curve.

    python benchmarks/learn_from_scratch.py                       # the recommended setting
    python benchmarks/learn_from_scratch.py --seeds 0 1 2         # several seeds
    python benchmarks/learn_from_scratch.py --set log_std_init=-1 --throws 150000   # a variant

Trains ``PPO("MlpPolicy", make_sb3_env(...), **ppo_kwargs())`` with no imitation. Every
``--every`` throws the policy's mean action throws ``--eval-throws`` fixed random throws of the
default task (targets, hands and hand noise drawn once from a fixed seed; ``until="decided"``,
the same faces as to rest); at the end ``--final-throws`` more are thrown to rest, with the
hand-written thrower on the same throws for reference. ``--set KEY=VALUE`` overrides one
hyperparameter (a PPO keyword, a ``policy_kwargs`` key such as ``log_std_init``, ``net_arch`` or
``features_extractor_class=agents.policy:TargetNormal``, or an env keyword such as ``shaping``);
``learning_rate=lin_X`` decays linearly from X. Prints the curve and writes
``benchmarks/results/learn_from_scratch.json`` (``--out``).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import argparse
import ast
import importlib
import inspect
import time
from typing import Any

import numpy as np
import torch
from harness import benchmark_parser, command_line, write_json
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.utils import LinearSchedule

from agents.baselines import HandThrower
from agents.hyperparams import NON_PPO_KEYS, PPO_HYPERPARAMS, ppo_kwargs
from dice_env.envs.sb3 import make_sb3_env
from dice_env.envs.throw_task import ThrowTask, make_task
from dice_env.intervals import wilson_bounds
from dice_env.provenance import code_version

ENV_ID = "DiceThrow-v0"
EVAL_SEED = 12345
POLICY_KEYS = ("net_arch", "log_std_init", "features_extractor_class", "ortho_init")
PPO_KEYS = set(inspect.signature(PPO).parameters) - {"policy", "env", *NON_PPO_KEYS}


class Throws:
    """``n`` fixed throws of ``task``: targets, hands, observations and hand noise.

    ``num_threads``: the kernel's threads (None: all).
    """

    def __init__(self, task: ThrowTask, n: int, seed: int, num_threads: int | None) -> None:
        rng = np.random.default_rng(seed)
        pairs = [task.sample_hand(rng) for _ in range(n)]
        self.task, self.num_threads = task, num_threads
        self.targets = np.array([t for t, _ in pairs])
        self.hands = np.stack([h for _, h in pairs])
        self.observations = task.observe(self.targets, self.hands)
        self.noise = task.sample_noise(rng, n)

    def success(self, actions: np.ndarray) -> np.ndarray:
        """Whether each throw lands its target face up (n,) bool."""
        return self.task.throw(actions, self.targets, self.hands, self.noise,
                               num_threads=self.num_threads).info["is_success"]


def mean_action(model: PPO, observations: np.ndarray) -> np.ndarray:
    """The policy's deterministic actions."""
    return model.predict(observations, deterministic=True)[0]


class Curve(BaseCallback):
    """Evaluate every ``every`` throws; ``points`` holds (throws, success, seconds)."""

    def __init__(self, throws: Throws, every: int) -> None:
        super().__init__()
        self.throws, self.every, self.next = throws, every, 0
        self.points: list[dict[str, float]] = []
        self.start = time.perf_counter()

    def record(self) -> None:
        """Append the current success rate."""
        success = float(self.throws.success(mean_action(self.model, self.throws.observations))
                        .mean())
        point = {"throws": self.model.num_timesteps, "success": success,
                 "seconds": round(time.perf_counter() - self.start, 1)}
        self.points.append(point)
        print(f"  {point['throws']:>9,d} throws  success {success:.3f}  "
              f"{point['seconds']:7.1f} s", flush=True)

    def _on_step(self) -> bool:
        if self.model.num_timesteps >= self.next:
            self.record()
            self.next += self.every
        return True


def parse_value(text: str) -> Any:
    """A Python literal, a ``lin_X`` schedule, a ``module:Name`` class or the bare string."""
    if text.startswith("lin_"):
        return LinearSchedule(float(text[4:]), 0.0, 1.0)
    if ":" in text:
        module, _, name = text.partition(":")
        return getattr(importlib.import_module(module), name)
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def settings(overrides: list[str]) -> tuple[dict[str, Any], dict[str, Any], int]:
    """PPO keywords, training env keywords and n_envs with ``KEY=VALUE`` overrides applied."""
    hp = PPO_HYPERPARAMS[ENV_ID]
    ppo, env, n_envs = ppo_kwargs(ENV_ID), dict(hp["env_kwargs"]), hp["n_envs"]
    env_keys = set(make_task.__kwdefaults__)
    for item in overrides:
        key, sep, text = item.partition("=")
        if not sep:
            raise ValueError(f"--set must be KEY=VALUE, got {item!r}")
        value = parse_value(text)
        if key == "n_envs":
            n_envs = value
        elif key in POLICY_KEYS:
            ppo["policy_kwargs"][key] = value
        elif key in env_keys:
            env[key] = value
        elif key in PPO_KEYS:
            ppo[key] = value
        else:
            raise ValueError(f"--set key must be a PPO keyword, one of {POLICY_KEYS} or a "
                             f"DiceThrow-v0 keyword, got {key!r}")
    return ppo, env, n_envs


def run(seed: int, args: argparse.Namespace) -> dict[str, Any]:
    """Train one seed; its curve, final success (to rest) and wall time."""
    ppo, env_kwargs, n_envs = settings(args.set)
    threads = {"num_threads": args.num_threads} if args.num_threads else {}
    env = make_sb3_env(n_envs, seed=seed, **env_kwargs, **threads)
    curve = Curve(Throws(make_task(until="decided"), args.eval_throws, EVAL_SEED,
                         args.num_threads), args.every)
    model = PPO(PPO_HYPERPARAMS[ENV_ID]["policy"], env, seed=seed, device="cpu", **ppo)
    model.learn(args.throws, callback=curve)
    curve.record()
    train_s = time.perf_counter() - curve.start
    final = Throws(make_task(), args.final_throws, EVAL_SEED + 1, args.num_threads)
    ppo_success = final.success(mean_action(model, final.observations))
    rule_success = final.success(HandThrower(final.task)(final.observations))
    result = {"seed": seed, "curve": curve.points, "seconds": round(train_s, 1),
              "final": {name: {"success": float(s.mean()),
                               "ci": tuple(round(v, 3) for v in wilson_bounds(s.sum(), s.size)),
                               "n": int(s.size)}
                        for name, s in (("ppo", ppo_success), ("rule", rule_success))}}
    print(f"seed {seed}: to rest, PPO {result['final']['ppo']}, rule {result['final']['rule']}, "
          f"training {train_s:.0f} s", flush=True)
    return result


def main() -> None:
    """Parse the options, train every seed, print and write the results."""
    parser = benchmark_parser(__doc__, "learn_from_scratch")
    parser.add_argument("--throws", type=int, default=PPO_HYPERPARAMS[ENV_ID]["n_timesteps"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--every", type=int, default=50_000)
    parser.add_argument("--eval-throws", type=int, default=2000)
    parser.add_argument("--final-throws", type=int, default=2000)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--num-threads", type=int, default=None,
                        help="kernel threads (None: all cores); PyTorch uses --torch-threads")
    parser.add_argument("--torch-threads", type=int, default=1)
    args = parser.parse_args()
    settings(args.set)  # refuse a bad --set before any work
    torch.set_num_threads(args.torch_threads)
    report: dict[str, Any] = {
        "command": command_line(), "commit": code_version(),
        "throws": args.throws, "set": args.set,
        "hyperparams": {k: repr(v) for k, v in PPO_HYPERPARAMS[ENV_ID].items()}, "runs": []}
    for seed in args.seeds:  # written after each seed, so a long run keeps what it has done
        report["runs"].append(run(seed, args))
        write_json(args.out, report, indent=1)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()

"""SB3's PPO with its defaults on one DiceThrow-v0 env: throws per second, then its success.

    python benchmarks/sb3_defaults.py          # 4,096 throws: two of PPO's default rollouts

Trains ``PPO("MlpPolicy", gym.make("DiceThrow-v0"), seed=0).learn(--throws)``, as an SB3 user
writes it first, on one thread (torch's and the kernel's) timed by this process's CPU time,
which other work on shared cores does not inflate. Then it throws the policy's mean action on
``--eval-throws`` seeded throws of the default task (one batch of the native vector env) and
gives their success with its Wilson 95 % interval beside chance (1/6). Writes
``benchmarks/results/sb3_defaults.json``. The recommended setting instead:
``agents/hyperparams.py`` (``docs/guide.md``).
"""

from __future__ import annotations

import gymnasium as gym
import torch
from harness import benchmark_parser, command_line, timed, write_json
from stable_baselines3 import PPO

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from dice_env.intervals import wilson_bounds
from dice_env.provenance import code_version

ENV_ID = "DiceThrow-v0"
EVAL_SEED = 12345


def success(model: PPO, throws: int) -> dict[str, object]:
    """The model's mean action on ``throws`` seeded throws: success, interval, verdict."""
    venv = gym.make_vec(ENV_ID, num_envs=throws)
    obs, _ = venv.reset(seed=EVAL_SEED)
    actions, _ = model.predict(obs, deterministic=True)
    hits = int(venv.step(actions)[4]["final_info"]["is_success"].sum())
    low, high = wilson_bounds(hits, throws)
    verdict = "above chance" if low > 1 / 6 else "below chance" if high < 1 / 6 else "at chance"
    return {"rate": hits / throws, "interval": [low, high], "chance": 1 / 6, "verdict": verdict}


def main() -> None:
    parser = benchmark_parser(__doc__, "sb3_defaults")
    parser.add_argument("--throws", type=int, default=4096, help="PPO's budget (throws)")
    parser.add_argument("--eval-throws", type=int, default=400)
    args = parser.parse_args()
    torch.set_num_threads(1)
    model = PPO("MlpPolicy", gym.make(ENV_ID, num_threads=1), seed=0)
    seconds, _ = timed(lambda: model.learn(args.throws), repeats=1)
    record = {"throws": model.num_timesteps, "cpu_seconds": seconds,
              "throws_per_s": model.num_timesteps / seconds, "threads": 1,
              "eval_throws": args.eval_throws, "success": success(model, args.eval_throws)}
    rate = record["success"]
    print(f"{record['throws']:,} throws in {seconds:.1f} s of CPU: "
          f"{record['throws_per_s']:.0f} throws/s; success {rate['rate']:.3f} "
          f"[{rate['interval'][0]:.3f}, {rate['interval'][1]:.3f}] "
          f"on {args.eval_throws} throws: {rate['verdict']}")
    write_json(args.out, record | {"command": command_line(), "commit": code_version()})


if __name__ == "__main__":
    main()

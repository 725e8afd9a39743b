"""DiceThrow-v0's speed: env throws/s, single and natively batched, against the raw kernel.

    python benchmarks/env.py            # batch 256, a few repeats (about a minute on 2 cores)
    python benchmarks/env.py --quick    # batch 64

The same seeded throws (default task, a seeded random policy) are run three ways: N single envs
(``gym.make``, reset + step per throw), the native vector env (``gym.make_vec``, one step = N
throws) and the raw kernel (:func:`dice_env.simulate` as the env calls it, on the very releases
the vector env used); once to rest (the default) and once with ``until="decided"``. The vector
env's overhead is its time over the kernel's on identical throws, measured alternately (best of
the repeats) so that load from other processes hits both alike. Prints a table and writes
``benchmarks/results/env.json``.
"""

from __future__ import annotations

import os
import time

import gymnasium as gym
import numpy as np
from harness import benchmark_parser, command_line, write_json

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from dice_env import State, simulate
from dice_env.provenance import code_version


def measure(until: str, n: int, repeats: int, n_single: int,
            seed: int = 0) -> tuple[dict, np.ndarray]:
    """Throws/s of the kernel, the vector env and single envs for the env keyword ``until``.

    Also returns the landed faces.
    """
    actions = np.random.default_rng(seed).uniform(-1, 1, (n, 6)).astype(np.float32)
    venv = gym.make_vec("DiceThrow-v0", num_envs=n, until=until)
    task = venv.unwrapped.task
    venv.reset(seed=seed)
    venv.step(actions)  # compile / warm up
    vector_s, kernel_s = [], []
    for _ in range(repeats):
        venv.reset(seed=seed)
        start = time.perf_counter()
        _, _, _, _, info = venv.step(actions)
        vector_s.append(time.perf_counter() - start)
        final = info["final_info"]
        state = State.release(task.scene, task.hand.centre, final["release_velocity"],
                              final["release_spin"], final["release_orientation"])
        start = time.perf_counter()
        result = simulate(task.scene, state, until=task.run_until)  # as ThrowTask.throw
        kernel_s.append(time.perf_counter() - start)
        assert np.array_equal(result.face, final["face"])  # the very same throws

    env = gym.make("DiceThrow-v0", until=until)
    single_s = []
    for _ in range(max(1, repeats // 2)):
        start = time.perf_counter()
        for i in range(n_single):
            env.reset(seed=seed + i)
            env.step(actions[i])
        single_s.append(time.perf_counter() - start)

    vector, kernel, single = min(vector_s), min(kernel_s), min(single_s)
    return {
        "batch": n,
        "threads": os.cpu_count(),
        "kernel_throws_per_s": n / kernel,
        "vector_env_throws_per_s": n / vector,
        "vector_overhead": vector / kernel - 1.0,
        "single_env_throws_per_s": n_single / single,
        "mean_end_time_s": float(final["rest_time"].mean()),
        "load_average": os.getloadavg()[0],
    }, final["face"]


def main() -> None:
    args = benchmark_parser(__doc__, "env", "batch 64, fewer repeats").parse_args()
    n, repeats, n_single = (64, 3, 32) if args.quick else (256, 5, 64)
    (rest, rest_faces), (decided, decided_faces) = (measure(until, n, repeats, n_single)
                                                    for until in ("rest", "decided"))
    rows = {"rest": rest, "decided": decided,
            "decided_over_rest_vector_env": (decided["vector_env_throws_per_s"]
                                             / rest["vector_env_throws_per_s"]),
            "same_faces": bool(np.array_equal(rest_faces, decided_faces))}
    print(f"{'until':>8} {'batch':>6} {'kernel/s':>10} {'vector env/s':>13} {'overhead':>9} "
          f"{'single env/s':>13} {'ends at s':>10}")
    for until in ("rest", "decided"):
        row = rows[until]
        print(f"{until:>8} {n:>6} {row['kernel_throws_per_s']:>10.0f} "
              f"{row['vector_env_throws_per_s']:>13.0f} {row['vector_overhead']:>9.1%} "
              f"{row['single_env_throws_per_s']:>13.0f} {row['mean_end_time_s']:>10.3f}")
    print(f"until='decided': {rows['decided_over_rest_vector_env']:.2f}x the vector env's "
          f"throws/s, the same faces: {rows['same_faces']}")
    write_json(args.out, rows | {"command": command_line(), "commit": code_version()})


if __name__ == "__main__":
    main()

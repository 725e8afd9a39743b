"""The several-dice tasks' throws in islands against stepped together: what islands buy a task.

    python benchmarks/islands.py            # 256 throws a task, 3 repeats (a few minutes)
    python benchmarks/islands.py --quick    # 32 throws, 1 repeat

For each named task of two or more dice (:data:`dice_env.envs.tasks.TASKS`), the vector env
throws seeded uniform random actions once; the releases it made (``info["final_info"]``'s
``release_*``) are then run through ``simulate_group`` as the env runs them (the task's
``until``), once in islands (``DieContact()``, the default, which must land the env's faces)
and once stepped together (``DieContact(islands=False)``), alternately, on one thread, timed
as this process's CPU time, best of the repeats. The ratio of the two is what a budget of
throws for that task can grow by (``agents/hyperparams.py``'s ``BUDGETS``). Prints a table
and writes ``benchmarks/results/islands.json``.
"""

from __future__ import annotations

import os

import gymnasium as gym
import numpy as np
from harness import benchmark_parser, command_line, timed, write_json

import dice_env  # noqa: F401  (registers the tasks)
from dice_env import State
from dice_env.envs.tasks import TASKS
from dice_env.markdown import markdown_table
from dice_env.provenance import code_version
from dice_env.simulation.group import DieContact, GroupState, simulate_group

SEED = 0


def task_releases(task_id: str, n: int) -> tuple[object, GroupState, np.ndarray]:
    """The task, the group of ``n`` releases its vector env made, and the faces it landed."""
    envs = gym.make_vec(task_id, num_envs=n, num_threads=1)
    envs.reset(seed=SEED)
    actions = np.random.default_rng(SEED).uniform(-1, 1, (n, *envs.single_action_space.shape))
    final = envs.step(actions)[4]["final_info"]
    task = envs.unwrapped.task
    state = GroupState.of([State.release(scene, task.hand.positions[j],
                                         final["release_velocity"][:, j],
                                         final["release_spin"][:, j],
                                         final["release_orientation"][:, j])
                           for j, scene in enumerate(task.die_scenes)])
    return task, state, final["face"]


def measure(task_id: str, n: int, repeats: int) -> dict:
    """Throws/s of one task's releases in islands and stepped together, and their faces."""
    task, state, faces = task_releases(task_id, n)
    rates, results = {}, {}
    for _ in range(repeats):  # alternately, so that the machine's drift hits both alike
        for islands in (True, False):
            seconds, results[islands] = timed(lambda i=islands: simulate_group(
                task.scene, task.dice, state, until=task.run_until, num_threads=1,
                contact=DieContact(islands=i)), 1)
            rates[islands] = max(rates.get(islands, 0.0), n / seconds)
    if not np.array_equal(results[True].face, faces):
        raise AssertionError(f"{task_id}: islands did not land the env's faces")
    return {"task": task_id, "dice": len(task.dice), "until": task.run_until, "throws": n,
            "islands_throws_per_s": rates[True], "together_throws_per_s": rates[False],
            "islands_over_together": rates[True] / rates[False],
            "same_faces": float((results[True].face == results[False].face).all(axis=1).mean())}


def main() -> None:
    args = benchmark_parser(__doc__, "islands", "32 throws, 1 repeat").parse_args()
    n, repeats = (32, 1) if args.quick else (256, 3)
    ids = [task.id for task in TASKS if task.keywords.get("num_dice", 1) > 1]
    for task_id in ids:  # compile, untimed
        measure(task_id, 2, 1)
    rows = [measure(task_id, n, repeats) for task_id in ids]
    print(markdown_table(
        "task | dice | throws | in islands (throws/s) | together (throws/s) | ratio | "
        "same faces",
        ((r["task"], r["dice"], r["throws"], f"{r['islands_throws_per_s']:,.1f}",
          f"{r['together_throws_per_s']:,.1f}", f"{r['islands_over_together']:.2f}",
          f"{r['same_faces']:.0%}") for r in rows)))
    write_json(args.out, {"rows": rows, "seed": SEED, "repeats": repeats, "threads": 1,
                          "timer": "process CPU time", "load_average": os.getloadavg()[0],
                          "command": command_line(), "commit": code_version()})


if __name__ == "__main__":
    main()

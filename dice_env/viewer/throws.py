"""Recordings of a task's throws: the env's releases, scored as the env scores them."""

from __future__ import annotations

from typing import Any

import numpy as np

from dice_env.envs.task import ThrowTask
from dice_env.model.checks import check_int
from dice_env.viewer.recording import FPS, Recording, record


def task_throws(task: ThrowTask, actions: np.ndarray, targets: Any, hands: np.ndarray,
                noise: np.ndarray, *, fps: float = FPS, titles: list[str] | None = None,
                aimed: bool = True) -> list[Recording]:
    """Recordings of ``task.throw(...)``, with its void reasons.

    ``aimed`` (the actions aim at ``targets``): each outcome's ``target`` and ``success``, which
    the page's heading shows.
    """
    throw = task.throw(actions, targets, hands, noise)
    state, _ = task.release(actions, hands, noise)
    info = throw.info
    targets = info.get("target_sum", info.get("target_face"))
    dice = task.scene.die if task.n_dice == 1 else task.dice
    recordings = record(task.scene, dice, state, fps=fps, until=task.run_until, titles=titles,
                        voids=[str(v) for v in info["void_reason"]])
    if aimed:
        for rec, target, success in zip(recordings, targets, info["is_success"], strict=True):
            rec.outcome.update(target=np.asarray(target).tolist(), success=bool(success))
    return recordings


def random_throws(task: ThrowTask, count: int, seed: int, *, fps: float = FPS) -> list[Recording]:
    """``count`` throws of random actions (aimed at no target), hands drawn as the env's."""
    check_int("count", count, 1)
    rng = np.random.default_rng(seed)
    rngs = [np.random.default_rng([seed, k]) for k in range(count)]
    targets, hands = task.sample_hands(rngs)
    actions = rng.uniform(-1.0, 1.0, (count, task.action_dim))
    return task_throws(task, actions, targets, hands, task.sample_noise(rng, count), fps=fps,
                       aimed=False)

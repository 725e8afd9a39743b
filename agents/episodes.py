"""The evaluation's throws: the run's evaluation task, batches of episodes, a policy as a thrower.

Every thrower of an evaluation faces the same :class:`Batch` (the same targets, hands,
observations and hand noise: common random numbers).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from agents.baselines import Thrower
from agents.config import Config
from dice_env.envs.throw_task import ThrowTask, make_task

EPISODE_KEYWORDS = ("target_face", "target_sum", "orientation_mode")
CHUNK = 256  # throws per kernel call when the evaluation shows its progress


class PolicyThrower:
    """A trained SB3 policy as a thrower (deterministic actions)."""

    def __init__(self, model: Any) -> None:
        self.model = model

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """The policy's mean action for each observation."""
        return self.model.predict(np.asarray(observations, np.float32), deterministic=True)[0]


@dataclass
class Batch:
    """``n`` episodes: targets, hands, observations (n, size), noise (n, d).

    One die: targets (n,), hands (n, 3, 3); N dice: targets (n, N) faces or (n,) totals,
    hands (n, N, 3, 3). ``num_threads``: the kernel's threads for the throws (None: all).
    """

    targets: np.ndarray
    hands: np.ndarray
    observations: np.ndarray
    noise: np.ndarray
    num_threads: int | None = None

    @classmethod
    def sample(cls, task: ThrowTask, n: int, rng: np.random.Generator,
               num_threads: int | None = None, **episode: Any) -> Batch:
        """Draw ``n`` episodes as the env does (:data:`EPISODE_KEYWORDS`)."""
        fixed = task.goal.fix(episode.get("target_face"), episode.get("target_sum"))
        pairs = [task.sample_hand(rng, fixed, episode.get("orientation_mode", "uniform"))
                 for _ in range(n)]
        targets = np.array([t for t, _ in pairs])
        hands = np.stack([h for _, h in pairs])
        return cls(targets, hands, task.observe(targets, hands), task.sample_noise(rng, n),
                   num_threads)

    def throw(self, task: ThrowTask, thrower: Thrower,
              progress: Callable[[int], None] | None = None) -> dict[str, np.ndarray]:
        """The thrower's actions and the throws' info arrays (in chunks when ``progress``)."""
        actions = np.asarray(thrower(self.observations), np.float64)
        step = CHUNK if progress is not None else len(actions)
        parts = []
        for i in range(0, len(actions), step):
            part = slice(i, i + step)
            parts.append(task.throw(actions[part], self.targets[part], self.hands[part],
                                    self.noise[part], num_threads=self.num_threads).info)
            if progress is not None:
                progress(len(actions[part]))
        info = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
        return {"action": actions, **info}


def make_eval_task(config: Config, **overrides: Any) -> tuple[ThrowTask, dict[str, Any]]:
    """The run's evaluation task and Batch.sample's keys.

    The task is the env id's (its registered keywords) with the run's ``--env`` keywords, no
    shaping.
    """
    import gymnasium as gym

    import dice_env  # noqa: F401  (registers the named tasks)

    kwargs = {**gym.spec(config.env_id).kwargs, **config.env_kwargs(),
              **config.num_threads_kwargs(), **overrides}
    episode = {k: kwargs.pop(k) for k in (*EPISODE_KEYWORDS, "num_threads") if k in kwargs}
    for key in ("render_mode", "render_width", "render_height"):
        kwargs.pop(key, None)
    return make_task(**kwargs), episode


def throw_impacts(throws: dict[str, np.ndarray]) -> np.ndarray:
    """Impacts per throw (n,): the die's, or the sum over the dice of several."""
    impacts = np.asarray(throws["impacts"])
    return impacts.reshape(len(impacts), -1).sum(axis=1)

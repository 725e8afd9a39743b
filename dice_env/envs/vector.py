"""DiceThrow-v0 natively batched: N throws per step in one kernel call, SAME_STEP autoreset."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from dice_env.envs.dice_throw import (
    RENDER_FPS,
    action_space,
    configure,
    episode_hand,
    observation_space,
)
from dice_env.model.checks import check_int

MAX_NUM_ENVS = 2**20  # about 1 kB per env in the kernel's and the env's arrays


class DiceThrowVectorEnv(VectorEnv):
    """``num_envs`` DiceThrow-v0 envs stepped together (``gym.make_vec("DiceThrow-v0", n)``).

    Takes :class:`~dice_env.envs.dice_throw.DiceThrowEnv`'s keywords. Autoreset in the same
    step: ``step`` returns the *next* episodes' observations, the throw's own in
    ``info["final_obs"]`` and ``info["final_info"]``. Env ``i`` draws from its generator
    (seeded ``seed + i`` or ``seed[i]``) exactly as a single env reset with that seed.
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"], "render_fps": RENDER_FPS,
        "autoreset_mode": AutoresetMode.SAME_STEP,
    }

    def __init__(self, num_envs: int = 1, render_mode: str | None = None,
                 **keywords: Any) -> None:
        check_int("num_envs", num_envs, 1, MAX_NUM_ENVS)
        self.task, self.settings = configure(("rgb_array",), render_mode, **keywords)
        self.render_mode = self.settings.render_mode
        self.num_envs = int(num_envs)
        self.single_observation_space = observation_space(self.task)
        self.single_action_space = action_space(self.task)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._rngs: list[np.random.Generator] = []
        # Placeholders until reset: the dice in the hand, unturned.
        self._targets, self._hands = self.task.sample_hands(
            [np.random.default_rng(0)] * self.num_envs, orientation_mode="identity")

    def reset(self, *, seed: int | list[int | None] | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Seed (``seed + i`` per env, or a list) and reset every env with ``options``."""
        if seed is None or isinstance(seed, (int, np.integer)):
            seeds = [None if seed is None else int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
        return self.reset_envs(seeds, [options or {}] * self.num_envs), {}

    def reset_envs(self, seeds: Sequence[int | None],
                   options: Sequence[dict[str, Any] | None]) -> np.ndarray:
        """Reset env ``i`` with ``seeds[i]`` and ``options[i]``, as a single env's ``reset``.

        A ``None`` seed keeps env ``i``'s generator (a fresh one on the first reset).
        """
        for name, values in (("seed", seeds), ("options", options)):
            if len(values) != self.num_envs:
                raise ValueError(f"{name} must be one per env ({self.num_envs}), "
                                 f"got {len(values)}")
        self._rngs = [seeding.np_random(seed)[0] if seed is not None or not self._rngs
                      else self._rngs[i] for i, seed in enumerate(seeds)]
        for i, rng in enumerate(self._rngs):
            self._targets[i], self._hands[i] = episode_hand(self.task, self.settings, rng,
                                                              options[i])
        return self.task.observe(self._targets, self._hands)

    def step(self, actions: np.ndarray,
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Throw all N dice in one kernel call, then start the next episodes."""
        if not self._rngs:
            raise RuntimeError("call reset() before step()")
        throw = self.task.throw(actions, self._targets, self._hands, self._rngs,
                                action_shape=self.action_space.shape,
                                num_threads=self.settings.num_threads)
        mask = np.ones(self.num_envs, np.bool_)
        final_info = {k: v for key, value in throw.info.items()
                      for k, v in ((key, value), ("_" + key, mask))}
        info = {"final_obs": throw.observation, "_final_obs": mask,
                "final_info": final_info, "_final_info": mask}
        self._targets, self._hands = self.task.sample_hands(
            self._rngs, self.task.fixed_target(self.settings.target_face,
                                               self.settings.target_sum),
            self.settings.orientation_mode)
        return (self.task.observe(self._targets, self._hands), throw.reward.copy(),
                mask.copy(), np.zeros(self.num_envs, np.bool_), info)

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Each env's dice in the hand ("rgb_array"), a tuple of ``num_envs`` frames."""
        if self.render_mode != "rgb_array":
            return None
        from dice_env.envs.render import render_task

        task = self.task
        return tuple(render_task(task, task.hand_position, self._hands[i],
                                 size=self.settings.render_size) for i in range(self.num_envs))

"""DiceThrow-v0 natively batched: N throws per step in one kernel call, any Gymnasium autoreset."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from dice_env.envs.dice_throw import (
    RENDER_FPS,
    RESET_OPTIONS,
    action_space,
    configure,
    episode_hand,
    observation_space,
)
from dice_env.model.checks import check_choice, check_int

MAX_NUM_ENVS = 2**20  # about 1 kB per env in the kernel's and the env's arrays


class DiceThrowVectorEnv(VectorEnv):
    """``num_envs`` DiceThrow-v0 envs stepped together (``gym.make_vec("DiceThrow-v0", n)``).

    Takes :class:`~dice_env.envs.dice_throw.DiceThrowEnv`'s keywords. Every step ends every
    episode; ``autoreset_mode`` (an :class:`~gymnasium.vector.AutoresetMode` or its value) starts
    the next ones in the same step (``SAME_STEP``, the default: the throw's own observations and
    info in ``info["final_obs"]`` and ``info["final_info"]``), at the next step (``NEXT_STEP``:
    actions ignored, rewards 0, as Gymnasium's vector wrappers expect) or at ``reset``
    (``DISABLED``: all envs, or ``options["reset_mask"]``). Env ``i`` draws from its generator
    (seeded ``seed + i`` or ``seed[i]``) as a single env reset with that seed, so every mode
    throws the same throws.
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"], "render_fps": RENDER_FPS,
        "autoreset_mode": AutoresetMode.SAME_STEP,
    }

    def __init__(self, num_envs: int = 1, render_mode: str | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.SAME_STEP,
                 **keywords: Any) -> None:
        check_int("num_envs", num_envs, 1, MAX_NUM_ENVS)
        if not isinstance(autoreset_mode, AutoresetMode):  # or its value
            check_choice("autoreset_mode", autoreset_mode, [mode.value for mode in AutoresetMode],
                         also=" or a gymnasium.vector.AutoresetMode")
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        self.task, self.settings = configure(("rgb_array",), render_mode, **keywords)
        self.render_mode = self.settings.render_mode
        self.num_envs = int(num_envs)
        self._ended = np.zeros(self.num_envs, np.bool_)  # thrown, not started again
        self._at_rest: np.ndarray | None = None  # their observations, the dice at rest
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
        """Seed (``seed + i`` per env, or a list) and reset every env, or ``reset_mask``'s ones.

        ``options``: as a single env's, and ``"reset_mask"``, a bool array over the envs.
        """
        if seed is None or isinstance(seed, (int, np.integer)):
            seeds = [None if seed is None else int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
        if options is not None and not isinstance(options, dict):
            raise ValueError(f"options must be None or a dict with keys among {RESET_OPTIONS}, "
                             f"got {options!r}")
        options = dict(options or {})
        mask = options.pop("reset_mask", None)  # None: all
        if mask is not None and (not isinstance(mask, np.ndarray) or mask.dtype != np.bool_
                                 or mask.shape != (self.num_envs,) or not mask.any()):
            raise ValueError(f"options['reset_mask'] must be a numpy bool array of shape "
                             f"({self.num_envs},) with a True, got {mask!r}")
        return self.reset_envs(seeds, [options] * self.num_envs, mask), {}

    def reset_envs(self, seeds: Sequence[int | None], options: Sequence[dict[str, Any] | None],
                   mask: np.ndarray | None = None) -> np.ndarray:
        """Reset env ``i`` with ``seeds[i]`` and ``options[i]``, as a single env's ``reset``.

        A ``None`` seed keeps env ``i``'s generator (a fresh one on the first reset); ``mask``
        (None: all) picks the envs to reset, once every env has been reset; an env thrown and
        not reset keeps its observation at rest.
        """
        for name, values in (("seed", seeds), ("options", options)):
            if len(values) != self.num_envs:
                raise ValueError(f"{name} must be one per env ({self.num_envs}), "
                                 f"got {len(values)}")
        mask = np.ones(self.num_envs, np.bool_) if mask is None else mask
        if not self._rngs and not mask.all():
            raise ValueError("options['reset_mask'] needs a first reset of every env")
        self._rngs = [seeding.np_random(seed)[0] if seed is not None or not self._rngs
                      else self._rngs[i] for i, seed in enumerate(seeds)]
        for i in np.flatnonzero(mask):
            self._targets[i], self._hands[i] = episode_hand(self.task, self.settings,
                                                            self._rngs[i], options[i])
        obs = self.task.observe(self._targets, self._hands)
        self._ended &= ~mask
        if self._ended.any():  # thrown and not reset: still at rest
            obs[self._ended] = self._at_rest[self._ended]
        return obs

    def step(self, actions: np.ndarray,
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Throw all N dice in one kernel call; NEXT_STEP's step after a throw only starts anew."""
        if not self._rngs:
            raise RuntimeError("call reset() before step()")
        if self._ended.any():
            return self._start_next()
        throw = self.task.throw(actions, self._targets, self._hands, self._rngs,
                                action_shape=self.action_space.shape,
                                num_threads=self.settings.num_threads,
                                device=self.settings.device)
        mask = np.ones(self.num_envs, np.bool_)
        info = {k: v for key, value in throw.info.items()
                for k, v in ((key, value), ("_" + key, mask))}
        done = (throw.reward.copy(), mask.copy(), np.zeros(self.num_envs, np.bool_))
        if self.autoreset_mode is not AutoresetMode.SAME_STEP:
            self._ended[:], self._at_rest = True, throw.observation
            return throw.observation, *done, info
        info = {"final_obs": throw.observation, "_final_obs": mask,
                "final_info": info, "_final_info": mask}
        self._targets, self._hands = self._next_hands()
        return self.task.observe(self._targets, self._hands), *done, info

    def _next_hands(self) -> tuple[np.ndarray, np.ndarray]:
        """The next episodes' targets and hands, drawn from each env's generator."""
        settings = self.settings
        return self.task.sample_hands(
            self._rngs, self.task.goal.fix(settings.target_face, settings.target_sum),
            settings.orientation_mode)

    def _start_next(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        """NEXT_STEP's step after a throw: the next episodes, no throw; refused elsewhere."""
        ended = np.flatnonzero(self._ended).tolist()
        if self.autoreset_mode is AutoresetMode.DISABLED:
            raise RuntimeError(f"envs {ended} ended at the last step and autoreset_mode is "
                               "DISABLED: reset them (reset(), or options['reset_mask'])")
        if not self._ended.all():
            raise RuntimeError(f"envs {ended} ended at the last step and the others were reset "
                               "since: reset them all, or none, before the next step")
        self._targets, self._hands = self._next_hands()
        self._ended[:] = False
        none = np.zeros(self.num_envs, np.bool_)
        return (self.task.observe(self._targets, self._hands), np.zeros(self.num_envs),
                none, none.copy(), {})

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Each env's dice in the hand ("rgb_array"), a tuple of ``num_envs`` frames."""
        if self.render_mode != "rgb_array":
            return None
        from dice_env.envs.render import render_task

        task = self.task
        return tuple(render_task(task, task.hand_position, self._hands[i],
                                 size=self.settings.render_size) for i in range(self.num_envs))

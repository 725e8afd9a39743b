"""DiceThrow-v0's native batch as a Stable-Baselines3 ``VecEnv`` (SB3 cannot take a Gymnasium one).

Every step ends every episode (``dones`` all True); ``infos[i]`` holds the single env's info,
``"terminal_observation"`` (the dice at rest) and ``"TimeLimit.truncated": False``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from stable_baselines3.common.vec_env import VecEnv, VecMonitor
from stable_baselines3.common.vec_env.base_vec_env import VecEnvIndices, VecEnvStepReturn

from dice_env.envs.vector import DiceThrowVectorEnv
from dice_env.model.checks import check_int


def make_sb3_env(n_envs: int = 256, seed: int | None = None, *, env_id: str = "DiceThrow-v0",
                 **env_kwargs: Any) -> VecMonitor:
    """``n_envs`` DiceThrow envs as one SB3 VecEnv in SB3's ``VecMonitor``, like ``make_vec_env``.

    ``seed`` (None: unseeded) seeds env ``i`` with ``seed + i`` at the first ``reset``;
    ``env_kwargs``: ``gym.make``'s keywords. ``env_id``: an env with DiceThrow-v0's native batch.
    """
    seed = None if seed is None else check_int("seed", seed, 0, also=" or None")
    env = DiceThrowSB3VecEnv(gym.make_vec(env_id, num_envs=n_envs, vectorization_mode=None,
                                          **env_kwargs))
    if seed is not None:
        env.seed(seed)
    return VecMonitor(env)


class DiceThrowSB3VecEnv(VecEnv):
    """SB3 ``VecEnv`` over a :class:`DiceThrowVectorEnv` (``gym.make_vec("DiceThrow-v0", n)``).

    ``seed(s)`` makes the next ``reset`` seed env ``i`` with ``s + i``. The N envs are one batch:
    ``get_attr`` gives the batch's value per index; ``set_attr`` and ``env_method`` act on the
    whole batch (``indices`` must cover every env).
    """

    def __init__(self, venv: VectorEnv) -> None:
        if not isinstance(venv, DiceThrowVectorEnv):
            raise ValueError(f"venv must be an unwrapped DiceThrowVectorEnv (wrap the adapter in "
                             f"SB3's wrappers instead), got {type(venv).__name__}")
        if venv.autoreset_mode is not AutoresetMode.SAME_STEP:
            raise ValueError(f"venv must autoreset in the same step (autoreset_mode=SAME_STEP, "
                             f"the default), got {venv.autoreset_mode}")
        self.venv = venv
        self._actions: np.ndarray | None = None
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self.metadata = {**venv.metadata, **self.metadata}

    def reset(self) -> np.ndarray:
        """Start new episodes with the seeds and options set since the last reset (then cleared)."""
        obs = self.venv.reset_envs(self._seeds, self._options)
        self.reset_infos = [{} for _ in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Keep the actions (N, 6) for :meth:`step_wait`."""
        self._actions = np.asarray(actions)

    def step_wait(self) -> VecEnvStepReturn:
        """Throw all N dice in one kernel call; the observations are of the next episodes."""
        if self._actions is None:
            raise RuntimeError("call step_async() before step_wait()")
        obs, rewards, terminated, truncated, info = self.venv.step(self._actions)
        self._actions = None
        columns = {key: value.tolist() if value.ndim == 1 else value
                   for key, value in info["final_info"].items() if not key.startswith("_")}
        columns["terminal_observation"] = info["final_obs"]
        columns["TimeLimit.truncated"] = (truncated & ~terminated).tolist()
        infos = [{key: column[i] for key, column in columns.items()} for i in range(self.num_envs)]
        dones = np.logical_or(terminated, truncated)
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        """Close the vector env."""
        self.venv.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        """Each env's frame (render_mode "rgb_array")."""
        frames = self.venv.render()
        return [None] * self.num_envs if frames is None else list(frames)

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The batch's attribute, once per index."""
        value = getattr(self.venv, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set an attribute of the whole batch (``indices`` must cover every env)."""
        self._check_all(indices)
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        """Call a method of the batch once; its result once per index."""
        self._check_all(indices)
        result = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [result for _ in range(self.num_envs)]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper],
                       indices: VecEnvIndices = None) -> list[bool]:
        """False for each index: the envs of a native batch carry no per-env wrappers."""
        return [False for _ in self._get_indices(indices)]

    def _check_all(self, indices: VecEnvIndices) -> None:
        if sorted(self._get_indices(indices)) != list(range(self.num_envs)):
            raise ValueError(f"indices must cover all {self.num_envs} envs (one shared batch), "
                             f"got {indices!r}")


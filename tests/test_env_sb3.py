"""The SB3 VecEnv adapter over DiceThrow-v0's native batch."""

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import VecMonitor

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from dice_env.envs import DiceThrowSB3VecEnv

FAST = {"t_max": 2.0}  # gentle throws settle well within 2 s


def adapter(n: int, **kwargs: object) -> DiceThrowSB3VecEnv:
    return DiceThrowSB3VecEnv(gym.make_vec("DiceThrow-v0", num_envs=n, **FAST, **kwargs))


def test_same_seeds_as_vector_and_single_envs():
    n, seed = 3, 5
    actions = np.random.default_rng(1).uniform(-1.2, 1.2, (2, n, 6)).astype(np.float32)
    sb3 = adapter(n)
    sb3.seed(seed)
    sb3_obs = [sb3.reset()]
    sb3_steps = []
    for k in range(2):
        obs, rewards, dones, infos = sb3.step(actions[k])
        sb3_obs.append(obs)
        sb3_steps.append((rewards, dones, infos))
    venv = gym.make_vec("DiceThrow-v0", num_envs=n, **FAST)
    assert venv.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP
    obs, _ = venv.reset(seed=seed)
    assert np.array_equal(obs, sb3_obs[0])
    for k in range(2):
        obs, rewards, _, _, info = venv.step(actions[k])
        assert np.array_equal(obs, sb3_obs[k + 1])
        assert np.array_equal(rewards.astype(np.float32), sb3_steps[k][0])
        for i, sb3_info in enumerate(sb3_steps[k][2]):
            assert np.array_equal(sb3_info["terminal_observation"], info["final_obs"][i])
            assert sb3_info["face"] == info["final_info"]["face"][i]
    for i in range(n):
        env = gym.make("DiceThrow-v0", **FAST)
        obs, _ = env.reset(seed=seed + i)
        for k in range(2):
            assert np.array_equal(obs, sb3_obs[k][i])
            final, reward, _, _, info = env.step(actions[k, i])
            rewards, dones, infos = sb3_steps[k]
            assert np.array_equal(final, infos[i]["terminal_observation"])
            assert reward == rewards[i] and dones[i]
            assert info.keys() <= infos[i].keys()
            assert all(np.array_equal(info[key], infos[i][key]) for key in info)
            obs, _ = env.reset()


def test_step_output_types():
    sb3 = VecMonitor(adapter(2))
    sb3.seed(0)
    obs = sb3.reset()
    assert obs.shape == (2, 15) and obs.dtype == np.float32
    obs, rewards, dones, infos = sb3.step(np.zeros((2, 6), np.float32))
    assert rewards.dtype == np.float32 and dones.dtype == np.bool_ and dones.all()
    for info in infos:
        assert info["TimeLimit.truncated"] is False and type(info["is_success"]) is bool
        assert info["terminal_observation"].shape == (15,)
        assert info["episode"]["l"] == 1  # VecMonitor saw one-step episodes


def test_seed_is_used_once_and_options_per_env():
    sb3 = adapter(2)
    sb3.seed(3)
    first = sb3.reset()
    assert not np.array_equal(sb3.reset(), first)  # seeds are used once, then the rng goes on
    sb3.seed(3)
    assert np.array_equal(sb3.reset(), first)
    sb3.set_options([{"target_face": 2}, {"target_face": 5}])
    obs = sb3.reset()
    assert obs[0, 1] == 1.0 and obs[1, 4] == 1.0


def test_attributes_methods_and_wrappers():
    sb3 = adapter(2, render_mode="rgb_array", render_width=32, render_height=24)
    assert sb3.get_attr("target_face") == [None, None]
    sb3.set_attr("target_face", 6)
    sb3.seed(0)
    assert (sb3.reset()[:, 5] == 1.0).all()
    with pytest.raises(ValueError, match="indices"):
        sb3.set_attr("target_face", 1, indices=[0])
    assert len(sb3.env_method("render")) == 2
    assert sb3.env_is_wrapped(Monitor) == [False, False]
    assert sb3.render().dtype == np.uint8  # the N frames tiled
    with pytest.raises(ValueError, match="venv"):
        DiceThrowSB3VecEnv(gym.make_vec("CartPole-v1", num_envs=2))

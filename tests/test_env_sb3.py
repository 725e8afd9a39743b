"""The SB3 VecEnv adapter over DiceThrow-v0's native batch."""

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3 import PPO
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import VecCheckNan, VecMonitor

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from dice_env.envs import DiceThrowSB3VecEnv
from dice_env.envs.sb3 import make_sb3_env

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


def test_make_sb3_env_is_one_monitored_batch():
    env = make_sb3_env(n_envs=4, seed=0, **FAST)
    assert isinstance(env, VecMonitor) and isinstance(env.venv, DiceThrowSB3VecEnv)
    assert env.num_envs == 4 and env.observation_space.shape == (15,)
    assert env.action_space.shape == (6,)
    checked = VecCheckNan(env, raise_exception=True)  # SB3's NaN/inf check of obs and rewards
    checked.reset()
    _, rewards, dones, infos = checked.step(np.zeros((4, 6), np.float32))
    assert rewards.shape == (4,) and dones.all()
    assert all(info["episode"]["l"] == 1 for info in infos)


def test_make_sb3_env_seeding_reproducible():
    actions = np.random.default_rng(2).uniform(-1, 1, (3, 6)).astype(np.float32)

    def run(seed: int | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        env = make_sb3_env(n_envs=3, seed=seed, **FAST)
        first = env.reset()
        _, rewards, _, infos = env.step(actions)
        return first, rewards, np.array([info["face"] for info in infos])

    (obs_a, rewards_a, faces_a), (obs_b, rewards_b, faces_b) = run(7), run(7)
    assert np.array_equal(obs_a, obs_b) and np.array_equal(faces_a, faces_b)
    assert np.array_equal(rewards_a, rewards_b)
    venv = gym.make_vec("DiceThrow-v0", num_envs=3, **FAST)
    assert np.array_equal(venv.reset(seed=7)[0], obs_a)  # seed s: env i seeded with s + i
    assert not np.array_equal(run(8)[0], obs_a)


def test_make_sb3_env_passes_keywords_and_trains_ppo():
    env = make_sb3_env(n_envs=8, seed=1, shaping=0.5, until="decided", **FAST)
    assert env.get_attr("task")[0].shaping == 0.5
    model = PPO("MlpPolicy", env, n_steps=2, batch_size=16, n_epochs=1, seed=0, device="cpu")
    model.learn(16)
    assert model.num_timesteps == 16


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"n_envs": 0}, "num_envs"), ({"n_envs": 2.5}, "num_envs"), ({"seed": -1}, "seed"),
    ({"seed": "0"}, "seed"), ({"seed": True}, "seed"), ({"shaping": -1.0}, "shaping"),
    ({"until": "never"}, "until"),
])
def test_make_sb3_env_refuses_bad_values(kwargs: dict, match: str):
    with pytest.raises(ValueError, match=match):
        make_sb3_env(**{"n_envs": 2, **kwargs})


def test_set_attr_checks_a_setting_as_gym_make_does():
    sb3 = adapter(2, num_threads=1)
    assert sb3.get_attr("num_threads") == [1, 1]
    with pytest.raises(ValueError, match=r"target_face must be in \[1, 6\], got 7"):
        sb3.set_attr("target_face", 7)
    assert sb3.get_attr("target_face") == [None, None]  # the refused value is not kept
    sb3.set_attr("orientation_mode", "identity")
    sb3.seed(0)
    assert np.array_equal(sb3.reset()[:, 6:], np.tile(np.eye(3).ravel(), (2, 1)))

"""The native vector env's autoreset modes, and Gymnasium's vector wrappers around it."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode
from gymnasium.wrappers.vector import NormalizeObservation, RecordEpisodeStatistics

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from dice_env.envs import DiceThrowSB3VecEnv

N, SEED = 3, 7
FAST = {"t_max": 2.0}  # gentle throws settle in under 2 s
ACTIONS = np.random.default_rng(2).uniform(-1, 1, (2, N, 6)).astype(np.float32)


def make(mode: object = AutoresetMode.SAME_STEP, **kwargs: object) -> gym.vector.VectorEnv:
    return gym.make_vec("DiceThrow-v0", num_envs=N, autoreset_mode=mode, **FAST, **kwargs)


def same_step_throws() -> list:
    """Observations in the hand, then per step the reward and the throw's own observation."""
    venv = make()
    run = [venv.reset(seed=SEED)[0]]
    for actions in ACTIONS:
        obs, reward, _, _, info = venv.step(actions)
        run += [reward, info["final_obs"], obs]
    return run


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.DISABLED])
def test_every_mode_throws_the_same_throws(mode):
    venv = make(mode)
    assert venv.metadata["autoreset_mode"] is mode
    run = [venv.reset(seed=SEED)[0]]
    for actions in ACTIONS:
        obs, reward, terminated, truncated, info = venv.step(actions)
        assert terminated.all() and not truncated.any() and info["_is_success"].all()
        run += [reward, obs]
        if mode is AutoresetMode.NEXT_STEP:  # the next step starts the next episodes
            obs, reward, terminated, truncated, info = venv.step(actions)
            assert not (reward.any() or terminated.any() or truncated.any()) and info == {}
        else:
            obs, _ = venv.reset()
        run.append(obs)
    for ours, theirs in zip(run, same_step_throws(), strict=True):
        assert np.array_equal(ours, theirs)


def test_gymnasium_vector_wrappers_work_in_next_step_mode():
    with pytest.raises(ValueError, match="NEXT_STEP"):
        NormalizeObservation(make())  # Gymnasium's own refusal of SAME_STEP
    stats = RecordEpisodeStatistics(make("NextStep"))
    venv = NormalizeObservation(stats)
    first, _ = venv.reset(seed=SEED)
    rewards = []
    for actions in ACTIONS:
        obs, reward, _, _, info = venv.step(actions)
        assert np.array_equal(info["episode"]["r"], reward) and (info["episode"]["l"] == 1).all()
        rewards += list(reward)
        obs, _, _, _, info = venv.step(actions)
        assert "episode" not in info and np.isfinite(obs).all()
    assert list(stats.return_queue) == rewards and list(stats.length_queue) == [1] * 2 * N
    assert venv.obs_rms.count > N and not np.array_equal(obs, first)


def test_disabled_mode_and_a_reset_mask():
    venv = make(AutoresetMode.DISABLED)
    with pytest.raises(RuntimeError, match="reset"):
        venv.step(ACTIONS[0])
    venv.reset(seed=SEED)
    at_rest = venv.step(ACTIONS[0])[0]
    with pytest.raises(RuntimeError, match=r"envs \[0, 1, 2\] ended .* DISABLED"):
        venv.step(ACTIONS[1])
    obs, _ = venv.reset(options={"reset_mask": np.array([True, False, True])})
    assert np.array_equal(obs[1], at_rest[1]) and not np.array_equal(obs[0], at_rest[0])
    with pytest.raises(RuntimeError, match=r"envs \[1\] ended"):
        venv.step(ACTIONS[1])
    venv.reset(options={"reset_mask": np.array([False, True, False])})
    assert venv.step(ACTIONS[1])[2].all()


def test_next_step_mode_refuses_a_step_after_a_partial_reset():
    venv = make(AutoresetMode.NEXT_STEP)
    venv.reset(seed=SEED)
    venv.step(ACTIONS[0])
    venv.reset(options={"reset_mask": np.array([True, True, False])})
    with pytest.raises(RuntimeError, match=r"envs \[2\] ended .* reset them all, or none"):
        venv.step(ACTIONS[1])


@pytest.mark.parametrize(("value", "options", "match"), [
    ("sometimes", None, "autoreset_mode must be one of 'NextStep', 'SameStep', 'Disabled'"),
    (AutoresetMode.NEXT_STEP, {"reset_mask": [True] * N}, r"reset_mask'\] must be a numpy bool"),
    (AutoresetMode.NEXT_STEP, {"reset_mask": np.zeros(N, bool)}, "with a True"),
])
def test_bad_autoreset_mode_or_reset_mask(value, options, match):
    with pytest.raises(ValueError, match=match):
        make(value).reset(seed=0, options=options)


def test_a_first_reset_covers_every_env_and_sb3_needs_same_step():
    with pytest.raises(ValueError, match="needs a first reset of every env"):
        make().reset(options={"reset_mask": np.array([True, False, False])})
    with pytest.raises(ValueError, match="autoreset_mode=SAME_STEP"):
        DiceThrowSB3VecEnv(make("NextStep"))

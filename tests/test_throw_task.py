"""The task's pieces: one target object per kind, the reward apart from the info, and the
execution settings on the env rather than the task."""

from dataclasses import fields

import gymnasium as gym
import numpy as np
import pytest

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from dice_env.envs import throw_task
from dice_env.envs.targets import TARGETS, AvoidSumTarget, FaceTarget, SumTarget
from dice_env.envs.throw_task import ThrowTask, make_task

FAST = {"until": "decided", "t_max": 1.5}


@pytest.mark.parametrize("kind", sorted(TARGETS))
def test_each_target_kind_is_one_object_that_encodes_and_decodes(kind):
    task = make_task(num_dice=2, target=kind)
    assert type(task.goal) is TARGETS[kind] and task.goal.kind == kind
    rngs = [np.random.default_rng(k) for k in range(64)]
    targets, hands = task.sample_hands(rngs)
    assert targets.shape == (64, *task.target_shape)
    decoded, _ = task.decode(task.observe(targets, hands))
    np.testing.assert_array_equal(decoded, targets)


def test_a_sum_hits_its_total_and_avoid_sum_every_other():
    faces = np.array([[1, 6], [3, 3], [2, 2]])
    totals = np.array([7, 7, 7])
    np.testing.assert_array_equal(SumTarget((6, 6)).hit(faces, totals), [True, False, False])
    np.testing.assert_array_equal(AvoidSumTarget((6, 6)).hit(faces, totals), [False, True, True])
    np.testing.assert_array_equal(FaceTarget((6, 6)).hit(faces, np.array([[1, 6], [3, 4], [2, 2]])),
                                  [True, False, True])


@pytest.mark.parametrize("keywords", [{"shaping": 0.5}, {"num_dice": 2, "target": "faces",
                                                          "shaping": 0.5, **FAST}])
def test_the_reward_is_the_task_s_function_of_the_landing(keywords):
    task = make_task(**keywords)
    rng = np.random.default_rng(3)
    targets, hands = task.sample_hands([rng] * 8)
    actions, noise = rng.uniform(-1, 1, (8, task.action_dim)), task.sample_noise(rng, 8)
    thrown = task.throw(actions, targets, hands, noise)
    state, _ = task.release(actions, hands, noise)
    reward = task.reward(task.land(state, targets))
    np.testing.assert_array_equal(reward.total, thrown.reward)
    np.testing.assert_array_equal(reward.success, thrown.info["reward_success"])
    np.testing.assert_array_equal(reward.shaping, thrown.info["reward_shaping"])
    assert np.any(reward.shaping != 0.0)


def test_execution_settings_are_the_env_s_not_the_task_s(monkeypatch):
    for name in ("num_threads", "device"):
        assert name not in {f.name for f in fields(ThrowTask)}
        with pytest.raises(ValueError, match=rf"unknown keyword\(s\) \['{name}'\]"):
            make_task(**{name: 1})
    seen, real = [], throw_task.simulate

    def spy(*args, **kwargs):
        seen.append((kwargs["num_threads"], kwargs["device"]))
        return real(*args, **kwargs)

    monkeypatch.setattr(throw_task, "simulate", spy)
    env = gym.make("DiceThrow-v0", num_threads=1, device="cpu")
    assert (env.unwrapped.settings.num_threads, env.unwrapped.settings.device) == (1, "cpu")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    envs = gym.make_vec("DiceThrow-v0", num_envs=2, num_threads=1)
    envs.reset(seed=0)
    envs.step(envs.action_space.sample())
    assert seen == [(1, "cpu"), (1, "cpu")]

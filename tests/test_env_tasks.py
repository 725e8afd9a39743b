"""The named tasks: registered beside DiceThrow-v0, valid keywords, clean checkers, documented."""

import json
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from dice_env.envs import tasks
from dice_env.envs.dice_throw import DiceThrowEnv
from dice_env.envs.tasks import TASKS
from dice_env.envs.throw_task import check_task_keywords

ROOT = Path(__file__).resolve().parents[1]
IDS = [task.id for task in TASKS]
ENV_KEYWORDS = ("target_face", "target_sum", "orientation_mode")  # DiceThrowEnv's own


def test_dice_throw_v0_keeps_its_meaning():
    spec = gym.spec("DiceThrow-v0")
    assert spec.kwargs == {} and TASKS[0].id == "DiceThrow-v0" and TASKS[0].keywords == {}
    assert spec.entry_point == "dice_env.envs.dice_throw:DiceThrowEnv"
    assert spec.vector_entry_point == "dice_env.envs.vector:DiceThrowVectorEnv"


@pytest.mark.parametrize("task", TASKS, ids=IDS)
def test_each_id_is_the_env_with_its_keywords(task):
    spec = gym.spec(task.id)
    assert spec.kwargs == dict(task.keywords)
    assert (spec.entry_point, spec.vector_entry_point) == (
        gym.spec("DiceThrow-v0").entry_point, gym.spec("DiceThrow-v0").vector_entry_point)
    physics = {k: v for k, v in task.keywords.items() if k not in ENV_KEYWORDS}
    assert check_task_keywords(physics) == physics
    with pytest.raises(TypeError):  # the keywords are the registered ones, not copies to edit
        task.keywords["die"] = "d4"


def test_ids_are_unique_and_in_the_module_docstring():
    assert len(set(IDS)) == len(IDS)
    for task in TASKS:
        assert f"``{task.id}``" in tasks.__doc__
        assert all(f"``{key}" in tasks.__doc__ for key in task.keywords), task.id


@pytest.mark.parametrize("task", TASKS, ids=IDS)
def test_checkers_pass_and_a_sampled_throw_steps(task):
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(task.id)
    assert isinstance(env.unwrapped, DiceThrowEnv)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)
        sb3_check_env(gym.make(task.id).unwrapped)
    env.action_space.seed(0)
    obs, _ = env.reset(seed=0)
    assert obs in env.observation_space
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert obs in env.observation_space and np.isfinite(reward)
    assert terminated and not truncated and info["void_reason"] in ("", "leaning")


@pytest.mark.parametrize("task", TASKS, ids=IDS)
def test_the_vector_env_takes_the_registered_keywords(task):
    venv = gym.make_vec(task.id, num_envs=2)
    assert venv.unwrapped.task == gym.make(task.id).unwrapped.task
    venv.reset(seed=0)
    venv.step(venv.action_space.sample())


def test_the_benchmark_measured_every_registered_task():
    report = json.loads((ROOT / "benchmarks/results/tasks.json").read_text())
    assert [(t["id"], t["keywords"]) for t in report["tasks"]] == [
        (task.id, dict(task.keywords)) for task in TASKS]
    assert all(t["description"] == task.description
               for t, task in zip(report["tasks"], TASKS, strict=True))

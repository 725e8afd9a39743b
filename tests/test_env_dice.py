"""The environment and the agents follow the die and the walls: any standard die, a tray."""

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium.utils.env_checker import check_env

import dice_env  # noqa: F401
from agents.baselines import HandThrower, RandomThrower
from agents.config import Config
from agents.episodes import Batch
from agents.policy import TargetNormal
from dice_env import Die, Scene
from dice_env.envs import DiceThrowVectorEnv
from dice_env.envs.hand import face_up_rotation
from dice_env.envs.throw_task import make_task
from dice_env.model.rotations import uniform_rotations
from dice_env.model.surroundings import tray

NAMES = ("d4", "d6", "d8", "d10", "d12", "d20")


@pytest.mark.parametrize("name", NAMES)
def test_env_sizes_itself_from_the_die(name):
    env = gym.make("DiceThrow-v0", die=name, walls="tray", until="decided")
    faces = Die.standard(name).n_faces
    assert env.observation_space.shape == (faces + 9,)
    targets = set()
    for seed in range(12 * faces):
        obs, _ = env.reset(seed=seed)
        assert obs in env.observation_space and obs[:faces].sum() == 1
        targets.add(int(obs[:faces].argmax()) + 1)
    assert targets == set(range(1, faces + 1))  # every face is a target
    obs, _, terminated, _, info = env.step(np.zeros(6, np.float32))
    assert terminated and obs in env.observation_space and 1 <= info["face"] <= faces
    assert len(env.unwrapped.task.scene.walls) == 4


def test_d20_in_a_tray_passes_the_env_checker():
    env = gym.make("DiceThrow-v0", die="d20", walls="tray", until="decided")
    check_env(env.unwrapped, skip_render_check=True)


def test_keywords_build_the_die_and_the_walls():
    task = make_task(die="d20", size=0.025, mass=0.008, load_face=20, load_fraction=0.2,
                     walls="tray")
    die = task.scene.die
    assert die.name == "d20" and die.size == 0.025 and die.mass == 0.008
    assert np.dot(die.com, die.face_normals[19]) > 0  # the load sits toward face 20
    assert task.scene.walls == tray()
    assert make_task(die=Die.cuboid((0.01, 0.02, 0.02))).n_faces == 6
    assert make_task(walls=tray(0.2, 0.2)).scene.walls == tray(0.2, 0.2)
    # The default env is unchanged: the d6, no walls, released at 1.5 cm.
    default = make_task()
    assert default.scene.die == Die() and default.scene.walls == () and default.obs_dim == 15
    assert default.release_height == 0.015


@pytest.mark.parametrize(("keywords", "match"), [
    ({"die": "d7"}, "die must be a Die or one of"),
    ({"die": "d20", "edge": 0.02}, "edge is the d6's size; the die is a d20: use size"),
    ({"size": 0.02, "edge": 0.02}, "give size or edge, not both"),
    ({"size": -1.0}, "size must be"),
    ({"die": "d4", "target_face": 5}, r"target_face must be .*\[1, 4\]"),
    ({"die": "d8", "load_face": 9, "load_fraction": 0.1}, r"load_face must be .*\[1, 8\]"),
    ({"walls": "box"}, "walls must be one of"),
    ({"walls": [1, 2]}, "walls must be one of"),
    ({"scene": Scene(die=Die.cuboid((0.01, 0.02, 0.02))), "size": 0.02},
     "not a uniform die of a standard shape"),
])
def test_bad_die_keywords_are_refused(keywords, match):
    with pytest.raises(ValueError, match=match):
        gym.make("DiceThrow-v0", **keywords)


def test_release_height_follows_the_die():
    # The d10's corners reach 1.57 cm: it is released higher by default, with the d6's gap.
    task = make_task(die="d10")
    reach = np.linalg.norm(task.scene.die.vertices_body, axis=1).max()
    assert task.release_height > reach + 0.001
    with pytest.raises(ValueError, match="release_height must be >"):
        make_task(die="d10", release_height=0.015)


@pytest.mark.parametrize("name", NAMES)
def test_flat_hands_and_face_up_rotations_read_their_face(name):
    task = make_task(die=name)
    die = task.scene.die
    for face in die.labels:
        assert die.face_read(face_up_rotation(die, int(face)), np.array([0, 0, 1.0])) == face
    rngs = [np.random.default_rng(s) for s in range(40)]
    _, hands = task.sample_hands(rngs, orientation_mode="flat")
    reading = np.einsum("nij,fj->nfi", hands, die.reading)[..., 2].max(axis=1)
    assert np.allclose(reading, 1.0)  # a face's reading direction points straight up


@pytest.mark.parametrize("name", ["d4", "d8", "d20"])
def test_hand_thrower_beats_chance_on_every_die(name):
    task = make_task(die=name, until="decided")
    batch = Batch.sample(task, 300, np.random.default_rng(0), num_threads=1)
    hand = batch.throw(task, HandThrower(task))["is_success"].mean()
    chance = batch.throw(task, RandomThrower(0))["is_success"].mean()
    assert hand > 2.0 / task.n_faces and hand > chance + 0.1, (hand, chance)


def test_target_normal_extractor_uses_the_die_reading():
    task = make_task(die="d4")
    space = gym.spaces.Box(-1, 1, (task.obs_dim,), np.float32)
    extractor = TargetNormal(space)  # a d4 by its number of faces
    targets = np.array([1, 2, 3, 4])
    hands = uniform_rotations(np.random.default_rng(0).random((3, 4)))
    features = extractor(torch.as_tensor(task.observe(targets, hands)))
    expected = np.einsum("nij,nj->ni", hands, task.scene.die.reading[targets - 1])
    assert np.allclose(features[:, -3:].numpy(), expected, atol=1e-6)
    with pytest.raises(ValueError, match="pass reading"):
        TargetNormal(gym.spaces.Box(-1, 1, (16,), np.float32))
    kwargs = Config(preset="quick").ppo_kwargs(task.scene.die)["policy_kwargs"]
    assert np.allclose(kwargs["features_extractor_kwargs"]["reading"], task.scene.die.reading)


def test_vector_env_follows_the_die():
    env = DiceThrowVectorEnv(4, die="d12", until="decided")
    obs, _ = env.reset(seed=0)
    assert obs.shape == (4, 21)
    obs, reward, *_ = env.step(np.zeros((4, 6)))
    assert obs.shape == (4, 21) and reward.shape == (4,)

"""DiceThrow-v0 with several dice: the hand, the targets, the spaces, voids, batches, checkers."""

import gymnasium as gym
import numpy as np
import pytest

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from dice_env import Die, Wall
from dice_env.envs import throw_task as task_module
from dice_env.envs.hand import HAND_GAP
from dice_env.envs.sb3 import DiceThrowSB3VecEnv
from dice_env.envs.throw_task import ThrowTask, make_task
from dice_env.simulation.group import GroupResult

FAST = {"until": "decided", "t_max": 1.5}  # group throws: ended when decided, short


def make(**kwargs):
    return gym.make("DiceThrow-v0", **{**FAST, **kwargs})


# --- one die is today's env ------------------------------------------------------------------

@pytest.mark.parametrize("one", [{"num_dice": 1}, {"die": ("d6",)},
                                 {"die": ("d6",), "num_dice": 1}])
def test_one_die_is_the_single_die_env(one):
    assert type(make_task(**one)) is ThrowTask
    plain, given = make(), make(**one)
    for seed in range(3):
        a, b = plain.reset(seed=seed)[0], given.reset(seed=seed)[0]
        np.testing.assert_array_equal(a, b)
        action = np.random.default_rng(seed).uniform(-1, 1, 6)
        step_a, step_b = plain.step(action), given.step(action)
        np.testing.assert_array_equal(step_a[0], step_b[0])
        assert step_a[1:4] == step_b[1:4]
        for key, value in step_a[4].items():
            np.testing.assert_array_equal(value, step_b[4][key])


# --- spaces ------------------------------------------------------------------------------

@pytest.mark.parametrize(("kwargs", "obs", "act"), [
    ({"num_dice": 2}, 11 + 18, 6),                        # a total 2 ... 12, two orientations
    ({"num_dice": 2, "target": "faces"}, 12 + 18, 6),     # a one-hot per die
    ({"die": ("d6", "d20")}, 25 + 18, 6),                 # totals 2 ... 26
    ({"die": ("d6", "d20"), "target": "faces"}, 26 + 18, 6),
    ({"num_dice": 3, "set_dice": True}, 16 + 27, 6 + 9),  # a rotation vector per die
])
def test_spaces_are_sized_by_the_dice_and_the_target(kwargs, obs, act):
    env = make(**kwargs)
    assert env.observation_space.shape == (obs,) and env.action_space.shape == (act,)
    first, _ = env.reset(seed=0)
    assert first in env.observation_space
    assert env.unwrapped.task.obs_dim == obs


def test_sum_is_the_default_target_and_drawn_uniformly_over_the_totals():
    task = make_task(num_dice=2)
    assert task.target == "sum" and list(task.totals) == list(range(2, 13))
    targets, hands = task.sample_hands([np.random.default_rng(s) for s in range(2200)])
    assert hands.shape == (2200, 2, 3, 3)
    counts = np.bincount(targets, minlength=13)[2:]
    assert counts.min() > 140 and counts.max() < 260  # 200 each expected


def test_observations_decode_back_to_targets_and_hands():
    for target in ("sum", "faces"):
        task = make_task(die=("d4", "d6", "d20"), target=target)
        targets, hands = task.sample_hands([np.random.default_rng(s) for s in range(5)])
        decoded, back = task.decode(task.observe(targets, hands))
        np.testing.assert_array_equal(decoded, targets)
        np.testing.assert_allclose(back, hands, atol=1e-6)


# --- the hand ----------------------------------------------------------------------------

def test_hand_holds_the_dice_in_rows_of_four_centred_on_the_release_point():
    task = make_task(num_dice=2)
    reach = np.linalg.norm(Die().vertices_body, axis=1).max()
    spacing = 2 * reach + HAND_GAP
    assert task.hand.spacing == pytest.approx(spacing)
    np.testing.assert_allclose(task.hand.offsets, [[0, -spacing / 2, 0], [0, spacing / 2, 0]])
    np.testing.assert_allclose(task.hand.positions[:, 2], task.release_height)
    five = make_task(num_dice=5).hand.offsets
    np.testing.assert_allclose(five[:4, 0], -spacing / 2)  # the first row of four
    np.testing.assert_allclose(five[:4, 1], spacing * np.array([-1.5, -0.5, 0.5, 1.5]))
    np.testing.assert_allclose(five[4], [spacing / 2, 0, 0])  # the fifth, centred behind
    mixed = make_task(die=("d6", "d20"))
    d20 = np.linalg.norm(Die.standard("d20").vertices_body, axis=1).max()
    assert mixed.hand.spacing == pytest.approx(2 * max(reach, d20) + HAND_GAP)
    assert mixed.release_height > d20


def test_the_hand_is_rigid_and_each_die_has_its_own_noise():
    task = make_task(num_dice=3, hand_noise=0.05, orientation_noise=0.05)
    action = np.array([[0.3, -0.2, 0.1, 0.5, -0.4, 0.2]])
    hands = np.tile(np.eye(3), (1, 3, 1, 1))
    state, _ = task.release(action, hands, np.zeros((1, 27)))
    v, w = action[0, :3] * task.max_speed, action[0, 3:] * task.max_spin
    for i, r in enumerate(task.hand.offsets):
        np.testing.assert_allclose(state.velocity[0, i], v + np.cross(w, r))
        np.testing.assert_allclose(state.angular_velocity[0, i], w)
        np.testing.assert_allclose(state.position[0, i], task.hand.centre + r)
    assert task.sample_noise(np.random.default_rng(0), 4).shape == (4, 27)
    noise = np.zeros((1, 27))
    noise[0, 9:18] = 1.0  # die 1's own draws only
    noisy, _ = task.release(action, hands, noise)
    for i in (0, 2):
        np.testing.assert_array_equal(noisy.velocity[0, i], state.velocity[0, i])
        np.testing.assert_array_equal(noisy.orientation[0, i], state.orientation[0, i])
    assert not np.allclose(noisy.angular_velocity[0, 1], w)
    assert not np.allclose(noisy.orientation[0, 1], np.eye(3))


def test_each_die_draws_its_own_orientation_in_the_hand():
    task = make_task(num_dice=2)
    _, hands = task.sample_hand(np.random.default_rng(0))
    assert not np.allclose(hands[0], hands[1])
    _, flat = task.sample_hand(np.random.default_rng(0), orientation_mode="flat")
    assert np.allclose(np.abs(flat[:, 2]).max(axis=1), 1.0)  # a face read straight up


def test_set_dice_turns_each_die_in_the_hand():
    task = make_task(num_dice=2, set_dice=True, hand_noise=0.0, orientation_noise=0.0)
    action = np.zeros((1, 12))
    action[0, 6:9] = [0.5, 0.0, 0.0]  # die 0 half of pi about x
    state, _ = task.release(action, np.tile(np.eye(3), (1, 2, 1, 1)), np.zeros((1, 18)))
    np.testing.assert_allclose(state.orientation[0, 0], [[1, 0, 0], [0, 0, -1], [0, 1, 0]],
                               atol=1e-12)
    np.testing.assert_allclose(state.orientation[0, 1], np.eye(3))


# --- scoring: constructed group results ------------------------------------------------------

def fake_result(face, read, settled=True):
    """A simulate_group stand-in returning these faces (B, N) at rest."""
    def simulate_group(scene, dice, state, **_):
        b, n = np.shape(face)
        return GroupResult(
            face=np.where(read, face, 0), read=np.asarray(read), settled=np.full(b, settled),
            decided=np.zeros(b, bool), rest_time=np.ones(b), impacts=np.ones((b, n), int),
            unstable=np.zeros(b, bool), energy_rise=np.zeros(b), max_penetration=np.zeros((b, n)),
            overlap=np.zeros(b), sunk=np.zeros((b, n), bool), steps=np.ones(b, int),
            final=state, die_impacts=np.zeros((b, n), int), touched=np.ones((b, n, 1), bool),
            meet_dice=np.full((b, 2), -1), meet_steps=np.full((b, 2), -1),
            meet_velocity=np.zeros((b, 2, n, 3)), meet_spin=np.zeros((b, 2, n, 3)))
    return simulate_group


def throw_with(monkeypatch, task, targets, face, read):
    monkeypatch.setattr(task_module, "simulate_group", fake_result(face, read))
    n = len(face)
    hands = np.tile(np.eye(3), (n, task.n_dice, 1, 1))
    return task.throw(np.zeros((n, 6)), targets, hands, np.zeros((n, 9 * task.n_dice)))


def test_sum_target_succeeds_when_the_faces_add_up(monkeypatch):
    task = make_task(num_dice=2, until="rest", shaping=0.5)
    throw = throw_with(monkeypatch, task, [7, 5, 12], [[3, 4], [2, 2], [6, 6]],
                       np.ones((3, 2), bool))
    np.testing.assert_array_equal(throw.info["is_success"], [True, False, True])
    np.testing.assert_array_equal(throw.info["total"], [7, 4, 12])
    np.testing.assert_array_equal(throw.reward, [1.0, 0.0, 1.0])  # no shaping for a total
    np.testing.assert_array_equal(throw.info["target_sum"], [7, 5, 12])


def test_avoid_sum_target_succeeds_on_any_other_total_and_fails_when_void(monkeypatch):
    task = make_task(num_dice=2, target="avoid_sum", until="rest")
    throw = throw_with(monkeypatch, task, [7, 7, 5, 7], [[3, 4], [2, 2], [2, 3], [6, 6]],
                       np.array([[1, 1], [1, 1], [1, 1], [1, 0]], bool))
    np.testing.assert_array_equal(throw.info["is_success"], [False, True, False, False])
    np.testing.assert_array_equal(throw.info["void_reason"], ["", "", "", "leaning"])
    np.testing.assert_array_equal(throw.info["target_sum"], [7, 7, 5, 7])
    targets, _ = task.decode(throw.observation)
    np.testing.assert_array_equal(targets, [7, 7, 5, 7])  # observed as the "sum" target is


def test_faces_target_needs_every_die_and_shapes_by_the_mean_alignment(monkeypatch):
    task = make_task(num_dice=2, target="faces", until="rest", shaping=0.5)
    # Identity hands: face 1 (+z) up on both dice; face 2 (+x) on a side.
    throw = throw_with(monkeypatch, task, [[1, 1], [1, 2]], [[1, 1], [1, 1]],
                       np.ones((2, 2), bool))
    np.testing.assert_array_equal(throw.info["is_success"], [True, False])
    np.testing.assert_allclose(throw.info["reward_shaping"], [0.5, 0.25])
    np.testing.assert_allclose(throw.reward, [1.5, 0.25])


def test_a_die_leaning_on_another_voids_the_throw(monkeypatch):
    task = make_task(num_dice=2, until="rest")
    throw = throw_with(monkeypatch, task, [7, 7], [[3, 4], [3, 4]], [[True, True], [True, False]])
    np.testing.assert_array_equal(throw.info["void_reason"], ["", "leaning"])
    np.testing.assert_array_equal(throw.info["leaning"], [[False, False], [False, True]])
    np.testing.assert_array_equal(throw.reward, [1.0, 0.0])
    np.testing.assert_array_equal(throw.info["face"], [[3, 4], [3, 0]])


# --- envs ----------------------------------------------------------------------------------

def test_two_dice_are_thrown_and_scored():
    env = make(num_dice=2, target_sum=7)
    obs, _ = env.reset(seed=1)
    assert obs[5] == 1.0 and obs[:11].sum() == 1.0  # the one-hot of 7
    obs, reward, terminated, truncated, info = env.step(np.array([0.3, 0.1, 0.2, 0.3, -0.5, 0.4]))
    assert terminated and not truncated and obs in env.observation_space
    assert info["face"].shape == (2,) and info["release_velocity"].shape == (2, 3)
    assert info["is_success"] == (info["total"] == 7 and info["void_reason"] == "")
    assert reward == float(info["is_success"])


def test_vector_env_and_sb3_adapter_with_two_dice_match_single_envs():
    kwargs = {**FAST, "num_dice": 2, "target": "faces"}
    venv = gym.make_vec("DiceThrow-v0", num_envs=2, vectorization_mode=None, **kwargs)
    obs, _ = venv.reset(seed=5)
    assert obs.shape == (2, 30)
    actions = np.random.default_rng(0).uniform(-1, 1, (2, 6))
    _, rewards, terminated, _, info = venv.step(actions)
    assert terminated.all() and info["final_info"]["face"].shape == (2, 2)
    assert info["final_obs"].shape == (2, 30)
    for i in range(2):
        single = gym.make("DiceThrow-v0", **kwargs)
        np.testing.assert_array_equal(single.reset(seed=5 + i)[0], obs[i])
        final, reward, *_, single_info = single.step(actions[i])
        np.testing.assert_array_equal(final, info["final_obs"][i])
        np.testing.assert_array_equal(single_info["face"], info["final_info"]["face"][i])
        assert reward == rewards[i]
    sb3 = DiceThrowSB3VecEnv(gym.make_vec("DiceThrow-v0", num_envs=2, vectorization_mode=None,
                                          **kwargs))
    sb3.seed(5)
    assert sb3.reset().shape == (2, 30)
    sb3.step_async(actions)
    obs, rewards, dones, infos = sb3.step_wait()
    assert obs.shape == (2, 30) and dones.all() and infos[0]["face"].shape == (2,)
    assert infos[1]["terminal_observation"].shape == (30,)


def test_both_checkers_pass_with_two_dice():
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    check_env(make(num_dice=2, t_max=1.0).unwrapped, skip_render_check=True)
    sb3_check_env(make(num_dice=2, t_max=1.0, target="faces"), warn=False)


def test_render_shows_every_die():
    env = make(num_dice=2, render_mode="rgb_array", render_width=80, render_height=60,
               walls="tray")
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (60, 80, 3) and frame.dtype == np.uint8
    one = make(render_mode="rgb_array", render_width=80, render_height=60, walls="tray")
    one.reset(seed=0)
    white = (frame.min(axis=2) > 150).sum()  # the dice's lit faces
    assert white > 1.3 * (one.render().min(axis=2) > 150).sum()
    venv = gym.make_vec("DiceThrow-v0", num_envs=2, vectorization_mode=None, num_dice=3,
                        render_mode="rgb_array", render_width=40, render_height=30, **FAST)
    venv.reset(seed=0)
    assert [f.shape for f in venv.render()] == [(30, 40, 3)] * 2


def test_frames_of_two_dice_come_at_render_fps():
    env = make(num_dice=2, render_mode="rgb_array_list", render_width=32, render_height=24,
               walls="tray")
    env.reset(seed=1)
    _, _, _, _, info = env.step(np.zeros(6))
    frames = env.render()  # in the hand, every 1/fps s of the throw, at rest
    assert abs(len(frames) - 2 - info["rest_time"] * env.metadata["render_fps"]) <= 2


# --- bad input -----------------------------------------------------------------------------

@pytest.mark.parametrize(("kwargs", "name"), [
    ({"num_dice": 0}, "num_dice"),
    ({"num_dice": 13}, "num_dice"),
    ({"num_dice": 2.0}, "num_dice"),
    ({"num_dice": True}, "num_dice"),
    ({"num_dice": 3, "die": ("d6", "d20")}, "die"),
    ({"die": ()}, "die"),
    ({"die": ("d6", "d7")}, "die"),
    ({"num_dice": 2, "target_sum": 1}, "target_sum"),
    ({"num_dice": 2, "target_sum": 13}, "target_sum"),
    ({"num_dice": 2, "target_sum": 7.0}, "target_sum"),
    ({"target_sum": 3}, "target_sum"),                       # one die
    ({"num_dice": 2, "target_face": 3}, "target_face"),      # sum target
    ({"num_dice": 2, "target": "faces", "target_face": (1, 7)}, "target_face"),
    ({"num_dice": 2, "target": "faces", "target_face": 3}, "target_face"),
    ({"num_dice": 2, "target": "faces", "target_sum": 7}, "target_sum"),
    ({"num_dice": 2, "target": "total"}, "target"),
    ({"target": "sum"}, "target"),                           # one die
    ({"target": "avoid_sum"}, "target"),                     # one die
    ({"num_dice": 2, "target": "avoid_sum", "target_face": (1, 2)}, "target_face"),
    ({"set_dice": True}, "set_dice"),                        # one die
    ({"num_dice": 2, "set_dice": "yes"}, "set_dice"),
    ({"num_dice": 12, "walls": (Wall.through((0.04, 0, 0), (-1, 0, 0)),)}, "walls"),
])
def test_bad_keywords_are_refused_naming_them(kwargs, name):
    with pytest.raises(ValueError, match=name):
        make(**kwargs)


def test_bad_actions_and_options_are_refused():
    env = make(num_dice=2, set_dice=True)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"action must have shape \(12,\)"):
        env.step(np.zeros(6))
    with pytest.raises(ValueError, match=r"options\['orientation'\] must be 2 rotation"):
        env.reset(options={"orientation": np.eye(3)})
    for one in (env, make()):
        with pytest.raises(ValueError, match=r"options\['orientation'\] must be an array of "):
            one.reset(options={"orientation": "eye"})
    obs, _ = env.reset(options={"orientation": np.stack([np.eye(3)] * 2), "target_sum": 12})
    assert obs[10] == 1.0
    assert type(make_task(num_dice=2)) is ThrowTask


# --- agents --------------------------------------------------------------------------------

def test_agents_size_themselves_from_a_task_of_two_dice():
    from agents.episodes import Batch
    from agents.evaluate import summary, target_values
    from agents.oracle import CEM, score, score_noise, search
    from agents.replay import gif_name

    task = make_task(num_dice=2, **FAST)
    rng = np.random.default_rng(0)
    batch = Batch.sample(task, 3, rng, target_sum=7)
    assert batch.observations.shape == (3, 29) and batch.noise.shape == (3, 18)
    np.testing.assert_array_equal(batch.targets, 7)
    actions = rng.uniform(-1, 1, (3, 6))
    info = batch.throw(task, lambda obs: actions)
    assert info["face"].shape == (3, 2)
    assert summary(info["is_success"], batch.targets, target_values(task))["per_target"].keys() \
        <= {7}
    tiny = CEM(global_candidates=1, restarts=1, iterations=1, population=2, noise_samples=1,
               finalists=1, validation_samples=1)
    found = search(task, batch.observations[:1], rng, tiny, starts={"random": actions[:1]})
    assert found.shape == (1, 6)
    assert score(task, batch.observations[:1], found, score_noise(task, rng, 1, 2)).shape == (1, 2)
    with pytest.raises(ValueError, match="starts"):
        search(task, batch.observations[:1], rng, tiny)
    one = {k: v[0] for k, v in info.items()}
    assert gif_name("throw", 0, "PPO", one).startswith("throw_0_PPO_sum7_landed")
    faces = make_task(num_dice=2, target="faces", **FAST)
    assert target_values(faces) == []
    one = {"is_success": True, "target_face": np.array([3, 5]), "face": np.array([3, 5])}
    assert gif_name("throw", 1, "PPO", one) == "throw_1_PPO_target3-5_landed3-5_success.gif"


def test_one_die_presets_are_refused_for_several_dice():
    from agents.config import parse_config

    with pytest.raises(SystemExit):
        parse_config(["--env", "num_dice=2", "--preset", "quick"])
    assert parse_config(["--env", "num_dice=2", "--preset", "scratch"]).env_kwargs() == {
        "num_dice": 2}


@pytest.mark.slow
def test_train_runs_end_to_end_with_two_dice(tmp_path):
    """About 10 minutes on two shared cores, most of it the oracle's search."""
    from agents.train import main

    main(["--env", "num_dice=2", "--total-timesteps", "2048", "--eval-throws", "64",
          "--oracle-observations", "2", "--robustness-throws", "0", "--gifs", "1",
          "--preset", "scratch", "--runs", str(tmp_path), "--no-progress"])
    run = next(tmp_path.iterdir())
    report = (run / "report.md").read_text()
    assert "oracle" in report and len(list(run.glob("throw_*.gif"))) == 1


def test_the_step_limit_counts_moves_near_another_die_not_units():
    """A throw's limit of ENV_MAX_STEPS bounds its moves at the die–die contact's step."""
    from dice_env.envs.keywords import ENV_MAX_STEPS
    from dice_env.simulation.group import group_step, pair_step

    scene = make_task(num_dice=2).scene
    near, unit = pair_step(scene, (Die(),) * 2), group_step(scene, (Die(),) * 2)
    assert near > 2 * unit  # a move near another die is several units
    make_task(num_dice=2, t_max=0.99 * ENV_MAX_STEPS * near)  # more units than the limit
    with pytest.raises(ValueError, match="t_max must be at most"):
        make_task(num_dice=2, t_max=1.01 * ENV_MAX_STEPS * near)

"""DiceThrow-v0 under bad and extreme input: refused where given, never a crash, hang or NaN."""

import math
import time

import gymnasium as gym
import numba
import numpy as np
import pytest

import dice_env
from dice_env import ContactLaw, Die, FrictionLaw, Ground, Rest, Scene, Scheme, simulate
from dice_env.envs import make_task
from dice_env.envs.throw_task import task_keywords

FAST = {"t_max": 2.0}


def make(**kwargs):
    return gym.make("DiceThrow-v0", **{**FAST, **kwargs})


def refused(match, **kwargs):
    with pytest.raises(ValueError, match=match):
        make(**kwargs)


# --- the paper's contact law -------------------------------------------------------------------

def test_paper_law_with_the_table_damping_is_refused_with_the_numbers():
    # The table's damping (6.4 N s/m) is an air drag that lets the die sink at 0.86 mm/s.
    for law in ("paper", ContactLaw.PAPER):
        refused(r"contact_law='paper' needs damping <= .* = 0\.01017 N s/m, got damping=6\.38"
                r".* falls at most .* = 0\.000864 m/s", contact_law=law)
    refused(r"needs damping <= .*0\.005", contact_law="paper", damping=0.01, release_height=0.06)
    # Without gravity the drag stops every die in the air (the kernel then divided by zero).
    refused(r"needs damping <= .* = 0 N s/m, got damping=0\.001", contact_law="paper",
            damping=0.001, gravity=0.0)
    with pytest.raises(ValueError, match="contact_law='paper' needs damping"):
        gym.make("DiceThrow-v0", scene=Scene(ground=Ground(contact_law=ContactLaw.PAPER)))


def test_paper_law_with_a_small_damping_lands_and_settles():
    venv = gym.make_vec("DiceThrow-v0", num_envs=16, contact_law="paper", damping=0.01, **FAST)
    venv.reset(seed=0)
    info = venv.step(np.random.default_rng(1).uniform(-1, 1, (16, 6)))[4]["final_info"]
    assert (info["impacts"] > 0).all()
    assert (info["void_reason"] == "").sum() >= 14  # measured 15 of 16 (t_max 5 s: the same)
    assert make(contact_law="paper", damping=0.0).unwrapped.task.scene.ground.damping == 0.0


# --- keywords checked where given ------------------------------------------------------------

@pytest.mark.parametrize(("keywords", "match"), [
    ({"num_threads": 1000},
     rf"num_threads must be an int in \[1, {numba.config.NUMBA_NUM_THREADS}\]"),
    ({"num_threads": True}, "num_threads"),
    ({"load_face": 9}, r"load_face must be in \[1, 6\]"),
    ({"load_face": 2.5}, "load_face must be an int"),
    ({"load_depth": 5.0}, r"load_depth must be in \[0.0, 1.0\)"),
    ({"load_depth": -1.0, "load_fraction": 0.0}, "load_depth"),
    ({"t_max": 1e30}, r"t_max / step must be <= 1e\+09 steps, .*t_max 1e\+30"),
    ({"stiffness": 1e12}, r"t_max must be at most .*the table \(stiffness 1e\+12"),
    ({"mass": 1e-9}, r"t_max / step must be <= .*mass 1e-09"),
    ({"damping": 1e6}, r"t_max / step must be <= .*damping 1e\+06"),
    ({"safety": 1e-9}, r"t_max / step must be <= .*safety 1e-09"),
    ({"dt": 1e-12}, r"t_max / step must be <= .*step 1e-12 s"),
    ({"rest_hold": 1e300}, r"rest_hold must be at most 1e\+07 steps"),
    ({"rest_hold": -1.0}, "rest_hold must be a finite number >= 0"),
    ({"rest_speed": 0.0}, "rest_speed must be a finite number > 0"),
    ({"mass": 1e30}, r"the step must be in \(0, t_max = 2\] s.*mass 1e\+30"),
    ({"gravity": 1e6}, r"weight would press .* gravity=1e\+06"),
    ({"edge": 1e-300, "dt": 1e-5}, r"edge=1e-300 m, .* give no valid die"),
    ({"damping": 1e30}, r"t_max / step must be <= .*damping 1e\+30"),
    ({"edge": 1e-300, "load_fraction": 0.2}, "edge=1e-300 m, .* give no valid die"),
    ({"edge": [1.0], "load_fraction": 0.2}, "edge must be a finite number > 0"),
    ({"dt": 1e-5, "safety": 0.3}, "safety has no effect with a fixed step"),
    ({"friction_vmin": 0.1}, "friction_vmin acts only with friction_law='regularized'"),
    ({"contact_law": Scheme.PAPER}, "contact_law must be a ContactLaw or one of 'gated', "),
    ({"contact_law": 7}, "contact_law"),
    ({"until": ["rest"]}, "until must be one of"),
    ({"orientation_mode": np.array(["flat"])}, "orientation_mode must be one of"),
    ({"render_mode": np.array(["rgb_array"])}, "render_mode must be None or one of"),
    ({"render_mode": "rgb_array_list", "t_max": 20.0, "render_width": 1024,
      "render_height": 1024}, r"t_max must be at most 11.38 s with render_mode='rgb_array_list'"),
    ({"scene": "default"}, "scene must be a dice_env.Scene"),
])
def test_bad_keywords_are_refused_at_make(keywords, match):
    refused(match, **keywords)


def test_bad_vector_keywords_are_refused_at_make():
    with pytest.raises(ValueError, match=r"num_envs must be an int in \[1, 1048576\]"):
        gym.make_vec("DiceThrow-v0", num_envs=10**9)
    with pytest.raises(ValueError, match="num_threads"):
        gym.make_vec("DiceThrow-v0", num_envs=2, num_threads=1000)


def test_enums_and_their_names_give_the_same_scene():
    by_name = make_task(contact_law="paper", damping=0.01, friction_law="regularized",
                        scheme="paper").scene
    by_member = make_task(contact_law=ContactLaw.PAPER, damping=0.01,
                          friction_law=FrictionLaw.REGULARIZED, scheme=Scheme.PAPER).scene
    upper = make_task(contact_law="PAPER", damping=0.01, friction_law="Regularized",
                      scheme="PAPER").scene
    assert by_name == by_member == upper
    assert by_name.ground.contact_law is ContactLaw.PAPER and by_name.scheme is Scheme.PAPER


def test_a_batch_of_actions_to_the_single_env_is_refused_before_simulating(monkeypatch):
    def fail(*args, **kwargs):
        raise AssertionError("simulated a refused action")

    env = make()
    env.reset(seed=0)
    monkeypatch.setattr("dice_env.envs.throw_task.simulate", fail)
    for bad in (np.zeros((2, 6)), np.zeros((1, 6)), [[0.0] * 6]):
        with pytest.raises(ValueError, match=r"action must have shape \(6,\)"):
            env.step(bad)
    for bad in (["a"] * 6, {"vx": 1.0}):
        with pytest.raises(ValueError, match="action must be an array of numbers"):
            env.step(bad)


def test_unknown_reset_options_are_refused():
    env = make()
    venv = gym.make_vec("DiceThrow-v0", num_envs=2, **FAST)
    for reset in (env.reset, venv.reset):
        for bad in ({"target": 3}, {"target_face": 3, "seed": 1}, [("target_face", 3)]):
            with pytest.raises(ValueError, match="options must be None or a dict with keys among"):
                reset(seed=0, options=bad)
        with pytest.raises(ValueError, match="orientation_mode must be one of"):
            reset(seed=0, options={"orientation_mode": ["flat"]})
    assert env.reset(seed=0, options={"target_face": 3})[0][2] == 1.0


# --- keywords modify the given scene, never replace parts of it ------------------------------

def test_keywords_keep_the_rest_of_the_given_scene():
    loaded = Die.loaded(face=2, fraction=0.2)
    scene = Scene(die=loaded, t_max=1.0, ground=Ground.tilted(5.0, tangential=0.5),
                  rest=Rest(speed=0.01))
    kept = make_task(scene=scene, stiffness=2e5, rest_hold=0.2).scene
    assert kept.die == loaded and kept.t_max == 1.0 and kept.rest == Rest(speed=0.01, hold=0.2)
    assert kept.ground == Ground.tilted(5.0, tangential=0.5, stiffness=2e5)
    assert make_task(scene=scene, tilt_deg=0.0).scene.ground.normal == (0.0, 0.0, 1.0)
    assert make_task(scene=Scene(t_max=1.0)).scene.t_max == 1.0  # not the env's 5 s
    assert make_task().scene == Scene(t_max=5.0)
    assert make_task(scene=scene).scene == scene


@pytest.mark.parametrize("keywords", [{"mass": 0.0045}, {"edge": 0.02},
                                      {"load_fraction": 0.0}, {"load_face": 3}])
def test_die_keywords_on_a_loaded_die_are_refused(keywords):
    name = next(iter(keywords))
    refused(rf"{name} cannot be applied to the scene's die: it is not a uniform die",
            scene=Scene(die=Die.loaded(face=2, fraction=0.2)), **keywords)


def test_die_keywords_build_the_die_on_a_uniform_one():
    die = make_task(scene=Scene(die=Die(edge=0.02)), mass=0.01, load_fraction=0.1,
                    load_face=3, release_height=0.03).scene.die
    assert die == Die.loaded(face=3, fraction=0.1, edge=0.02, mass=0.01)
    assert make_task(load_face=3, load_depth=0.5).scene.die == Die()  # no load at fraction 0


def test_rest_hold_decides_which_throws_settle_within_t_max():
    # As if the hold were waited out: a die quiet within rest_hold of t_max is not settled.
    n, hold, t_max = 64, 0.3, 0.6
    venv = gym.make_vec("DiceThrow-v0", num_envs=n, rest_hold=hold, t_max=t_max)
    venv.reset(seed=0)
    actions = np.random.default_rng(7).uniform(-1, 1, (n, 6))
    info = venv.step(actions)[4]["final_info"]
    task = venv.unwrapped.task
    release = task.scene.die, info["release_velocity"], info["release_spin"]
    assert release[0] == Die()
    state = dice_env.State.release(task.scene, task.hand.centre, info["release_velocity"],
                                   info["release_spin"], info["release_orientation"])
    waited = simulate(task.scene, state)  # the hold waited out
    np.testing.assert_array_equal(info["settled"], waited.settled)
    np.testing.assert_array_equal(info["face"], waited.face)
    np.testing.assert_allclose(info["rest_time"], waited.rest_time)
    assert 0 < waited.settled.sum() < n  # some dice went quiet too late for the hold
    short = gym.make_vec("DiceThrow-v0", num_envs=n, rest_hold=0.0, t_max=t_max)
    short.reset(seed=0)
    assert short.step(actions)[4]["final_info"]["settled"].sum() > waited.settled.sum()


# --- fuzz: random keyword sets through gym.make and step --------------------------------------

BAD = [-1.0, 0.0, math.nan, math.inf, -math.inf, 1e30, -1e30, 1e-300, "x", True, [1.0], None]
CHOICES = {
    "orientation_mode": ["uniform", "flat", "identity"],
    "contact_law": ["gated", "paper", ContactLaw.GATED, ContactLaw.PAPER, "GATED"],
    "scheme": ["paper", "midpoint", Scheme.MIDPOINT],
    "friction_law": ["stick_slip", "regularized", FrictionLaw.REGULARIZED],
    "until": ["rest", "decided"],
    "die": ["d4", "d6", "d8", "d10", "d12", "d20"],
    "walls": ["none", "tray", "craps"],
    "target": ["faces", "sum"],
    "set_dice": [False, True],
    "device": ["cpu", "CPU", "gpu"],  # "cuda" is refused by its own test (no GPU here)
}
RANGES = {  # name: (low, high, log scale)
    "release_height": (0.0145, 0.1, True), "max_speed": (0.1, 5.0, True),
    "max_spin": (1.0, 100.0, True), "hand_noise": (0.0, 0.5, False),
    "orientation_noise": (0.0, 0.5, False), "min_speed": (0.0, 1.0, False),
    "min_spin": (0.0, 20.0, False), "shaping": (0.0, 1.0, False), "t_max": (0.05, 2.0, True),
    "edge": (0.005, 0.03, True), "size": (0.005, 0.03, True), "mass": (1e-3, 0.05, True),
    "load_fraction": (0.0, 0.5, False),
    "load_depth": (0.0, 0.99, False), "stiffness": (1e3, 1e7, True), "damping": (1e-3, 20.0, True),
    "friction": (0.0, 1.0, False), "tilt_deg": (0.0, 30.0, False), "gravity": (0.0, 30.0, False),
    "dt": (1e-6, 1e-4, True), "safety": (0.05, 1.0, False), "rest_speed": (1e-4, 0.05, True),
    "rest_hold": (0.0, 0.5, False), "energy_tol": (0.01, 1.0, True),
    "friction_vmin": (1e-6, 0.1, True),
}
INTEGERS = {"target_face": (1, 6), "load_face": (1, 6), "num_dice": (1, 3),
            "num_threads": (1, numba.config.NUMBA_NUM_THREADS)}


def random_value(rng, name):
    """A valid value of keyword ``name`` (nine times in ten) or a bad one."""
    if rng.random() < 0.1:
        return BAD[rng.integers(len(BAD))]
    if name in CHOICES:
        return CHOICES[name][rng.integers(len(CHOICES[name]))]
    if name in INTEGERS:
        return int(rng.integers(INTEGERS[name][0], INTEGERS[name][1] + 1))
    low, high, log = RANGES[name]
    return float(np.exp(rng.uniform(np.log(low), np.log(high))) if log else rng.uniform(low, high))


def random_action(rng, dim=6):
    """Mostly a valid action of ``dim`` (in and out of [-1, 1]), sometimes a bad one."""
    bad = [np.full(dim, np.nan), np.zeros(dim - 1), np.zeros((2, dim)), ["a"] * dim,
           np.full(dim, np.inf)]
    if rng.random() < 0.1:
        return bad[rng.integers(len(bad))], True
    return rng.uniform(-2.0, 2.0, dim), False


def names_a_keyword(error, keywords):
    message = str(error).split(" was raised from the environment creator")[0]  # gym's suffix
    return any(name in message for name in keywords)


def fuzz(rng, budget_s=math.inf, iterations=None):
    """Random keyword sets through ``gym.make`` and a step each, for ``budget_s`` seconds.

    Or ``iterations`` keyword sets, whichever ends first.

    Each ends in a finite observation and reward, or a ValueError/TypeError naming one of the
    keywords (or the action) given. Returns the counts of the outcomes.
    """
    names = sorted([*RANGES, *CHOICES, *INTEGERS])
    start, outcomes = time.perf_counter(), {"made": 0, "refused": 0, "stepped": 0}
    while time.perf_counter() - start < budget_s and (
            iterations is None or outcomes["made"] + outcomes["refused"] < iterations):
        keywords = {str(name): random_value(rng, name)
                    for name in rng.choice(names, rng.integers(1, 5), replace=False)}
        keywords.setdefault("t_max", 1.0)
        try:
            env = gym.make("DiceThrow-v0", **keywords)
        except (ValueError, TypeError) as error:
            assert names_a_keyword(error, keywords), (keywords, error)
            outcomes["refused"] += 1
            continue
        except Exception as error:
            raise AssertionError(f"gym.make(**{keywords}) raised {error!r}") from error
        outcomes["made"] += 1
        env.reset(seed=int(rng.integers(1000)))
        action, bad = random_action(rng, env.action_space.shape[0])
        began = time.perf_counter()
        try:
            obs, reward, *_, info = env.step(action)
        except ValueError as error:
            assert bad and "action" in str(error), (keywords, action, error)
            continue
        except Exception as error:
            raise AssertionError(f"step({action!r}) with {keywords} raised {error!r}") from error
        assert not bad, (keywords, action)
        assert time.perf_counter() - began < 30.0, keywords
        assert np.isfinite(obs).all() and math.isfinite(reward), (keywords, action, info)
        assert obs in env.observation_space, (keywords, obs)
        outcomes["stepped"] += 1
    return outcomes


def test_fuzz_keywords_and_actions():
    known = task_keywords() - {"scene"}
    assert set(RANGES) | set(CHOICES) | set(INTEGERS) == known | {
        "target_face", "orientation_mode", "num_threads", "device"}  # the env's, not the task's
    for dice in (1, 2):  # compile the one-die and the group kernels outside the time budget
        env = gym.make("DiceThrow-v0", num_dice=dice, t_max=0.05)
        env.reset(seed=0)
        env.step(env.action_space.sample())
    outcomes = fuzz(np.random.default_rng(14), budget_s=6.0)
    assert outcomes["stepped"] >= 10 and outcomes["refused"] >= 10, outcomes


@pytest.mark.slow
def test_fuzz_keywords_and_actions_long():
    totals = {"made": 0, "refused": 0, "stepped": 0}
    for seed in range(200, 230):  # 30 seeds x 5000 keyword sets
        for key, count in fuzz(np.random.default_rng(seed), iterations=5000).items():
            totals[key] += count
    print(totals)

"""Random keyword sets and random states: a result or a named refusal, nothing else."""

import numpy as np

from dice_env import Die, Ground, Scene, State, simulate
from dice_env.model.rotations import random_rotations

CASES = 300  # cases per test (each a short run: about 10 s in all)
GROUND = {
    "stiffness": [1e-3, 10.0, 1e3, 1e5, 1e8, 1e12, 1e30, 0.0, -1.0, np.nan, np.inf, "1e5"],
    "damping": [0.0, 0.1, 6.0, 1e3, 1e15, -1.0, np.nan],
    "friction": [0.0, 0.4, 2.0, 1e6, -0.1, np.inf],
    "normal": [(0, 0, 1), (0.3, 0, 1), (0, 0, -1), (0, 0, 0), (1, 2), (np.nan, 0, 1)],
    "contact_law": ["gated", "paper", 0, 1, 7, "sticky", None],
}
DIE = {
    "edge": [1e-4, 0.016, 1.0, 0.0, -1.0, np.inf],
    "mass": [1e-9, 1e-3, 0.0045, 10.0, 1e30, 0.0, np.nan],
}
SCENE = {
    "gravity": [0.0, 9.81, 1e3, 1e6, -9.81, np.nan],
    "safety": [1e-9, 0.05, 0.15, 0.9, 1.0, 1.5, 0.0],
    "t_max": [1e-4, 0.05, 0.3, 1e30, 0.0, -1.0],
    "dt": [None, None, 1e-6, 1e-3, 0.0, -1e-5],
    "rotation": [True, False, "no", 1],
    "friction_law": ["stick_slip", "regularized", 1, "coulomb"],
    "scheme": ["midpoint", "paper", 2],
    "energy_tol": [0.1, 1e-9, 0.0],
    "sink_limit": [0.25, 1e-6, 0.0],
    "allow_unstable": [False, True, "yes"],
}
NAMES = set(GROUND) | set(DIE) | set(SCENE) | {
    "step", "t_max / step", "critical step", "State.", "position", "orientation",
    "num_threads", "state", "sink limit", "t_max", "State",
}


def pick(rng, table):
    return {k: v[rng.integers(len(v))] for k, v in table.items() if rng.random() < 0.15}


def named(error):
    return any(name in str(error) for name in NAMES)


def check(result, scene):
    final = np.concatenate([result.final.position, result.final.velocity,
                            result.final.angular_momentum], axis=1)
    finite = np.isfinite(final).all(axis=1)
    assert (finite | result.unstable).all(), "a non-finite state not flagged unstable"
    assert np.isin(result.face, scene.die.labels).all()
    deep = result.max_penetration > scene.sink_limit * scene.die.size
    assert (result.sunk == deep).all()
    assert np.isfinite(result.rest_time).all() and (result.steps >= 0).all()


def fuzz(seed, case):
    """Run ``case(rng) -> (result, scene)`` CASES times: a result or a named refusal."""
    rng = np.random.default_rng(seed)
    outcomes = {"ran": 0, "refused": 0}
    for _ in range(CASES):
        try:
            result, scene = case(rng)
        except (ValueError, TypeError) as error:
            assert named(error), f"unnamed refusal: {error}"
            outcomes["refused"] += 1
            continue
        check(result, scene)
        outcomes["ran"] += 1
    assert outcomes["ran"] > 10 and outcomes["refused"] > 10, outcomes


def random_scene_throw(rng):
    kwargs = pick(rng, DIE), pick(rng, GROUND), pick(rng, SCENE)
    scene = Scene(die=Die(**kwargs[0]), ground=Ground(**kwargs[1]), **kwargs[2])
    n = int(rng.integers(1, 5))
    state = State.release(scene, [0, 0, 0.05 * rng.uniform(1, 100)], rng.normal(0, 2, (n, 3)),
                          rng.normal(0, 50, (n, 3)), random_rotations(rng, n))
    return simulate(scene, state, t_max=min(scene.t_max, 0.05),
                    until="decided" if rng.random() < 0.5 else "rest"), scene


def test_random_scenes_end_in_a_result_or_a_named_error():
    fuzz(2026, random_scene_throw)


def random_state(rng):
    n = int(rng.integers(0, 4))
    sizes = [n if rng.random() < 0.8 else int(rng.integers(0, 4)) for _ in range(5)]
    arrays = [rng.normal(0, 1, (s, 3)) for s in sizes[:3]]
    q = random_rotations(rng, sizes[3]) if rng.random() < 0.8 else rng.normal(0, 1,
                                                                               (sizes[3], 3, 3))
    arrays.insert(3, q)
    arrays.append(rng.normal(0, 1, (sizes[4], 3)))
    arrays[0][:, 2] = np.abs(arrays[0][:, 2]) * 0.05  # centres from 0 to about 0.1 m up
    if rng.random() < 0.1 and arrays[1].size:
        arrays[1][0, 0] = np.nan
    if rng.random() < 0.2:
        k = int(rng.integers(5))
        arrays[k] = np.nan_to_num(arrays[k]).astype(int)
    if rng.random() < 0.1:
        arrays[2] = arrays[2][..., :2]
    return arrays


def random_state_throw(rng):
    scene = Scene()
    state = State(*random_state(rng))
    return simulate(scene, state, t_max=0.05, num_threads=int(rng.integers(1, 3))), scene


def test_random_states_end_in_a_result_or_a_named_error():
    fuzz(7, random_state_throw)

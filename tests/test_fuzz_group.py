"""Several dice fuzzed: a result or a named refusal, nothing else (as tests/test_fuzz.py).

Random dice sets, walls, states, die-die materials and flags go through
:func:`dice_env.simulation.group.simulate_group`, and random keywords, reset options and actions
through the several-dice env. Each case ends in a result whose promises hold (finite unless flagged
unstable, faces read or 0 where not read, ``sunk`` exactly as the limit says, no pair left
overlapping unflagged) or in a ``ValueError``/``TypeError`` naming what was wrong; never in
another error, a hang or a non-finite output. Every run is capped at :data:`STEPS` steps, so
the whole file takes seconds. ``DICE_ENV_FUZZ_SEED`` shifts the seeds (try another draw).
"""

import os
import warnings

import gymnasium as gym
import numba
import numpy as np
import pytest

import dice_env  # noqa: F401  (registers DiceThrow-v0)
from dice_env import Die, Ground, Scene, State, Wall
from dice_env.envs.hand import face_up_rotation
from dice_env.model.rotations import random_rotations
from dice_env.model.scene import MAX_STEPS, Rest
from dice_env.model.surroundings import craps, tray
from dice_env.simulation.group import (
    MAX_DICE,
    DieContact,
    GroupResult,
    GroupState,
    group_step,
    overlaps,
)
from dice_env.simulation.group import simulate_group as run_group

CASES = 300  # cases per test, each capped at STEPS steps (about 15 s in all, warm)
ENV_CASES = 150
STEPS = 20_000  # at most this many steps per run (0.13 s of two default dice)
SHIFT = int(os.environ.get("DICE_ENV_FUZZ_SEED", "0"))
THREADS = numba.config.NUMBA_NUM_THREADS
SHAPES = ("d4", "d6", "d8", "d10", "d12", "d20")

# Each keyword: (valid values, bad values). A case corrupts at most one area (PARTS).
GROUND = {
    "stiffness": ([1e3, 1e5, 1e8], [0.0, -1.0, np.nan, "1e5"]),
    "damping": ([0.0, 1.0, 1e3], [-1.0, np.nan]),
    "friction": ([0.0, 0.4, 2.0], [-0.1, np.inf]),
    "normal": ([(0, 0, 1), (0.3, 0, 1)], [(0, 0, -1), (0, 0, 0), (1, 2)]),
    "contact_law": (["gated", "paper", 0, 1], [7, None]),
}
SCENE = {
    "gravity": ([0.0, 9.81, 1e3, 1e300], [-9.81, np.nan]),
    "safety": ([0.05, 0.15, 0.9, 1.0], [1.5, 0.0]),
    "dt": ([None, 1e-7, 1e-6], [1e-3, 0.0]),
    "rotation": ([True, False], ["no"]),
    "friction_law": (["stick_slip", "regularized", 0, 1], ["coulomb", 2]),
    "scheme": (["midpoint", "paper", 0, 1], [2, "euler"]),
    "energy_tol": ([0.1, 1e-9], [0.0]),
    "sink_limit": ([0.25, 1e-6, 2.0], [0.0]),
    "allow_unstable": ([False, True], ["yes"]),
    "rest": ([Rest(), Rest(speed=1.0, hold=0.0), Rest(speed=1e-9, hold=1e-3), Rest(hold=1e20)],
             ["rest"]),
}
CONTACT = {
    "stiffness": ([1e5, 1e3, 1e-3, 1e8, 1e30], [0.0, -1.0, np.nan, "1e5"]),
    "damping": ([0.0, 1e-3, 1.0, 1e3, 1e300], [-1.0, np.nan]),
    "friction": ([0.0, 0.4, 2.0, 1e6], [-0.1, np.inf]),
    "friction_law": (["stick_slip", "regularized", 0, 1], [2, None, "glue"]),
    "tangential": ([2 / 7, 1.0, 1e-9], [0.0, 1.5, np.nan]),
    "islands": ([False, True], [1, "yes"]),
}
RUN = {
    "t_max": ([1e-9, 1e-4, 0.01, 0.05, 0.3, None], [0.0, -1.0, np.nan, np.inf, "0.1"]),
    "until": (["rest", "decided", "decided", "t_max"], ["early_rest", "no", None, 1]),
    "free_flight": ([True, False], [0]),
    "record_every": ([0, 1, 7, 1000, 10**30, np.int64(5)], [-1, 1.5, True]),
    "orientations": ([True, False], ["yes"]),
    "num_threads": ([None, 1, THREADS], [0, THREADS + 1, "2", 1.0, True]),
}
PARTS = ("dice", "ground", "scene", "walls", "state", "contact", "run")
ENV = {  # gym.make keywords
    "num_dice": ([None, 1, 2, 2, 3, 5], [0, 13, 2.0, "2", True]),
    "die": ([None, "d6", "d20", ("d6", "d20"), ("d4", "d8", "d12"), [Die(), "d10"]],
            [("d6", 3), (), "d7", 3, (Die.loaded(), "d6") * 7]),
    "walls": ([None, "none", "tray", "craps", (Wall.through((0.3, 0, 0), (-1, 0, 0)),)],
              ["wall", 3, ["tray"], (Wall.through((0.01, 0, 0), (-1, 0, 0)),)]),
    "target": ([None, "sum", "faces"], ["max", 1]),
    "target_sum": ([None], [1, 7.0, "7", 10**6]),
    "target_face": ([None], [0, 3.0, (1,), "12"]),
    "set_dice": ([False, True], [1, "yes"]),
    "until": (["decided", "decided", "rest"], ["never", None]),
    "t_max": ([0.02, 0.05, 0.1, 0.3], [0.0, -1.0, np.nan, "0.1"]),
    "release_height": ([None, 0.05], [0.001, -1.0]),
    "max_speed": ([1.0, 3.0], [0.0, np.inf]),
    "max_spin": ([40.0, 200.0], [-1.0]),
    "hand_noise": ([0.0, 0.05, 1.0], [-0.1, np.nan]),
    "orientation_noise": ([0.0, 0.05, 3.0], [-1.0]),
    "min_speed": ([0.0, 0.5], [-1.0]),
    "shaping": ([0.0, 0.5], [-1.0]),
    "num_threads": ([None, 1, THREADS], [0, "1"]),
    "orientation_mode": (["uniform", "flat", "identity"], ["x", None]),
    "size": ([None, 0.01, 0.03], [0.0, -1.0]),
    "mass": ([None, 0.002, 0.02], [0.0, 1e-9]),
    "stiffness": ([None, 1e4, 1e6], [0.0, "1e5"]),
    "friction": ([None, 0.0, 1.0], [-1.0]),
    "gravity": ([None, 9.81, 20.0], [-1.0, 0.0]),
    "render_mode": ([None], ["rgb", "human_"]),  # a non-str: gymnasium's make fails on it
    "foo": ([], [1]),
}
NAMES = set(GROUND) | set(SCENE) | set(CONTACT) | set(RUN) | {
    "dice", "die", "scene", "state", "states", "contact", "State.", "GroupState", "position",
    "velocity", "angular_velocity", "orientation", "batch size", "step", "normal", "point",
    "walls", "edge", "size", "sides", "mass", "face", "fraction", "depth", "vertices",
    "labels", "length", "width", "distance", "t_max / step", "name",
} | set(ENV) | {"action", "options", "unknown keyword", "target_face", "target_sum"}


def named(error):
    return any(name in str(error) for name in NAMES)


def choice(rng, values):
    return values[rng.integers(len(values))]


def pick(rng, table, bad=False, p=0.2):
    """Keywords of ``table``, each given with probability ``p``; with ``bad`` one is bad."""
    kwargs = {k: choice(rng, good) for k, (good, _) in table.items()
              if good and rng.random() < p}
    if bad:
        key = choice(rng, list(table))
        kwargs[key] = choice(rng, table[key][1])
    return kwargs


# --- the draws -------------------------------------------------------------------------------

def random_die(rng, bad=False):
    """A die of a random shape, size, mass or load; a bad one is refused when built."""
    kind = int(rng.integers(8))
    if kind < 3:
        size = choice(rng, [0.0, -1.0, np.nan] if bad else [None, None, 0.006, 0.012, 0.03])
        return Die.standard(choice(rng, SHAPES), size=size,
                            mass=choice(rng, [None, None, None, 1e-3, 2e-2]))
    if kind == 3:
        return Die.standard(choice(rng, SHAPES) if not bad else "d7")
    if kind == 4:
        sides = rng.uniform(0.006, 0.03, 3) if not bad else choice(
            rng, [(0.01, 0.0, 0.02), (0.01, 0.02), (np.nan, 0.01, 0.01)])
        return Die.cuboid(tuple(sides), mass=choice(rng, [None, 1e-3, 1e-2]))
    if kind == 5:
        return Die.loaded(int(rng.integers(1, 7)) if not bad else 7,
                          choice(rng, [0.1, 0.3, 0.5]), choice(rng, [0.8, 0.3]))
    if kind == 6:
        return Die(edge=choice(rng, [0.016, 0.008, 0.025]) if not bad else 0.0,
                   mass=choice(rng, [0.0045, 0.002, 0.01]))
    points = rng.normal(0, 1, (int(rng.integers(5, 13)), 3))  # a random hull, corners on a
    points *= 0.01 / np.linalg.norm(points, axis=1, keepdims=True)  # sphere of 1 cm
    return Die.from_vertices(points if not bad else points[:3])


def random_dice(rng, bad=False):
    """1 to 5 dice as a tuple (or list); bad: a bad die, a non-Die, none, a generator, ..."""
    n = int(rng.integers(1, 6))
    dice = tuple(random_die(rng, bad and i == 0 and rng.random() < 0.3) for i in range(n))
    if not bad:
        return list(dice) if rng.random() < 0.2 else dice
    return choice(rng, [dice, (), (*dice, 3), (*dice, "d6"), dice[0], (Die(),) * (MAX_DICE + 1),
                        "d6d6", None, np.array(dice, dtype=object), (d for d in dice)])


def random_walls(rng, dice, bad=False):
    """No walls, a preset, walls cutting close by the dice (even through them), or bad ones."""
    if bad:
        kind = int(rng.integers(6))
        if kind == 0:
            return tray(**pick(rng, {"stiffness": ([1e4], [-1.0])}, True))
        if kind == 1:
            return craps(choice(rng, [0.0, -1.0, np.nan]))
        if kind == 2:
            return Wall.through((0, 0, 0), choice(rng, [(0, 0, 0), (1, 0), (np.inf, 0, 0)]))
        if kind == 3:
            return (Wall.through((np.nan, 0, 0), (1, 0, 0)),)
        return choice(rng, ["tray", (1, 2), [Wall(), "wall"]])
    kind = int(rng.integers(5))
    if kind == 0:
        return ()
    if kind == 1:
        return tray(**pick(rng, {"stiffness": ([1e4, 1e6], [])}, p=0.3))
    if kind == 2:
        return craps(choice(rng, [1.0, 0.05]), choice(rng, [0.6, 0.08]))
    far = max(d.reach for d in dice)
    walls = []
    for _ in range(int(rng.integers(1, 4))):
        direction = rng.normal(0, 1, 3)
        direction /= np.linalg.norm(direction)
        point = np.array([0.0, 0.0, 2 * far]) + rng.uniform(2, 10) * far * direction
        walls.append(Wall.through(point, -direction + rng.normal(0, 0.2, 3),
                                  **pick(rng, {"friction": ([0.0, 1.0], []),
                                               "stiffness": ([1e4, 1e7], [])}, p=0.3)))
    return walls if rng.random() < 0.2 else tuple(walls)


def random_scene(rng, dice, bad):
    walls = random_walls(rng, dice, bad == "walls")
    ground = Ground(**pick(rng, GROUND, bad == "ground", p=0.1))
    kwargs = pick(rng, SCENE, bad == "scene", p=0.1)
    if kwargs.get("dt") is not None and rng.random() < 0.7:
        kwargs["allow_unstable"] = True  # a fixed step above the dice's critical one runs
    return Scene(ground=ground, walls=walls, t_max=choice(rng, [0.05, 0.3, 0.3]), **kwargs)


def random_state(rng, scene, dice, bad=False):
    """B throws of the dice near each other: apart, touching or inside each other or a plane.

    In the air, on the floor (a corner pressed in a little, or just above) or lying flat on a
    face; mostly released (:meth:`State.release`), sometimes built raw (a corner may start
    deep in a plane); velocities toward the cluster's middle, spins up to huge; bad: NaN, inf,
    no rotations, batches that disagree, a State or a list where the GroupState belongs.
    """
    n, b = len(dice), int(rng.integers(1, 4))
    far = max(d.reach for d in dice)
    pitch = 2 * far * choice(rng, [0.6, 1.02, 1.2, 1.5, 2.5])  # < 1: some start inside
    jitter = far * choice(rng, [0.0, 0.1, 0.5])
    where = choice(rng, ["air", "air", "floor", "flat"])
    speed = choice(rng, [0.0, 0.3, 1.0, 1.0, 3.0, 30.0, 1e30])
    spin = choice(rng, [0.0, 0.0, 20.0, 200.0, 1e4, 1e30])
    if where != "air" and rng.random() < 0.7:  # mostly still: they settle, or are decided
        speed, spin = choice(rng, [0.0, 0.01, 0.1]), choice(rng, [0.0, 1.0, 10.0])
    how = choice(rng, ["speed", "spin", "rotation", "rows", "single", "list"]) if bad else ""
    if how == "speed":
        speed = np.nan
    elif how == "spin":
        spin = choice(rng, [np.inf, 1e300])
    grid = pitch * np.array([[i % 3 - 1, i // 3, 0.0] for i in range(n)])
    middle = grid.mean(axis=0)  # where the dice are thrown at
    states = []
    for i, die in enumerate(dice):
        rows = int(rng.integers(1, 4)) if how == "rows" else b
        offset = rng.normal(0, jitter, (rows, 3)) + grid[i]
        inward = middle - offset
        velocity = speed * (rng.normal(0, 0.3, (rows, 3)) + inward / (np.linalg.norm(
            inward, axis=1, keepdims=True) + 1e-12))
        velocity[:, 2] -= speed * rng.random()
        omega = rng.normal(0, 1, (rows, 3)) * spin
        rotation = random_rotations(rng, rows)
        if where == "flat":
            rotation = np.stack([face_up_rotation(die, int(rng.integers(1, die.n_faces + 1)))
                                 for _ in range(rows)])
        position = offset.copy()
        position[:, 2] = die.reach * rng.uniform(0.95, 3.0, rows)
        if where != "air":  # the lowest corner from 1e-3 size inside the floor to just above
            normal = np.asarray(scene.ground.normal)
            corners = position[:, None] + np.einsum("bij,kj->bki", rotation, die.vertices_body)
            gap = die.size * rng.uniform(-1e-3, 1e-3, rows) - (corners @ normal).min(axis=1)
            position += gap[:, None] * normal
        if how == "rotation" and i == n - 1:
            rotation = choice(rng, [1.1 * np.eye(3), np.zeros((rows, 2, 2)), -np.eye(3)])
        if rng.random() < 0.8 or rotation.shape[-2:] != (3, 3):
            states.append(State.release(scene.with_(die=die), position, velocity, omega,
                                        rotation))
        else:
            rotation = np.broadcast_to(rotation, (rows, 3, 3))
            position[:, 2] -= rng.exponential(0.1 * die.size, rows)  # maybe deep inside
            with np.errstate(all="ignore"):
                momentum = np.einsum("bij,jk,blk,bl->bi", rotation, die.inertia_body,
                                     rotation, omega)
            states.append(State(position, velocity, momentum, rotation, omega))
    if how == "single":
        return states[0]
    return states if how == "list" else GroupState.of(states)


def random_contact(rng, bad=False):
    if bad and rng.random() < 0.1:
        return "contact"
    return DieContact(**pick(rng, CONTACT, bad, p=0.15))


def capped(scene, dice, contact, t_max):
    """``t_max`` cut to at most :data:`STEPS` steps where the dice's step is known."""
    if not isinstance(t_max, float) or not np.isfinite(t_max) or t_max <= 0:
        return t_max
    try:
        step = group_step(scene, dice, contact)
    except (ValueError, TypeError):
        return t_max  # the run itself must refuse it, named
    if not step > 0 or t_max / step > MAX_STEPS:
        return t_max
    return min(t_max, STEPS * step)


def group_throw(rng):
    """One random throw through simulate_group: (result, case) or a refusal."""
    bad = choice(rng, PARTS) if rng.random() < 0.4 else ""
    dice = random_dice(rng, bad == "dice")
    good = _all_dice(dice)
    scene = random_scene(rng, dice if good else (Die(),), bad)
    state = random_state(rng, scene, dice if good else (Die(),) * 2, bad == "state")
    contact = random_contact(rng, bad == "contact")
    run = pick(rng, RUN, bad == "run", p=0.3)
    t_max = run.get("t_max")
    if good and isinstance(contact, DieContact):
        run["t_max"] = capped(scene, dice, contact, scene.t_max if t_max is None else t_max)
    before = [np.array(a) for a in state._arrays()] if isinstance(state, GroupState) else None
    result = run_group(scene, dice, state, contact=contact, **run)
    if before is not None:  # the state given is not modified
        for a, b in zip(before, state._arrays(), strict=True):
            np.testing.assert_array_equal(a, b)
    return result, (scene, tuple(dice), state, contact, run)


def _all_dice(dice):
    return isinstance(dice, (tuple, list)) and 1 <= len(dice) <= MAX_DICE and all(
        isinstance(d, Die) for d in dice)


# --- the promises ----------------------------------------------------------------------------

def check(result, case):
    """What a GroupResult promises, for the throw ``case`` = (scene, dice, state, contact, run)."""
    scene, dice, state, contact, run = case
    assert isinstance(result, GroupResult)
    b, n = state.batch_size, len(dice)
    assert result.face.shape == result.read.shape == result.sunk.shape == (b, n)
    assert result.touched.shape == (b, n, len(scene.planes))
    final = result.final
    assert isinstance(final, GroupState) and final.position.shape == (b, n, 3)
    values = np.concatenate([final.position, final.velocity, final.angular_momentum,
                             final.angular_velocity, final.orientation.reshape(b, n, 9)],
                            axis=2)
    finite = np.isfinite(values).all(axis=(1, 2))
    assert (finite | result.unstable).all(), "a non-finite state not flagged unstable"
    for i, die in enumerate(dice):  # the label read, 0 exactly where not read
        face, read = result.face[:, i], result.read[:, i]
        assert np.isin(face[read], die.labels).all(), (die, face, read)
        assert (face[~read] == 0).all()
    limit = scene.sink_limit * min(d.size for d in dice)
    deep = (result.max_penetration > limit) | (result.overlap[:, None] > limit)
    np.testing.assert_array_equal(result.sunk, deep)
    assert (result.max_penetration >= 0).all() and (result.overlap >= 0).all()
    assert not np.isnan(result.energy_rise).any(), "energy_rise NaN"
    assert not (result.settled & result.decided).any()
    if run.get("until", "rest") != "decided":
        assert not result.decided.any()
    if run.get("until") == "t_max":
        assert not result.settled.any()
    dt = group_step(scene, dice, contact)
    t_max = scene.t_max if run.get("t_max") is None else run["t_max"]
    n_steps = max(1, round(t_max / dt))
    assert ((result.steps >= 0) & (result.steps <= n_steps)).all()
    assert np.isfinite(result.rest_time).all() and (result.rest_time >= 0).all()
    assert (result.rest_time <= n_steps * dt * (1 + 1e-9)).all()
    assert (result.impacts >= 0).all() and (result.die_impacts >= 0).all()
    met = result.meet_dice
    assert ((met == -1).all(axis=1) | ((0 <= met[:, 0]) & (met[:, 0] < met[:, 1])
                                       & (met[:, 1] < n))).all()
    with np.errstate(all="ignore"):  # a flagged throw may end anywhere
        depth = overlaps(dice, final) if n > 1 else np.full((b, 1, 1), -np.inf)
    flagged = result.unstable | result.sunk.any(axis=1)
    still = (depth > limit).any(axis=(1, 2))
    assert (flagged | ~still).all(), "dice left inside each other, not flagged"
    every = run.get("record_every", 0)
    if every:
        assert result.x_cm.shape == (b, n_steps // every, n, 3)
        recorded = np.isfinite(result.x_cm).reshape(b, -1).all(axis=1)
        assert (recorded | result.unstable).all(), "a non-finite record not flagged unstable"


def fuzz(seed, case, cases=CASES, check=check):
    """Run ``case(rng) -> (result, case)`` ``cases`` times: a result or a named refusal."""
    rng = np.random.default_rng(seed + SHIFT)
    outcomes = {"ran": 0, "refused": 0, "met": 0}
    for k in range(cases):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the env checker's and numpy's, on bad input
                result, args = case(rng)
        except (ValueError, TypeError) as error:
            assert named(error), f"case {k}: unnamed refusal: {type(error).__name__}: {error}"
            outcomes["refused"] += 1
            continue
        check(result, args)
        outcomes["ran"] += 1
        if isinstance(result, GroupResult):
            outcomes["met"] += bool((result.meet_dice >= 0).any())
    return outcomes


def test_random_dice_walls_states_and_flags_end_in_a_result_or_a_named_error():
    outcomes = fuzz(2030, group_throw)
    assert outcomes["ran"] > 20 and outcomes["refused"] > 20 and outcomes["met"] > 5, outcomes


def random_group_arrays(rng):
    """GroupState's five arrays, raw: shapes that disagree, NaN, ints, no rotations."""
    b, n = int(rng.integers(0, 3)), int(rng.integers(1, 4))
    shapes = [(b, n) if rng.random() < 0.85 else (int(rng.integers(0, 3)),
                                                  int(rng.integers(0, 4))) for _ in range(5)]
    arrays = [rng.normal(0, 1, (*shape, 3)) for shape in shapes]
    arrays[0] = 0.05 * np.array([np.arange(shapes[0][1]) - 1, np.zeros(shapes[0][1]),
                                 np.ones(shapes[0][1])]).T * np.ones((*shapes[0], 1))
    arrays[0] += rng.normal(0, 0.005, arrays[0].shape)
    rotations = random_rotations(rng, int(np.prod(shapes[3]))).reshape(*shapes[3], 3, 3)
    arrays[3] = rotations if rng.random() < 0.85 else rng.normal(0, 1, (*shapes[3], 3, 3))
    if rng.random() < 0.1 and arrays[1].size:
        arrays[1].flat[0] = np.nan
    if rng.random() < 0.15:
        k = int(rng.integers(5))
        arrays[k] = np.nan_to_num(arrays[k]).astype(int)
    if rng.random() < 0.1:
        arrays[2] = arrays[2][..., :2]
    if rng.random() < 0.05:
        arrays[4] = arrays[4].tolist()
    return arrays, n if rng.random() < 0.9 else int(rng.integers(1, 4))


def raw_group_throw(rng):
    arrays, n = random_group_arrays(rng)
    state = GroupState(*arrays)
    dice = tuple(Die.standard(choice(rng, SHAPES)) for _ in range(n))
    run = {"t_max": 0.01, "num_threads": int(rng.integers(1, THREADS + 1))}
    return run_group(Scene(), dice, state, **run), (Scene(), dice, state, DieContact(), run)


def test_random_group_states_end_in_a_result_or_a_named_error():
    outcomes = fuzz(11, raw_group_throw)
    assert outcomes["ran"] > 10 and outcomes["refused"] > 10, outcomes


# --- the env ---------------------------------------------------------------------------------

def random_options(rng, task):
    """reset options: None, a fixed target, hands, a mode; one in four bad."""
    n, bad = task.n_dice, rng.random() < 0.25
    kind = int(rng.integers(5))
    if kind in (1, 2):  # the target the task takes (bad: the other)
        kind = 1 if (task.target == "sum") != bad else 2
    if kind == 0:
        return choice(rng, [{"foo": 1}, "options", [("target_sum", 7)]]) if bad else choice(
            rng, [None, {}])
    if kind == 1:
        return {"target_sum": choice(rng, [0, 7.5, "7"] if bad else [n, 2 * n, 3 * n])}
    if kind == 2:
        faces = [int(rng.integers(1, 5)) for _ in range(n)]
        wrong = [[9] * n, [*faces, 1], "1"]
        return {"target_face": choice(rng, wrong) if bad else faces[0] if n == 1 else faces}
    if kind == 3:
        hands = random_rotations(rng, n)
        hands = hands[0] if n == 1 else hands
        return {"orientation": choice(rng, [1.01 * hands, np.full_like(hands, np.nan),
                                            "hands", hands[..., :2]]) if bad else hands}
    return {"orientation_mode": choice(rng, ["x", 1] if bad else ["uniform", "flat",
                                                                  "identity"])}


def random_action(rng, dim):
    action = rng.uniform(-1.5, 1.5, dim)
    if rng.random() < 0.8:
        return action if rng.random() < 0.9 else action.tolist()
    return choice(rng, [np.append(action, 0.0), action[None], np.full(dim, np.nan),
                        "action", None, np.full(dim, 1e308), np.ones(dim, int), {}])


def env_throw(rng):
    """gym.make with random keywords, reset with random options, one or two random steps."""
    bad = rng.random() < 0.4
    kwargs = pick(rng, ENV, bad, p=0.25)
    if not isinstance(kwargs.get("die"), (tuple, list)):
        kwargs.setdefault("num_dice", choice(rng, [1, 2, 2, 3, 4]))
    kwargs.setdefault("until", "decided")
    kwargs.setdefault("t_max", choice(rng, [0.02, 0.05, 0.1]))
    env = gym.make("DiceThrow-v0", **kwargs)
    try:
        task = env.unwrapped.task
        steps = []
        obs, _ = env.reset(seed=int(rng.integers(2**31)), options=random_options(rng, task))
        assert env.observation_space.contains(obs), obs
        for _ in range(int(rng.integers(1, 3))):
            steps.append(env.step(random_action(rng, task.action_dim)))
        return steps, (env.observation_space, task)
    finally:
        env.close()


def check_env(steps, case):
    space, task = case
    for obs, reward, terminated, truncated, info in steps:
        assert obs.dtype == np.float32 and np.isfinite(obs).all() and space.contains(obs), obs
        assert isinstance(reward, float) and np.isfinite(reward)
        assert terminated is True and truncated is False
        assert info["void_reason"] in ("", "foul", "unstable", "sunk", "not_settled",
                                       "not_decided", "leaning")
        assert not info["is_success"] or info["void_reason"] == ""
        faces = np.atleast_1d(info["face"])
        assert faces.shape == (task.n_dice,)
        for face, die in zip(faces, task.dice, strict=True):
            assert face == 0 or face in die.labels
        if task.n_dice > 1:
            np.testing.assert_array_equal(faces == 0, info["leaning"])
            assert info["total"] == faces.sum()


def test_the_env_with_random_keywords_options_and_actions_steps_or_refuses_named():
    outcomes = fuzz(2031, env_throw, ENV_CASES, check_env)
    assert outcomes["ran"] > 10 and outcomes["refused"] > 10, outcomes


# --- regressions: what the fuzz found ------------------------------------------------------

def two_dice(spin=(0.0, 0.0, 0.0)):
    scene = Scene(t_max=0.01)
    return scene, (Die(), Die()), GroupState.of([
        State.release(scene, [x, 0.0, 0.05], [0.0, 0.0, 0.0], spin) for x in (-0.02, 0.02)])


def test_a_contact_damping_whose_step_underflows_is_refused_named():
    scene, dice, state = two_dice()
    contact = DieContact(damping=1e300)  # the pair's critical step comes out as 0 s
    for call in (lambda: group_step(scene, dice, contact),
                 lambda: run_group(scene, dice, state, contact=contact)):
        with pytest.raises(ValueError, match="step of die against die comes out as 0 s"):
            call()  # was ZeroDivisionError (t_max / step)


@pytest.mark.parametrize("every", [10**30, 2**63])
def test_a_record_stride_beyond_the_run_records_nothing(every):
    scene, dice, state = two_dice()
    result = run_group(scene, dice, state, record_every=every, orientations=True)
    assert result.x_cm.shape == (1, 0, 2, 3) and result.t.shape == (0,)  # was OverflowError
    plain = run_group(scene, dice, state)
    np.testing.assert_array_equal(result.final.position, plain.final.position)


def test_an_orientation_that_overflows_in_the_last_step_is_flagged_unstable():
    scene, dice, state = two_dice(spin=(1e300, 1.5e300, -1e300))
    result = run_group(scene, dice, state, t_max=1e-9)  # one step: the rotation overflows
    assert not np.isfinite(result.final.orientation).all()
    assert result.unstable.all()  # was False: the kernel checks x, u and L only


def test_a_rest_hold_beyond_the_run_never_settles_and_fits_the_kernel():
    scene, dice, state = two_dice()
    for hold in (1e20, 1e300):  # was a numba TypingError: the hold's steps beyond int64
        result = run_group(scene.with_(rest=Rest(hold=hold)), dice, state)
        assert not result.settled.any() and (result.steps == result.steps[0]).all()


def test_a_gravity_that_overflows_the_decision_rule_is_refused_named():
    scene, dice, state = two_dice()
    heavy = scene.with_(gravity=1e300)
    assert run_group(heavy, dice, state).final.position.shape == (1, 2, 3)  # was OverflowError
    with pytest.raises(ValueError, match="gravity=1e"):
        run_group(heavy, dice, state, until="decided")

"""Stopping when the face is decided: the energy lock gives the face the die comes to rest on."""

import math

import numpy as np
import pytest

from dice_env import Die, FrictionLaw, Ground, Scene, Scheme, State, simulate
from dice_env.model.rotations import random_rotations
from dice_env.simulation.simulate import LOCK_MARGIN, lock_energy


def throws(scene: Scene, n: int, seed: int, height=(0.05, 0.15), speed=(0.5, 1.0),
           spin=(0.0, 30.0)) -> State:
    """Hand throws: uniform directions of velocity and spin, uniform orientation."""
    rng = np.random.default_rng(seed)

    def directions() -> np.ndarray:
        v = rng.normal(size=(n, 3))
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    position = np.column_stack([np.zeros((n, 2)), rng.uniform(*height, n)])
    return State.release(scene, position, directions() * rng.uniform(*speed, (n, 1)),
                         directions() * rng.uniform(*spin, (n, 1)), random_rotations(rng, n))


CASES = {
    "default": (Scene(), {}),
    "vigorous": (Scene(), {"speed": (1.0, 2.0), "spin": (20.0, 60.0)}),
    "gentle": (Scene(), {"height": (0.014, 0.025), "speed": (0.0, 0.3), "spin": (0.0, 5.0)}),
    "loaded": (Scene(die=Die.loaded(face=6, fraction=0.3)), {}),
    "listing friction and step": (
        Scene(friction_law=FrictionLaw.REGULARIZED, scheme=Scheme.PAPER), {}),
    "coarse step": (Scene(safety=0.9), {}),
}


def decided_against_rest(name: str, n: int, seed: int) -> tuple[np.ndarray, object, object]:
    scene, kwargs = CASES[name]
    start = throws(scene, n, seed, **kwargs)
    rest = simulate(scene, start, until="early_rest")
    decided = simulate(scene, start, until="decided")
    return rest.face == decided.face, rest, decided


@pytest.mark.parametrize("name", CASES)
def test_decided_face_is_the_face_at_rest(name):
    agree, rest, decided = decided_against_rest(name, 48, seed=3)
    assert rest.settled.mean() > 0.9
    assert decided.decided[rest.settled].all()
    assert not decided.settled.any()
    assert agree[rest.settled].all()
    # it ends before the rest begins, never after
    assert (decided.rest_time <= rest.rest_time + 1e-12)[rest.settled].all()
    assert (decided.steps < rest.steps).all()


def test_margin_zero_is_the_tie_energy_and_the_fair_die_tips_over_an_edge():
    scene = Scene()
    die, weight = scene.die, scene.die.mass * scene.gravity
    np.testing.assert_allclose(die.tipping_heights, math.sqrt(2) * die.size / 2, rtol=1e-3)
    assert (die.tipping_heights <= math.sqrt(2) * die.size / 2).all()
    np.testing.assert_allclose(die.resting_heights, die.size / 2)
    tie = weight * math.sqrt(2) * die.size / 2 - weight**2 / (2 * scene.ground.stiffness)
    np.testing.assert_allclose(lock_energy(scene, margin=0.0), tie, rtol=1e-3)
    np.testing.assert_allclose(lock_energy(scene, margin=1.0), weight * die.size / 2
                               - weight**2 / (2 * scene.ground.stiffness))


def test_a_die_balanced_on_an_edge_is_not_decided_and_one_lying_flat_is():
    scene = Scene()
    h = scene.die.size / 2
    on_edge = State.release(scene, [0, 0, math.sqrt(2) * h], [0, 0, 0],
                            orientation=_about_x(math.pi / 4))
    flat = State.release(scene, [0, 0, h + 1e-4], [0.05, 0, 0])
    res = simulate(scene, on_edge, t_max=1e-3, until="decided")
    assert not res.decided[0]
    res = simulate(scene, flat, until="decided")
    assert res.decided[0] and res.steps[0] == 0 and res.face[0] == 1


def test_a_loaded_die_holds_its_heavy_face_down_harder():
    loaded = Die.loaded(face=6, fraction=0.3)  # the mass moves toward face 6: 1 up lies low
    rest, tip = loaded.resting_heights, loaded.tipping_heights
    assert rest[0] < Die().size / 2 < rest[5]
    # the barrier out of "6 down, 1 up" is higher than out of "1 down, 6 up"
    assert tip[5] - rest[5] < tip[0] - rest[0]


@pytest.mark.parametrize("scene", [
    Scene(ground=Ground.tilted(10.0)), Scene(gravity=0.0), Scene(rotation=False),
], ids=["tilted", "no gravity", "no rotation"])
def test_no_lock_where_energy_does_not_bound_the_face(scene):
    assert (lock_energy(scene) == -math.inf).all()
    start = throws(scene, 2, seed=0)
    assert not simulate(scene, start, t_max=0.5, until="decided").decided.any()


def test_lock_margin_is_checked():
    with pytest.raises(ValueError, match="margin must be in"):
        lock_energy(Scene(), margin=1.5)


@pytest.mark.slow
@pytest.mark.parametrize("name", CASES)
def test_decided_face_is_the_face_at_rest_in_thousands_of_throws(name):
    agree, rest, decided = decided_against_rest(name, 3000, seed=7)
    # how far the energy still rises after a decision, against the margin that allows for it:
    # rerun from the decided states (a restart, so the sticking springs start afresh)
    scene = CASES[name][0]
    start = decided.final
    again = simulate(scene, start, until="early_rest")
    die, weight = scene.die, scene.die.mass * scene.gravity
    kinetic = 0.5 * die.mass * (start.velocity**2).sum(1) + 0.5 * (
        start.angular_momentum * start.angular_velocity).sum(1)
    scale = weight * die.size + kinetic + weight * np.maximum(0.0, start.position[:, 2])
    rise = again.energy_rise * scene.energy_tol * scale
    barrier = weight * (die.tipping_heights - die.resting_heights).min()
    print(f"\n{name}: {agree[rest.settled].mean():.5f} of {rest.settled.sum()} settled throws "
          f"agree; energy rise after the decision at most {rise.max() / barrier:.4f} of the "
          f"barrier (margin {LOCK_MARGIN})")
    assert agree[rest.settled].all()
    assert rise.max() < LOCK_MARGIN * barrier


def _about_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])

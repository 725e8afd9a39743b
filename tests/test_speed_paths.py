"""The fast paths: analytic free flight, skipped parts and records, against plain stepping."""

import numpy as np
import pytest
from listing_transcription import ground_cube as listing_ground
from listing_transcription import real_throw_cube as listing_throw

from dice_env import Die, Scene, State, simulate
from dice_env.model.rotations import random_rotations
from dice_env.model.scene import Scheme
from dice_env.simulation import paper


def throws(scene: Scene, n: int, seed: int = 0) -> State:
    """Realistic throws: 5-15 cm up, about 0.5 m/s, spins up to 30 rad/s, random orientation."""
    rng = np.random.default_rng(seed)
    position = np.column_stack([np.zeros((n, 2)), rng.uniform(0.05, 0.15, n)])
    return State.release(scene, position, rng.normal(0, 0.5, (n, 3)),
                         rng.uniform(-30, 30, (n, 3)), random_rotations(rng, n))


@pytest.mark.parametrize(("die", "scheme", "bound"), [
    (Die(), Scheme.PAPER, 0.05),
    (Die.loaded(face=6, fraction=0.3), Scheme.PAPER, 0.1),
    (Die(), Scheme.MIDPOINT, 1e-4),
], ids=["fair", "loaded", "fair-midpoint"])
def test_free_flight_agrees_with_plain_stepping_within_its_error(die, scheme, bound):
    # through the first two or three impacts on the default table. Jumping changes only
    # round-off, which the chaotic rattling amplifies like any other perturbation (fastest
    # under the listing's sign-like friction): compare it with the step's own error, per throw
    scene = Scene(die=die, t_max=0.3, scheme=scheme)
    start = throws(scene, 6, seed=1)
    kwargs = {"until": "t_max", "record_every": 50, "record": ("orientations",)}
    jumped = simulate(scene, start, **kwargs)
    plain = simulate(scene, start, free_flight=False, **kwargs)
    half = simulate(scene.with_(dt=scene.step / 2), start, free_flight=False,
                    **{**kwargs, "record_every": 100})
    assert (jumped.steps == plain.steps).all()
    for name in ("x_cm", "orientations"):
        a, b, c = (getattr(r, name).reshape(6, -1) for r in (jumped, plain, half))
        gap, stepping_error = np.abs(a - b).max(axis=1), np.abs(c - b).max(axis=1)
        assert (stepping_error > 1e-6).all()
        assert (gap < bound * stepping_error).all()


def test_a_fall_jumped_in_closed_form_lands_where_stepping_does():
    scene = Scene(t_max=0.2)
    start = State.release(scene, [0, 0, 0.3], [0.4, 0.1, 0.0], [5.0, -3.0, 2.0])
    jumped = simulate(scene, start, until="t_max")
    plain = simulate(scene, start, until="t_max", free_flight=False)
    # no contact within 0.2 s: jumped, equal to the 11,817 plain steps up to their round-off
    np.testing.assert_allclose(jumped.final.position, plain.final.position, rtol=0, atol=1e-11)
    np.testing.assert_allclose(jumped.final.velocity, plain.final.velocity, rtol=0, atol=1e-11)
    np.testing.assert_allclose(jumped.final.orientation, plain.final.orientation, atol=1e-12)
    assert jumped.steps[0] == plain.steps[0] == scene.n_steps


def test_recording_does_not_change_the_throw():
    scene = Scene(t_max=1.0)
    start = throws(scene, 4, seed=2)
    bare = simulate(scene, start)
    recorded = simulate(scene, start, record_every=37, record=("energy", "orientations", "nodes"))
    for name in ("position", "velocity", "angular_momentum", "orientation"):
        np.testing.assert_array_equal(getattr(recorded.final, name), getattr(bare.final, name))
    for name in ("face", "settled", "rest_time", "impacts", "steps", "max_penetration"):
        np.testing.assert_array_equal(getattr(recorded, name), getattr(bare, name))
    # records taken inside jumps are the plain steps' states
    plain = simulate(scene, start, record_every=37, record=("orientations",), free_flight=False)
    before = recorded.t < 0.02  # all four still in the air
    np.testing.assert_allclose(recorded.x_cm[:, before], plain.x_cm[:, before], atol=1e-14)
    np.testing.assert_allclose(recorded.orientations[:, before], plain.orientations[:, before],
                               atol=1e-13)


def test_frictionless_undamped_paths_equal_the_listing_with_zero_terms():
    # mu = 0 skips friction, D = 0 skips damping and lets the paper law jump free flights
    ours = paper.ground_cube(D=0.0, mu=0.0, clockmax=4000, tmax=4.0)
    ref = listing_ground(D=0.0, mu=0.0, clockmax=4000, tmax=4.0)
    np.testing.assert_allclose(ours.x_cm, ref["x_cm"], rtol=0, atol=1e-9)
    ours = paper.real_throw_cube((0.3, 0.2, 0.1), D=0.0, mu=0.0, clockmax=20000, tmax=2.0)
    ref = listing_throw((0.3, 0.2, 0.1), D=0.0, mu=0.0, clockmax=20000, tmax=2.0)
    np.testing.assert_allclose(ours.x_cm, ref["x_cm"], rtol=0, atol=1e-9)


def test_serial_and_parallel_paths_are_bit_identical():
    scene = Scene(die=Die.loaded(face=2, fraction=0.2), t_max=0.5)
    start = throws(scene, 5, seed=3)
    two = simulate(scene, start, num_threads=2)
    one = simulate(scene, start, num_threads=1)
    for name in ("position", "velocity", "angular_momentum", "orientation"):
        np.testing.assert_array_equal(getattr(two.final, name), getattr(one.final, name))
    for k in range(start.batch_size):
        single = State(*(a[k:k + 1] for a in start._arrays()))
        np.testing.assert_array_equal(simulate(scene, single).final.position,
                                      two.final.position[k:k + 1])


def test_early_rest_gives_the_rest_that_the_hold_confirms():
    scene = Scene(t_max=3.0)
    start = throws(scene, 24, seed=4)
    early = simulate(scene, start, until="early_rest")
    held = simulate(scene, start)
    assert early.settled.all()
    for name in ("face", "settled", "rest_time", "impacts", "max_penetration", "energy_rise"):
        np.testing.assert_array_equal(getattr(early, name), getattr(held, name))
    hold_steps = np.ceil(scene.rest.hold / scene.step)
    assert (early.steps < held.steps - hold_steps / 2).all()  # most of the hold is skipped
    # where energy can grow or the die's rest energy differs, the hold is waited out
    for other in (scene.with_(die=Die.loaded(face=1, fraction=0.2)),
                  scene.with_(ground=scene.ground.tilted(10.0))):
        start = throws(other, 2, seed=5)
        np.testing.assert_array_equal(simulate(other, start, until="early_rest").steps,
                                      simulate(other, start).steps)

"""The paper scene's vectorised kernel: bit-identical to the scalar kernel, and to the listing."""

import numpy as np
import pytest
from listing_transcription import real_throw_cube as listing_throw

from dice_env import Scene, State, paper, simulate, vector_kernel
from dice_env.simulate import _NEVER

FIELDS = ("face", "settled", "decided", "rest_time", "impacts", "unstable", "energy_rise",
          "max_penetration", "steps")


def paper_throws(n: int, spin: float = 0.75, seed: int = 0) -> State:
    """The paper's throw with the listing's random angular momentum, up to ``spin`` a side."""
    rng = np.random.default_rng(seed)
    return State(position=np.tile([0.0, 0.0, 3.0], (n, 1)), velocity=np.tile([5.0, 0, 5], (n, 1)),
                 angular_momentum=rng.random((n, 3)) * spin + 1e-6,
                 orientation=np.tile(np.eye(3), (n, 1, 1)), angular_velocity=np.zeros((n, 3)))


def scalar(scene: Scene, start: State, monkeypatch, **kwargs):
    with monkeypatch.context() as patch:
        patch.setattr(vector_kernel, "covers", lambda *args: False)
        return simulate(scene, start, **kwargs)


def assert_identical(a, b) -> None:
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for x, y in zip(a.final._arrays(), b.final._arrays(), strict=True):
        np.testing.assert_array_equal(x, y)


def overflowing(n: int) -> State:
    """Paper throws so fast sideways that each die's state overflows at its own step."""
    start = paper_throws(n)
    start.velocity[:, 0] = np.linspace(0.9e308, 1.7e308, n)
    return start


@pytest.mark.parametrize(("scene", "start", "free_flight"), [
    (paper.paper_scene(t_max=1.5), paper_throws(37), True),  # two full tiles and a part
    (paper.paper_scene(t_max=1.5, normal=(0.2, -0.1, 1.0)), paper_throws(37), True),
    (paper.paper_scene(t_max=1.0, mu=0.0), paper_throws(37), True),
    (paper.paper_scene(t_max=1.0, D=0.0), paper_throws(37), False),  # flight: scalar kernel
    (paper.paper_scene(t_max=0.5), paper_throws(37, spin=300.0), True),  # turns > 1/64 rad
    (paper.paper_scene(t_max=1.0), overflowing(37), True),
], ids=["paper", "tilted", "frictionless", "undamped", "fast-spin", "overflow"])
def test_bit_identical_to_the_scalar_kernel(scene, start, free_flight, monkeypatch):
    kwargs = {"stop_at_rest": False, "record": (), "free_flight": free_flight}
    assert vector_kernel.covers(scene, start.batch_size, False, False, False, _NEVER)
    with np.errstate(over="ignore", invalid="ignore"):
        fast = simulate(scene, start, **kwargs)
        assert_identical(fast, scalar(scene, start, monkeypatch, **kwargs))
    if start.velocity[0, 0] > 1e300:
        assert fast.unstable.all() and len(set(fast.steps)) > 30  # each at its own step
        assert (fast.steps < scene.n_steps).all() and np.isfinite(fast.final.position).all()


def test_same_results_for_any_thread_count_and_batch():
    scene = paper.paper_scene(t_max=0.5)
    start = paper_throws(40)
    two = simulate(scene, start, stop_at_rest=False, record=(), num_threads=2)
    one = simulate(scene, start, stop_at_rest=False, record=(), num_threads=1)
    assert_identical(two, one)
    rows = slice(5, 21)  # another tile, other neighbours
    part = simulate(scene, State(*(a[rows] for a in start._arrays())), stop_at_rest=False,
                    record=())
    np.testing.assert_array_equal(part.final.orientation, two.final.orientation[rows])


def test_a_batch_of_paper_throws_ends_where_the_listing_does():
    # the independent transcription of real_throw_cube.m, 3000 steps of its own dt = 1e-4
    start = paper_throws(16, seed=3)
    ours = simulate(paper.paper_scene(t_max=0.3), start, stop_at_rest=False, record=())
    for k in (0, 7, 15):
        ref = listing_throw(start.angular_momentum[k], clockmax=3000, tmax=0.3)
        np.testing.assert_allclose(ours.final.position[k], ref["x_cm"][-1], rtol=0, atol=1e-9)


def test_other_scenes_and_runs_take_the_scalar_kernel():
    paper_scene = paper.paper_scene()
    lock = np.zeros(6)
    assert not vector_kernel.covers(Scene(), 64, False, False, False, _NEVER)
    assert not vector_kernel.covers(paper_scene, vector_kernel.TILE - 1, False, False, False,
                                    _NEVER)
    assert not vector_kernel.covers(paper_scene, 64, True, False, False, _NEVER)
    assert not vector_kernel.covers(paper_scene, 64, False, True, False, _NEVER)
    assert not vector_kernel.covers(paper_scene, 64, False, False, True, _NEVER)
    assert not vector_kernel.covers(paper_scene, 64, False, False, False, lock)
    assert not vector_kernel.covers(paper.paper_scene(rotation=False), 64, False, False, False,
                                    _NEVER)

"""The paper scene's vectorised kernel: bit-identical to the scalar kernel, and to the listing."""

import numpy as np
import pytest
from listing_transcription import real_throw_cube as listing_throw

from dice_env import Die, Rest, Scene, State, Wall, simulate
from dice_env.physics import vector_kernel
from dice_env.simulation import paper

FIELDS = ("face", "settled", "decided", "rest_time", "impacts", "unstable", "energy_rise",
          "max_penetration", "steps")


def paper_throws(n: int, spin: float = 0.75, seed: int = 0) -> State:
    """The paper's throw with the listing's random angular momentum, up to ``spin`` a side."""
    rng = np.random.default_rng(seed)
    return State(position=np.tile([0.0, 0.0, 3.0], (n, 1)), velocity=np.tile([5.0, 0, 5], (n, 1)),
                 angular_momentum=rng.random((n, 3)) * spin + 1e-6,
                 orientation=np.tile(np.eye(3), (n, 1, 1)), angular_velocity=np.zeros((n, 3)))


def scalar(scene: Scene, start: State, **kwargs):
    with vector_kernel.disabled():
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


SETTLING = paper.paper_scene().with_(rest=Rest(speed=0.2))  # most dice rest by 9 s
PLAIN = {"until": "t_max", "record": ()}


@pytest.mark.parametrize(("scene", "start", "kwargs"), [
    (paper.paper_scene().with_(t_max=1.5), paper_throws(37), PLAIN),  # two full tiles and a part
    (paper.paper_scene(normal=(0.2, -0.1, 1.0)).with_(t_max=1.5), paper_throws(37), PLAIN),
    (paper.paper_scene(mu=0.0).with_(t_max=1.0), paper_throws(37), PLAIN),
    (paper.paper_scene(D=0.0).with_(t_max=1.0), paper_throws(37), {**PLAIN, "free_flight": False}),
    (paper.paper_scene().with_(t_max=0.5), paper_throws(37, spin=300.0), PLAIN),  # turns > 1/64 rad
    (paper.paper_scene().with_(t_max=1.0), overflowing(37), PLAIN),
    (SETTLING, paper_throws(37), {}),
    (SETTLING, paper_throws(37), {"until": "early_rest"}),
    (paper.paper_scene(), paper_throws(37), {"until": "decided"}),
], ids=["paper", "tilted", "frictionless", "undamped", "fast-spin", "overflow", "rest",
        "early-rest", "decided"])
def test_bit_identical_to_the_scalar_kernel(scene, start, kwargs):
    assert vector_kernel.covers(scene, start.batch_size, False, False)
    with np.errstate(over="ignore", invalid="ignore"):
        fast = simulate(scene, start, **kwargs)
        assert_identical(fast, scalar(scene, start, **kwargs))
    if start.velocity[0, 0] > 1e300:
        assert fast.unstable.all() and len(set(fast.steps)) > 30  # each at its own step
        assert (fast.steps < scene.n_steps).all() and np.isfinite(fast.final.position).all()
    if kwargs.get("until") != "t_max":  # the dice end at their own steps, most of them early
        ended = fast.decided if kwargs.get("until") == "decided" else fast.settled
        assert ended.mean() > 0.5 and len(set(fast.steps[ended])) == ended.sum()


def test_same_results_for_any_thread_count_and_batch():
    scene = paper.paper_scene().with_(t_max=0.5)
    start = paper_throws(40)
    two = simulate(scene, start, until="t_max", record=(), num_threads=2)
    one = simulate(scene, start, until="t_max", record=(), num_threads=1)
    assert_identical(two, one)
    rows = slice(5, 21)  # another tile, other neighbours
    part = simulate(scene, State(*(a[rows] for a in start._arrays())), until="t_max",
                    record=())
    np.testing.assert_array_equal(part.final.orientation, two.final.orientation[rows])


def test_a_batch_of_paper_throws_ends_where_the_listing_does():
    # the independent transcription of real_throw_cube.m, 3000 steps of its own dt = 1e-4
    start = paper_throws(16, seed=3)
    ours = simulate(paper.paper_scene().with_(t_max=0.3), start, until="t_max", record=())
    for k in (0, 7, 15):
        ref = listing_throw(start.angular_momentum[k], clockmax=3000, tmax=0.3)
        np.testing.assert_allclose(ours.final.position[k], ref["x_cm"][-1], rtol=0, atol=1e-9)


@pytest.mark.parametrize("scene", [
    paper.paper_scene().with_(t_max=1.0, walls=(Wall.through((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0)),)),
    paper.paper_scene().with_(t_max=3.0, ground=paper.paper_scene().ground.with_(offset=0.5)),
], ids=["a wall the dice reach", "a raised floor"])
def test_the_paper_law_with_other_planes_is_the_scalar_kernels(scene):
    start = paper_throws(2 * vector_kernel.TILE)  # a batch the tiles would take
    assert_identical(simulate(scene, start, **PLAIN), scalar(scene, start, **PLAIN))


def test_other_scenes_and_runs_take_the_scalar_kernel():
    paper_scene = paper.paper_scene()
    assert vector_kernel.covers(paper_scene, vector_kernel.TILE, False, False)
    assert not vector_kernel.covers(Scene(), 64, False, False)
    assert not vector_kernel.covers(paper_scene, vector_kernel.TILE - 1, False, False)
    assert not vector_kernel.covers(paper_scene, 64, True, False)  # free-flight jumps
    assert not vector_kernel.covers(paper_scene, 64, False, True)  # records
    assert not vector_kernel.covers(paper.paper_scene(rotation=False), 64, False, False)
    walled = paper_scene.with_(walls=(Wall.through((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0)),))
    assert not vector_kernel.covers(walled, 64, False, False)  # the tile reads the floor alone
    raised = paper_scene.with_(ground=paper_scene.ground.with_(offset=0.5))
    assert not vector_kernel.covers(raised, 64, False, False)
    loaded = paper_scene.with_(die=Die.loaded(face=6, fraction=0.2, edge=1.0, mass=1.0))
    assert not vector_kernel.covers(loaded, 64, False, False)

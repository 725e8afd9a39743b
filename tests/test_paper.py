"""The paper's scripts against the independent transcription of its listings."""

import numpy as np
import pytest
from listing_transcription import ground_cube as listing_ground
from listing_transcription import real_throw_cube as listing_throw

from dice_env import ContactLaw, Die, FrictionLaw, Ground, Scene, Scheme
from dice_env.simulation import paper

TILTED = (0.2, -0.1, 1.0)


def assert_same_run(ours: paper.PaperRun, ref: dict, tol: float = 1e-9) -> None:
    np.testing.assert_array_equal(ours.t, ref["t"])
    np.testing.assert_allclose(ours.x_cm, ref["x_cm"], rtol=0, atol=tol)
    scale = np.abs(ref["energy"]).max()
    np.testing.assert_allclose(ours.energy, ref["energy"], rtol=0, atol=tol * scale)
    if "nodes" in ref:
        np.testing.assert_allclose(ours.nodes, ref["nodes"], rtol=0, atol=tol)


@pytest.mark.parametrize("normal", [(0, 0, 1), TILTED])
def test_ground_cube_matches_listing_over_full_run(normal):
    assert_same_run(paper.ground_cube(normal=normal, record_nodes=True),
                    listing_ground(normal=normal, record_nodes=True))


@pytest.mark.parametrize(
    ("L0", "normal"),
    [((0.3, 0.2, 0.1), (0, 0, 1)), ((0.3, 0.2, 0.1), TILTED), ((1e-6, 1e-6, 1e-6), (0, 0, 1))],
    ids=["spin", "spin-tilted", "no-spin"],
)
def test_real_throw_matches_listing_over_first_3_seconds(L0, normal):
    # the listing's dt = 10 s / 100000; 30000 steps are its first 3 s
    ours = paper.real_throw_cube(L0, normal=normal, clockmax=30000, tmax=3.0, record_nodes=True)
    assert_same_run(ours, listing_throw(L0, normal=normal, clockmax=30000, tmax=3.0,
                                        record_nodes=True))


def test_real_throw_defaults_are_the_listings():
    run = paper.real_throw_cube(seed=1)
    assert run.t.shape == (100000,) and run.x_cm.shape == (100000, 3)
    assert run.t[-1] == pytest.approx(10.0)
    assert np.all((run.L0 >= 1e-6) & (run.L0 <= 0.75 + 1e-6))
    np.testing.assert_array_equal(run.L0, paper.real_throw_cube(seed=1, clockmax=10, tmax=1e-3).L0)
    # the die comes down and stays near the table: z_cm ends about half a side up
    assert 0.4 < run.x_cm[-1, 2] < 0.6


def test_zero_spin_is_finite_where_the_listing_gives_nan():
    with np.errstate(invalid="ignore", divide="ignore"):
        ref = listing_throw((0, 0, 0), clockmax=100, tmax=0.01)
    assert np.isnan(ref["x_cm"][-1]).any()
    ours = paper.real_throw_cube((0, 0, 0), clockmax=20000, tmax=2.0)
    assert np.isfinite(ours.x_cm).all() and np.isfinite(ours.energy).all()


def test_figure_9_stiff_ground_gains_energy_at_10000_steps_not_20000():
    with pytest.raises(ValueError, match="critical step"):
        paper.ground_cube(S=1e6)
    coarse = paper.ground_cube(S=1e6, clockmax=10000, allow_unstable=True)
    fine = paper.ground_cube(S=1e6, clockmax=20000)
    start = coarse.energy[0]
    assert coarse.energy.max() > 1.5 * start
    assert coarse.result.unstable[0]
    assert fine.energy.max() <= start * (1 + 1e-6)
    assert not fine.result.unstable[0]


def test_paper_law_pushes_on_falling_corners_above_the_ground():
    # the listing's max(0, S*dg - D*un) drags a falling die even in the air: about 8*D*|v|
    kwargs = {"clockmax": 500, "tmax": 0.5, "u0": (0, 0, -1)}
    paper_law = paper.ground_cube(**kwargs)
    gated = paper.ground_cube(**kwargs, contact_law=ContactLaw.GATED)
    fall_gated = 3 - gated.x_cm[-1, 2]
    fall_paper = 3 - paper_law.x_cm[-1, 2]
    assert fall_gated == pytest.approx(0.5 + 9.8 * 0.5**2 / 2, rel=1e-2)
    # linear drag k = 8*D on unit mass: fall = g t/k - (v0 + g/k)(1 - exp(-k t))/k
    k, t, g = 8 * 0.2, 0.5, 9.8
    fall_drag = g * t / k - (-1 + g / k) * (1 - np.exp(-k * t)) / k
    assert fall_paper == pytest.approx(fall_drag, rel=1e-2)


def test_the_listing_scene_takes_other_fields_with_with_to_the_bit():
    listing = paper.paper_scene(normal=TILTED, S=1e6, dt=None)
    scene = listing.with_(dt=1e-3, t_max=3.0, allow_unstable=True,
                          ground=listing.ground.with_(contact_law="gated"))
    assert scene == Scene(
        die=Die.paper(), ground=Ground(stiffness=1e6, damping=0.1, friction=0.1, normal=TILTED,
                                       contact_law=ContactLaw.GATED),
        gravity=9.8, dt=1e-3, t_max=3.0, friction_vmin=1e-6, allow_unstable=True,
        scheme=Scheme.PAPER, friction_law=FrictionLaw.REGULARIZED)

"""The convergence study: its pieces, a reduced run, and (slow) its claims at larger sizes."""

import numpy as np
import pytest

from dice_env import Scene, State, throws
from dice_env.model.scene import FrictionLaw, Scheme
from studies import convergence as cv


def test_release_sampling_and_energy():
    scene = Scene()
    rng = np.random.default_rng(0)
    gentle = throws.RELEASES[0]
    start = gentle.sample(scene, 4000, rng)
    assert start.batch_size == 4000
    assert np.std(start.position[:, 2]) == pytest.approx(gentle.sigma_position, rel=0.05)
    assert np.std(start.angular_velocity) == pytest.approx(gentle.sigma_spin, rel=0.05)
    # a still die resting flat has no throw energy; dropped from 5 cm it has 5 cm
    still = State.release(scene, [0, 0, scene.die.size / 2 + 0.05], [0, 0, 0])
    assert cv.drop_height(scene, still)[0] == pytest.approx(0.05)
    spinning = State.release(scene, [0, 0, scene.die.size / 2], [1.0, 0, 0], [0, 0, 10.0])
    inertia = scene.die.inertia_body[2, 2]
    expected = (0.5 * scene.die.mass + 0.5 * inertia * 100 / 1.0) / (scene.die.mass * 9.81)
    assert cv.drop_height(scene, spinning)[0] == pytest.approx(expected)


def test_order_and_bins_on_known_data():
    dt = np.array([1e-5, 5e-6, 2.5e-6])
    assert cv.observed_order(dt, 3.0 * dt**2) == pytest.approx(2.0)
    frac, err, count = cv.binned(np.array([0.01, 0.02, 0.1, 0.5]),
                                 np.array([True, False, True, True]))
    assert count.tolist() == [2, 1, 0, 0, 1]
    assert frac[0] == 0.5 and err[0] == pytest.approx(np.sqrt(0.25 / 2))


def test_trajectory_error_falls_with_the_step():
    scene = Scene()
    rng = np.random.default_rng(1)
    start = cv.trajectory_start(scene, 8, rng)
    reference = cv.run_at(scene, start, cv.HORIZON, scene.step / 32)[0]
    curve = cv.trajectory_errors(scene, start, cv.HORIZON, (0.4, 0.2, 0.1), reference)
    assert np.all(np.diff(curve["position"]) < 0)
    assert cv.observed_order(curve["dt"], curve["position"]) > 0.5  # about 1 with more throws
    assert curve["position"][-1] < 0.25 * scene.die.size


def test_midpoint_scheme_is_second_order_with_smooth_friction():
    scene = Scene(friction_law=FrictionLaw.REGULARIZED, friction_vmin=0.05, scheme=Scheme.MIDPOINT)
    start = cv.trajectory_start(scene, 8, np.random.default_rng(2))
    reference = cv.run_at(scene, start, cv.HORIZON, Scene().step / 32)[0]
    curve = cv.trajectory_errors(scene, start, cv.HORIZON, (0.4, 0.2, 0.1), reference)
    assert cv.observed_order(curve["dt"], curve["position"]) > 1.7


def test_outcome_test_counts_and_p_values():
    result = cv.outcome_test(Scene(), throws.RELEASES[2], 100, np.random.default_rng(3))
    assert result["counts"].shape == (2, 6)
    assert (result["counts"].sum(1) == 100).all()
    assert 0.0 <= result["p_faces"] <= 1.0 and 0.0 <= result["p_success"] <= 1.0
    assert result["settled"] == 1.0


@pytest.mark.slow
def test_report_written_by_the_cli(tmp_path):
    from studies.__main__ import main

    main(["error", "--quick", "--out", str(tmp_path)])
    text = (tmp_path / "error-vs-runtime.md").read_text()
    assert "## Conclusions" in text and "Observed order" in text
    for name in ("error-vs-runtime.png", "face-agreement.png", "outcome-statistics.png"):
        assert (tmp_path / "figures" / name).stat().st_size > 10_000


@pytest.mark.slow
def test_vigorous_outcome_statistics_agree_between_dt_and_dt_over_4():
    result = cv.outcome_test(Scene(), throws.RELEASES[2], 3000, np.random.default_rng(5))
    assert result["p_faces"] > 0.001 and result["p_success"] > 0.001
    assert np.abs(np.diff(result["counts"], axis=0)).max() / 3000 < 0.04


@pytest.mark.slow
def test_gentle_faces_converge_at_the_default_step():
    # the criterion is >= 98 % (2000 throws in the study: 98.2 %); 600 throws here
    scene = Scene()
    start = throws.RELEASES[0].sample(scene, 600, np.random.default_rng(6))
    agreement = throws.face_agreement(scene, start)
    assert agreement["settled"].all()
    assert agreement["step"].mean() >= 0.97
    # the listing's friction and step on the same throws: far from it
    listing = scene.with_(friction_law=FrictionLaw.REGULARIZED, scheme=Scheme.PAPER)
    assert throws.face_agreement(listing, start)["step"].mean() < 0.8

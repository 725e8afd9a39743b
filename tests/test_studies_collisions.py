"""Two dice that meet: the helpers of the collisions study, and its page."""

import numpy as np
import pytest

from dice_env import throws
from studies import collisions as co


def test_turn_is_the_angle_between_vectors():
    before = np.array([[1.0, 0, 0]] * 3)
    after = np.array([[2.0, 0, 0], [0, 3.0, 0], [-1.0, 0, 0]])
    np.testing.assert_allclose(co.turn(before, after), [0.0, 90.0, 180.0], atol=1e-12)


def test_measures_compare_the_first_and_the_second_state():
    velocity = np.zeros((1, 2, 2, 3))
    velocity[0, 0] = [[1.0, 0, 0], [0, 1.0, 0]]
    velocity[0, 1] = [[0, 2.0, 0], [0, 1.0, 0]]
    m = co.measures(velocity, velocity)
    np.testing.assert_allclose(m["speed_change"], [[1.0, 0.0]])
    np.testing.assert_allclose(m["velocity_turn"], [[90.0, 0.0]], atol=1e-12)
    assert set(m) == {key for key, _, _ in co.MEASURES}


def test_the_quantile_interval_covers_the_true_quantile():
    rng = np.random.default_rng(0)
    covered = 0
    for _ in range(200):
        median, lo, hi = co.quantile_interval(rng.normal(size=101), 0.5)
        assert lo <= median <= hi
        covered += lo <= 0.0 <= hi
    assert 0.9 <= covered / 200 <= 1.0
    with pytest.raises(ValueError, match="q must be in"):
        co.quantile_interval(np.ones(3), 1.0)


def test_entropy_of_a_fair_and_a_certain_die():
    assert co.entropy_bits(np.full(6, 10)) == pytest.approx(np.log2(6))
    assert co.entropy_bits([0, 5, 0]) == 0.0
    codes = np.random.default_rng(1).integers(0, 6, 3000)
    lo, hi = co.entropy_estimate(codes, 6, np.random.default_rng(2))[1:]
    assert lo < np.log2(6) < hi + 1e-3 and hi - lo < 0.05


def test_mcnemar_sees_only_the_discordant_pairs():
    same = np.array([True, False] * 50)
    assert co.mcnemar(same, same) == 1.0
    more = same.copy()
    more[1::2][:30] = True  # 30 throws change only in the second run
    assert co.mcnemar(same, more) < 1e-6


def test_alone_makes_each_die_its_own_throw():
    scene, dice = co.pair_scene()
    state = throws.group_throws(scene, dice, 3, np.random.default_rng(0))
    one = co.alone(state)
    assert one.batch_size == 6 and one.n_dice == 1
    np.testing.assert_array_equal(one.position[3:, 0], state.position[:, 1])
    np.testing.assert_array_equal(one.orientation[:3, 0], state.orientation[:, 0])


def test_quick_study_writes_its_page(tmp_path):
    n = co.run(tmp_path, quick=True)
    assert n["throws"] == co.QUICK and n["met"] > 0.2  # the dice do meet
    assert 0 < n["counted_met"] <= n["met"] * co.QUICK and n["windows"] > 0
    assert 0.0 <= n["in_flight"] <= 1.0 and n["die_impacts"] >= 1.0
    assert 0.0 <= n["change_together_share"] <= 1.0 and 0.0 <= n["mcnemar_p"] <= 1.0
    assert n["spin_turn_median"] > 1.0  # a collision turns the spin
    text = (tmp_path / "collisions.md").read_text()
    assert f"--throws {co.QUICK}" in text and "McNemar" in text and "nan" not in text
    assert (tmp_path / "figures" / "collisions.png").stat().st_size > 10_000

"""Setting the dice for a craps throw: the set, the throw, the voiding rule and the page."""

import numpy as np
import pytest

from dice_env import Die, State, throws
from dice_env.model.rotations import axis_angle
from dice_env.simulation.group import GroupState, simulate_group
from dice_env.simulation.simulate import UP
from studies import craps as cr


@pytest.mark.parametrize("angle", [0.0, 0.3, np.pi / 2, np.pi, 4.0, 3 * np.pi / 2])
def test_the_sevens_set_shows_a_seven_while_both_dice_turn_alike_about_the_roll_axis(angle):
    die = Die()
    turned = axis_angle([0.0, 1.0, 0.0], angle) @ throws.sevens_set()
    assert die.face_read(turned, UP).sum() == 7


def test_the_crossed_set_shows_a_seven_in_2_of_16_common_rolls():
    die, roll = Die(), [0.0, 1.0, 0.0]
    sevens = [die.face_read(axis_angle(roll, a * np.pi / 2)
                            @ np.stack([throws.crossed_set()[0],
                                        axis_angle(roll, b * np.pi / 2) @ throws.crossed_set()[1]]),
                            UP).sum() == 7 for a in range(4) for b in range(4)]
    assert sum(sevens) == 2


def test_the_throw_goes_forward_with_backspin():
    hand = throws.SET_THROW
    a = hand.action(2.0)
    np.testing.assert_allclose(a[:3] * hand.max_speed, [2.0, 0.0, hand.lift])
    assert a[4] * hand.max_spin == -hand.backspin and np.all(np.abs(a) <= 1.0)
    np.testing.assert_array_equal(hand.action(), hand.action(hand.speed))


def test_a_die_that_misses_the_back_wall_voids_the_throw():
    scene = cr.craps_scene().with_(t_max=0.3)
    near = State.release(scene, [0.96, 0.0, 0.02], [0.8, 0.0, 0.0])  # into the back wall
    short = State.release(scene, [0.0, 0.0, 0.02], [0.0, 0.0, -0.2])  # straight down
    both = GroupState.of([State(*(np.concatenate(a) for a in zip(
        near._arrays(), short._arrays(), strict=True)))])
    result = simulate_group(scene, (Die(),), both)
    assert scene.planes[cr.BACK_WALL].normal == (-1.0, 0.0, 0.0)  # the back wall
    assert cr.reasons(result)["a die did not touch the back wall"].tolist() == [False, True]


def test_quick_study_writes_its_page(tmp_path):
    n = cr.run(tmp_path, quick=True)
    assert n["throws_per_cell"] == cr.QUICK and 0.0 <= n["voided"] < 0.5
    cells = [k for k in n if k.startswith("p7_")]
    assert len(cells) == len(cr.QUICK_NOISES) * len(cr.QUICK_SPEEDS) * 2
    assert all(0.0 <= n[k] <= 1.0 for k in cells)
    text = (tmp_path / "craps.md").read_text()
    assert f"--throws {cr.QUICK}" in text and "Fisher" in text and "nan" not in text
    assert (tmp_path / "figures" / "craps.png").stat().st_size > 10_000

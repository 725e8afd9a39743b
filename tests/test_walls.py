"""Walls: any planes around the floor, each with its own material."""

import numpy as np
import pytest

from dice_env import Scene, State, simulate
from dice_env.model.rotations import axis_angle, random_rotations
from dice_env.model.scene import Ground, Wall
from dice_env.model.surroundings import craps, tray, walls


def test_a_die_thrown_into_the_tray_stays_in_it_and_never_sinks_into_a_wall():
    scene = Scene(walls=tray())
    rng = np.random.default_rng(3)
    n = 64
    heading = rng.normal(size=(n, 3)) * [1, 1, 0.2]
    heading /= np.linalg.norm(heading, axis=1, keepdims=True)
    start = State.release(scene, [0, 0, 0.05], heading * rng.uniform(1.5, 3.0, (n, 1)),
                          rng.normal(0, 40, (n, 3)), random_rotations(rng, n))
    result = simulate(scene, start, until="decided")
    x = result.final.position
    assert (np.abs(x[:, 0]) < 0.15).all() and (np.abs(x[:, 1]) < 0.10).all()
    assert result.impacts.max() > 1
    assert not result.sunk.any() and not result.unstable.any()
    floor_only = simulate(Scene(), State.release(Scene(), [0, 0, 0.05], [0, 0, -3.0]))
    assert result.max_penetration.max() < 2 * floor_only.max_penetration.max()


@pytest.mark.parametrize("tilt", [0.0, 30.0, 90.0, 135.0])
def test_a_wall_at_any_angle_bounces_like_the_floor_rotated_to_it(tilt):
    # no gravity: a flat face meets the plane at 1 m/s, from 1 mm away
    turn = axis_angle([0, 1, 0], np.radians(tilt))  # takes the floor's normal to the wall's
    normal = turn @ [0, 0, 1]
    base = Scene(gravity=0.0)
    floor = State.release(base, [0, 0, 0.009], [0, 0, -1.0])
    wall = Wall.through(-0.5 * normal, normal)
    scene = Scene(gravity=0.0, walls=(wall,), ground=Ground(normal=(0, 0, 1), offset=-1.0))
    start = State.release(scene, -0.5 * normal + 0.009 * normal, -normal, orientation=turn)
    a = simulate(base, floor, t_max=0.02, until="t_max")
    b = simulate(scene, start, t_max=0.02, until="t_max")
    np.testing.assert_allclose(b.final.velocity[0], turn @ a.final.velocity[0], atol=1e-9)
    np.testing.assert_allclose(b.max_penetration, a.max_penetration, rtol=1e-6)
    assert a.final.velocity[0, 2] > 0.4  # it bounced


def test_a_die_resting_against_a_wall_on_the_floor_is_at_rest():
    wall = Wall.through((0.0081, 0, 0), (-1, 0, 0))  # 0.1 mm from the die's side
    scene = Scene(walls=(wall,))
    start = State.release(scene, [0, 0, 0.0081], [0.05, 0, 0])
    result = simulate(scene, start)
    assert result.settled[0] and result.face[0] == 1
    assert result.final.position[0, 0] == pytest.approx(0.0081 - 0.008, abs=2e-4)


def test_the_stiffest_plane_sets_the_step():
    soft, stiff = Scene(), Scene(walls=(Wall(stiffness=1e7, offset=-1.0),))
    assert stiff.critical_dt < soft.critical_dt / 5
    assert Scene(walls=tray()).critical_dt == soft.critical_dt
    wall = Wall(stiffness=1e12, offset=-1.0)  # the refusals name the wall that sets the step
    with pytest.raises(ValueError, match=r"critical step .* of wall 1 \(stiffness 1e\+12"):
        Scene(walls=(Wall(offset=-1.0), wall), dt=1e-5)
    with pytest.raises(ValueError, match=r"of wall 0 \(stiffness 1e\+12.*soften the contact"):
        Scene(walls=(wall,))


def test_presets_and_bad_walls():
    assert len(tray()) == 4 and len(craps()) == 3 and walls("none") == ()
    assert walls("tray", friction=0.2)[0].friction == 0.2
    with pytest.raises(ValueError, match="walls must be one of"):
        walls("bowl")
    with pytest.raises(TypeError, match="walls must be a tuple of Wall"):
        Scene(walls=(Ground(),))
    with pytest.raises(ValueError, match="normal must be a finite non-zero vector"):
        Wall.through((0, 0, 0), (0, 0, 0))
    with pytest.raises(ValueError, match="length must be"):
        tray(length=0.0)
    with pytest.raises(ValueError, match="position must hold every corner"):
        State.release(Scene(walls=tray()), [0.5, 0, 0.05], [0, 0, 0])  # outside the tray

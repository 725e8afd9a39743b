"""Several dice in one throw: die–die contact conserves momentum, edges meet edges, stacks hold."""

import numpy as np
import pytest

from dice_env import Die, Scene, State, simulate
from dice_env.model.rotations import axis_angle, random_rotations
from dice_env.model.scene import FrictionLaw, Ground
from dice_env.model.surroundings import craps, tray
from dice_env.simulation.group import DieContact, GroupState, group_step, simulate_group

DIE = Die()
EDGE = DIE.size


def hand(n, seed, height=0.08):
    rng = np.random.default_rng(seed)
    return State.release(Scene(), [0.0, 0.0, height], rng.normal(0, 0.4, (n, 3)),
                         rng.normal(0, 20, (n, 3)), random_rotations(rng, n))


@pytest.mark.parametrize("flight", [False, True])
@pytest.mark.parametrize("decided", [False, True])
def test_a_group_of_one_die_is_the_single_die_bit_for_bit(decided, flight):
    scene = Scene(t_max=1.5)
    start = hand(6, 0)
    until = "decided" if decided else "rest"
    alone = simulate(scene, start, free_flight=flight, until=until)
    group = simulate_group(scene, (DIE,), GroupState.of([start]), until=until,
                           free_flight=flight)
    np.testing.assert_array_equal(group.face[:, 0], alone.face)
    np.testing.assert_array_equal(group.steps, alone.steps)
    np.testing.assert_array_equal(group.settled, alone.settled)
    np.testing.assert_array_equal(group.decided, alone.decided)
    np.testing.assert_array_equal(group.rest_time, alone.rest_time)
    np.testing.assert_array_equal(group.impacts[:, 0], alone.impacts)
    np.testing.assert_array_equal(group.final.position[:, 0], alone.final.position)
    np.testing.assert_array_equal(group.final.orientation[:, 0], alone.final.orientation)


def free_pair(offset, velocity, spin=(0.0, 0.0, 0.0), rot_a=None, rot_b=None):
    """Two dice high above the floor with no gravity, die 1 at ``offset`` from die 0."""
    scene = Scene(gravity=0.0, t_max=0.03)
    base = np.array([0.0, 0.0, 1.0])
    a = State.release(scene, base, velocity, spin, rot_a)
    b = State.release(scene, base + np.asarray(offset), -np.asarray(velocity),
                      -np.asarray(spin), rot_b)
    return scene, GroupState.of([a, b])


def momenta(state):
    p = state.velocity * DIE.mass
    linear = p.sum(axis=1)
    angular = (np.cross(state.position, p) + state.angular_momentum).sum(axis=1)
    return linear, angular


def energy(state):
    kinetic = 0.5 * DIE.mass * (state.velocity**2).sum(axis=(1, 2))
    return kinetic + 0.5 * np.einsum("bni,bni->b", state.angular_momentum,
                                     state.angular_velocity)


@pytest.mark.parametrize("law", list(FrictionLaw))
def test_a_collision_in_free_space_keeps_momentum_and_never_gains_energy(law):
    scene, start = free_pair([EDGE * 1.05, 0.003, 0.002], [0.6, 0.05, 0.0], spin=[3.0, -5.0, 8.0])
    result = simulate_group(scene, (DIE, DIE), start, until="t_max",
                            contact=DieContact(friction_law=law))
    assert result.overlap[0] > 0  # they met
    linear0, angular0 = momenta(start)
    linear1, angular1 = momenta(result.final)
    scale = DIE.mass * 0.6
    np.testing.assert_allclose(linear1, linear0, atol=1e-12 * scale)
    np.testing.assert_allclose(angular1, angular0, atol=1e-12 * scale * EDGE)
    assert energy(result.final)[0] <= energy(start)[0] * (1 + 1e-9)
    assert result.final.velocity[0, 0, 0] < 0.3  # die 0 was stopped or thrown back


def test_edge_on_edge_at_a_right_angle_bounces():
    # Die 0 turned 45 degrees about x has an edge along x at its bottom; die 1 below, turned
    # about y, an edge along y at its top: they meet edge across edge, no corner inside.
    half_diagonal = EDGE / np.sqrt(2)
    scene, start = free_pair([0.0, 0.0, -2 * half_diagonal - 1e-4], [0.0, 0.0, -0.3],
                             rot_a=axis_angle([1, 0, 0], np.pi / 4),
                             rot_b=axis_angle([0, 1, 0], np.pi / 4))
    result = simulate_group(scene, (DIE, DIE), start, until="t_max")
    assert result.overlap[0] > 0
    assert result.final.velocity[0, 0, 2] > 0 > result.final.velocity[0, 1, 2]  # bounced
    assert result.final.position[0, 0, 2] > result.final.position[0, 1, 2] + EDGE  # not through


def test_a_die_stacked_on_another_holds_and_is_not_read():
    scene = Scene(t_max=0.3)
    bottom = State.release(scene, [0, 0, EDGE / 2], [0, 0, 0])
    top = State.release(scene, [0.002, 0, 1.5 * EDGE + 1e-5], [0, 0, 0])
    result = simulate_group(scene, (DIE, DIE), GroupState.of([bottom, top]))
    assert np.isfinite(result.final.position).all() and not result.unstable.any()
    assert result.final.position[0, 1, 2] > result.final.position[0, 0, 2] + 0.9 * EDGE
    assert result.read.tolist() == [[True, False]] and result.face[0, 1] == 0
    assert result.face[0, 0] == 1
    # a die held by another rests: the throw ends at rest, long before t_max
    assert result.settled[0] and result.rest_time[0] < 0.2


def test_stick_slip_holds_a_die_stacked_on_another_on_a_slope_the_regularised_law_creeps():
    # 15 degrees: tan 15 = 0.27 < mu = 0.4 for the table and the dice, so both should hold
    angle = 15.0
    scene = Scene(ground=Ground.tilted(angle))
    normal = np.array(scene.ground.normal)
    load = DIE.mass * scene.gravity * np.cos(np.radians(angle)) / 4  # per corner, one die
    tilt = axis_angle([0, 1, 0], np.radians(angle))
    bottom = normal * (EDGE / 2 - 2 * load / scene.ground.stiffness)  # carrying both dice
    top = bottom + normal * (EDGE - load / DieContact().stiffness)
    start = GroupState.of([State.release(scene, centre, [0, 0, 0], orientation=tilt)
                           for centre in (bottom, top)])
    apart = start.position[0, 1] - start.position[0, 0]

    def slid(law):
        result = simulate_group(scene.with_(t_max=1.0), (DIE, DIE), start, until="t_max",
                                contact=DieContact(friction_law=law))
        assert not result.unstable.any() and result.overlap[0] > 0
        moved = result.final.position[0, 1] - result.final.position[0, 0] - apart
        return np.linalg.norm(moved - (moved @ normal) * normal)  # along the slope

    assert slid(FrictionLaw.STICK_SLIP) < 1e-6
    assert slid(FrictionLaw.REGULARIZED) > 1e-5


def test_dice_released_inside_each_other_are_refused():
    scene = Scene()
    a = State.release(scene, [0, 0, 0.05], [0, 0, 0])
    for offset, rot in (([0.5 * EDGE, 0, 0.05], None),  # aligned: corners on faces
                        ([1.05 * EDGE, 0, 0.05], axis_angle([0, 0, 1], np.pi / 4))):
        b = State.release(scene, offset, [0, 0, 0], None, rot)
        with pytest.raises(ValueError, match="dice 0 and 1 of throw 0 overlap"):
            simulate_group(scene, (DIE, DIE), GroupState.of([a, b]))
    touching = State.release(scene, [EDGE, 0, 0.05], [0, 0, 0])  # face to face
    simulate_group(scene.with_(t_max=0.01), (DIE, DIE), GroupState.of([a, touching]))


def test_the_pair_contact_sets_the_step():
    scene = Scene()
    soft, stiff = DieContact(stiffness=1e3, damping=0.1), DieContact(stiffness=1e8)
    assert group_step(scene, (DIE,)) == scene.step
    assert group_step(scene, (DIE, DIE), soft) == scene.step
    assert group_step(scene, (DIE, DIE), stiff) < scene.step / 10


def test_two_dice_and_a_d20_thrown_into_a_tray_land_and_are_read():
    scene = Scene(walls=tray(), t_max=4.0)
    dice = (DIE, DIE, Die.standard("d20"))
    rng = np.random.default_rng(3)
    n = 8
    states = [State.release(scene.with_(die=d), [0.0, 0.03 * (i - 1), 0.1],
                            np.array([0.4, -0.2 * (i - 1), 0.0]) + rng.normal(0, 0.1, (n, 3)),
                            rng.normal(0, 20, (n, 3)), random_rotations(rng, n))
              for i, d in enumerate(dice)]
    result = simulate_group(scene, dice, GroupState.of(states), until="decided")
    assert np.isfinite(result.final.position).all() and not result.unstable.any()
    assert result.decided.mean() >= 0.75
    read = result.face[result.decided]
    assert ((read[:, :2] >= 0) & (read[:, :2] <= 6)).all() and (read[:, 2] <= 20).all()
    assert (np.abs(result.final.position[..., 0]) < 0.15).all()  # inside the tray


def test_bad_arguments_are_refused():
    scene = Scene()
    state = GroupState.of([hand(2, 0)])
    with pytest.raises(ValueError, match="state holds 1 dice per throw, dice 2"):
        simulate_group(scene, (DIE, DIE), state)
    with pytest.raises(TypeError, match="dice must be a sequence of Die"):
        simulate_group(scene, DIE, state)
    with pytest.raises(ValueError, match=r"GroupState.position must have shape \(B, N, 3\)"):
        GroupState(*(np.zeros((2, 3)),) * 3, np.eye(3)[None], np.zeros((2, 3)))
    with pytest.raises(ValueError, match="stiffness"):
        DieContact(stiffness=0.0)
    with pytest.raises(ValueError, match="friction_law must be a FrictionLaw or one of"):
        DieContact(friction_law="glue")
    for tangential in (0.0, 1.5, float("nan")):
        with pytest.raises(ValueError, match="tangential must be in"):
            DieContact(tangential=tangential)
    assert DieContact().friction_law == FrictionLaw.STICK_SLIP  # the default
    assert DieContact(friction_law="regularized").friction_law == FrictionLaw.REGULARIZED
    with pytest.raises(TypeError, match="dice must be a sequence of Die"):
        simulate_group(scene, (d for d in (DIE,)), state)
    with pytest.raises(TypeError, match="states must be a non-empty sequence of State"):
        GroupState.of(hand(2, 0))
    for flag in ("free_flight", "orientations"):
        with pytest.raises(TypeError, match=f"{flag} must be a bool, got 'no'"):
            simulate_group(scene, (DIE,), state, **{flag: "no"})
    for until in ("early_rest", "no", None):  # early rest: one die alone (simulate)
        with pytest.raises(ValueError, match="until must be one of 'rest', 'decided', 't_max'"):
            simulate_group(scene, (DIE,), state, until=until)
    many = GroupState.of([State.release(scene, [x, 0.0, 0.08], np.zeros((64, 3)))
                          for x in (-0.03, 0.03)])
    with pytest.raises(ValueError, match=r"record_every=1 records .* GiB\), more than the limit"):
        simulate_group(scene.with_(t_max=10.0), (DIE, DIE), many, record_every=1,
                       orientations=True)


def test_a_throw_alone_equals_the_same_throw_inside_a_batch():
    scene = Scene(walls=tray(), t_max=1.5)
    rng = np.random.default_rng(5)
    n = 4
    states = [State.release(scene, [0.0, 0.025 * (2 * i - 1), 0.06],
                            np.array([0.5, -0.3 * (2 * i - 1), 0.0]) + rng.normal(0, 0.1, (n, 3)),
                            rng.normal(0, 20, (n, 3)), random_rotations(rng, n))
              for i in range(2)]
    batch = simulate_group(scene, (DIE, DIE), GroupState.of(states), until="decided")
    alone = simulate_group(scene, (DIE, DIE), _one(GroupState.of(states), 2),
                           until="decided")
    for field in ("face", "steps", "decided", "overlap"):
        np.testing.assert_array_equal(getattr(alone, field)[0], getattr(batch, field)[2])
    np.testing.assert_array_equal(alone.final.position[0], batch.final.position[2])


def _one(state, i):
    """Throw ``i`` of a batch as a batch of one."""
    return GroupState(*(a[i:i + 1] for a in state._arrays()))


@pytest.mark.parametrize("law", list(FrictionLaw))
def test_mirrored_throws_land_mirrored(law):
    # Two dice thrown at each other mirror-symmetrically about the plane y = 0, turned and
    # spinning about y (so that the faces that meet stay across the mirror): each state stays
    # the mirror image of the other's through the collision (in the air: a landing's chaos
    # would grow the round-off of summing the corners in another order).
    scene = Scene(t_max=0.06)
    mirror = np.diag([1.0, -1.0, 1.0])
    rot = axis_angle([0, 1, 0], 0.4)  # its own mirror image: M R M = R
    spin = np.array([0.0, 7.0, 0.0])  # a pseudovector: mirrored, -M w = w
    a = State.release(scene, [0.0, 0.02, 0.1], [0.2, -0.5, 0.0], spin, rot)
    b = State.release(scene, [0.0, -0.02, 0.1], [0.2, 0.5, 0.0], -mirror @ spin,
                      mirror @ rot @ mirror)
    result = simulate_group(scene, (DIE, DIE), GroupState.of([a, b]), until="t_max",
                            contact=DieContact(friction_law=law))
    assert result.overlap[0] > 0  # they met
    end = result.final
    np.testing.assert_allclose(end.position[0, 1], mirror @ end.position[0, 0], atol=1e-9)
    np.testing.assert_allclose(end.orientation[0, 1], mirror @ end.orientation[0, 0] @ mirror,
                               atol=1e-7)
    assert end.velocity[0, 0, 1] > 0 > end.velocity[0, 1, 1]  # bounced apart


@pytest.mark.parametrize("speed", [5.0, 20.0])
def test_fast_dice_do_not_pass_through_each_other(speed):
    # Head on, corner first and edge across edge, at up to 20 m/s each (a throw is ~1 m/s).
    for rot_a, rot_b in ((None, axis_angle([1, 1, 0], 0.6)),
                         (axis_angle([1, 0, 0], np.pi / 4), axis_angle([0, 1, 0], np.pi / 4))):
        scene, start = free_pair([0.0, 0.0, -1.5 * EDGE], [0.0, 0.0, -speed],
                                 rot_a=rot_a, rot_b=rot_b)
        result = simulate_group(scene.with_(t_max=0.005), (DIE, DIE), start,
                                until="t_max")
        assert np.isfinite(result.final.position).all()
        assert result.final.position[0, 0, 2] > result.final.position[0, 1, 2]
        assert result.final.velocity[0, 0, 2] > 0 > result.final.velocity[0, 1, 2]


def test_free_flight_jumps_only_where_no_die_can_touch_anything():
    # two dice dropped side by side from 30 cm toward each other: most of the fall is jumped;
    # the dice's first collision is that of stepping every step to round-off, the landing too
    # where the collisions are not chaotic, and after the bounces the faces agree as often as
    # round-off allows. A jump a step off would be 1e-5 m off (2.4 m/s for 6.5 us). The
    # round-off grows where a stick-slip tie or a contact point starts or ends on a threshold:
    # stepping alone turns 1e-13 m at the release into 1e-2 m by the landing in two of these
    # throws (a nudge of die 1's release by +-1e-13 or 3e-13 m).
    scene = Scene(walls=tray(), t_max=1.0)
    rng = np.random.default_rng(3)
    n = 8
    spin = rng.normal(0, 15, (2, n, 3))
    turn = random_rotations(rng, 2 * n).reshape(2, n, 3, 3)
    start = GroupState.of([State.release(scene, [x, 0.0, 0.3], [-np.sign(x) * 0.3, 0, 0],
                                         spin[i], turn[i])
                           for i, x in enumerate((-0.02, 0.02))])
    runs = {flight: simulate_group(scene.with_(t_max=0.26), (DIE, DIE), start,
                                   free_flight=flight, until="t_max",
                                   contact=DieContact(islands=False))  # the lockstep's jumps
            for flight in (True, False)}
    assert (runs[False].overlap > 0).any() and runs[False].impacts.all()  # met and landed
    met = runs[False].meet_steps[:, 1] >= 0
    assert met.sum() >= 6
    np.testing.assert_array_equal(runs[True].meet_steps[met], runs[False].meet_steps[met])
    for field in ("meet_velocity", "meet_spin"):
        np.testing.assert_allclose(getattr(runs[True], field)[met],
                                   getattr(runs[False], field)[met], rtol=1e-8, atol=1e-9)
    landed = np.abs(runs[True].final.position - runs[False].final.position).max(axis=(1, 2))
    assert (landed < 1e-6).mean() >= 0.75, landed
    faces = [simulate_group(scene, (DIE, DIE), start, free_flight=flight,
                            until="decided").face for flight in (True, False)]
    assert (faces[0] == faces[1]).all(axis=1).mean() >= 0.75


def test_the_first_meeting_records_the_velocities_before_and_after():
    scene, start = free_pair([EDGE * 1.05, 0.003, 0.002], [0.6, 0.05, 0.0], spin=[3.0, -5.0, 8.0])
    result = simulate_group(scene, (DIE, DIE), start, until="t_max")
    assert result.meet_dice.tolist() == [[0, 1]]
    begin, end = result.meet_steps[0]
    assert 0 < begin < end < result.steps[0]
    assert result.die_impacts.tolist() == [[1, 1]] and not result.touched.any()  # no floor
    # no force before the contact, none after it: the release's and the final velocities
    np.testing.assert_array_equal(result.meet_velocity[0, 0], start.velocity[0])
    np.testing.assert_allclose(result.meet_spin[0, 0], start.angular_velocity[0], rtol=1e-12)
    np.testing.assert_array_equal(result.meet_velocity[0, 1], result.final.velocity[0])
    np.testing.assert_allclose(result.meet_spin[0, 1], result.final.angular_velocity[0],
                               rtol=1e-12)
    momentum = result.meet_velocity[0].sum(axis=1)  # equal masses: kept across the contact
    np.testing.assert_allclose(momentum[1], momentum[0], atol=1e-15)
    assert not np.allclose(result.meet_spin[0, 1], result.meet_spin[0, 0])  # spins changed


def test_a_die_alone_moves_as_in_its_group_until_the_dice_meet():
    # stepped every step (a group's flight jumps depend on all its dice)
    scene = Scene(walls=tray(), t_max=4.0)
    scene = scene.with_(dt=group_step(scene, (DIE, DIE)))
    rng = np.random.default_rng(1)
    n = 6
    states = [State.release(scene, [0.0, 0.02 * (2 * i - 1), 0.05],
                            np.array([0.3, 0.0, 0.0]) + rng.normal(0, 0.4, (n, 3)),
                            rng.normal(0, 20, (n, 3)), random_rotations(rng, n))
              for i in range(2)]
    group = simulate_group(scene, (DIE, DIE), GroupState.of(states), until="decided",
                           free_flight=False)
    met = group.meet_steps[:, 0] >= 0
    np.testing.assert_array_equal(met, group.overlap > 0)
    assert 0 < met.sum() < n
    np.testing.assert_array_equal(group.die_impacts[~met], 0)
    assert (group.die_impacts[met] >= 1).all()
    alone = [simulate_group(scene, (DIE,), GroupState.of([s]), until="decided",
                            free_flight=False) for s in states]
    for i in range(2):  # dice that never met land as if thrown alone
        np.testing.assert_array_equal(group.face[~met, i], alone[i].face[~met, 0])
    start = GroupState.of(states)
    for throw in np.flatnonzero(met):  # alone to the step the dice met: the same, bit for bit
        steps = int(group.meet_steps[throw, 0])
        one = GroupState(*(a[throw, :, None] for a in start._arrays()))  # each die a throw
        run = simulate_group(scene.with_(t_max=steps * scene.dt), (DIE,), one,
                             until="t_max", free_flight=False)
        assert (run.steps == steps).all()
        np.testing.assert_array_equal(run.final.velocity[:, 0], group.meet_velocity[throw, 0])
        np.testing.assert_array_equal(run.final.angular_velocity[:, 0],
                                      group.meet_spin[throw, 0])


def test_touched_tells_which_planes_a_die_hit():
    scene = Scene(walls=craps(), t_max=0.4)
    ahead = State.release(scene, [0.95, 0.0, 0.02], [0.8, 0.0, 0.0])  # toward the back wall
    down = State.release(scene, [0.0, 0.0, 0.02], [0.0, 0.0, -0.2])
    result = simulate_group(scene, (DIE,), GroupState.of([State(*(
        np.concatenate(a) for a in zip(ahead._arrays(), down._arrays(), strict=True)))]))
    assert result.touched[:, 0].tolist() == [[True, True, False, False],
                                             [True, False, False, False]]
    assert result.meet_steps.tolist() == [[-1, -1]] * 2 and not result.die_impacts.any()


def test_records_fall_on_the_same_steps_with_free_flight():
    # a jump stops at the next record: the records are those of stepping (before any contact,
    # to round-off), every record filled, and the run ends
    scene = Scene(walls=tray(), t_max=0.2)
    start = GroupState.of([State.release(scene, [x, 0.0, 0.3], [0.0, 0.0, 0.0], [0, 0, 5.0])
                           for x in (-0.03, 0.03)])
    runs = [simulate_group(scene, (DIE, DIE), start, free_flight=flight, record_every=500,
                           until="t_max") for flight in (True, False)]
    np.testing.assert_array_equal(runs[0].t, runs[1].t)
    np.testing.assert_allclose(runs[0].x_cm, runs[1].x_cm, rtol=0, atol=1e-9)
    assert (runs[0].x_cm[:, :, :, 2] < 0.3).all()  # the dice fell: every record written

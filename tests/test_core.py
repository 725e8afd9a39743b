"""The simulator core: invariants, analytic cases, rest, stability, determinism, bad input."""

import numpy as np
import pytest

from dice_env import ContactLaw, Die, FrictionLaw, Ground, Scene, Scheme, State, simulate
from dice_env.model.rotations import (
    axis_angle,
    matrix_to_rotation_vector,
    random_rotations,
    rotation_vector_to_matrix,
)


def random_throws(scene: Scene, n: int, seed: int = 0, height: float = 0.1) -> State:
    rng = np.random.default_rng(seed)
    position = np.column_stack([np.zeros((n, 2)), np.full(n, height)])
    return State.release(scene, position, rng.normal(0, 0.5, (n, 3)), rng.normal(0, 20, (n, 3)),
                         random_rotations(rng, n))


# --- faces -----------------------------------------------------------------------------------

def test_standard_die_faces():
    die = Die()
    normals = {face: die.face_normals[face - 1] for face in range(1, 7)}
    for face in range(1, 7):
        np.testing.assert_array_equal(normals[face], -normals[7 - face])
    # right-handed die: 1, 2, 3 counter-clockwise around their shared corner seen from outside
    assert np.dot(np.cross(normals[1], normals[2]), normals[3]) > 0
    up = np.array([0.0, 0.0, 1.0])
    assert die.face_read(np.eye(3), up) == 1
    assert die.face_read(axis_angle([0, 1, 0], -np.pi / 2), up) == 2  # +x turned to +z
    assert die.face_read(axis_angle([1, 0, 0], np.pi / 2), up) == 3  # +y turned to +z
    assert die.face_read(axis_angle([1, 0, 0], np.pi), up) == 6


# --- flight --------------------------------------------------------------------------------

def test_free_fall_is_ballistic_and_spin_is_a_constant_rotation():
    scene = Scene()
    dt, t = scene.step, 0.2
    spin = np.array([3.0, -7.0, 11.0])
    start = State.release(scene, [0, 0, 1.0], [0.3, -0.2, 1.0], spin)
    res = simulate(scene, start, t_max=t, record_every=1, record=("orientations",))
    n = round(t / dt)
    time = res.t[-1]
    assert time == pytest.approx(n * dt)
    exact = np.array([0, 0, 1.0]) + time * np.array([0.3, -0.2, 1.0])
    exact[2] -= 9.81 * time**2 / 2
    # symplectic Euler is ballistic up to its own O(dt) offset g*dt*t/2
    np.testing.assert_allclose(res.x_cm[0, -1], exact, atol=9.81 * dt * time / 2 + 1e-12)
    np.testing.assert_allclose(res.final.velocity[0], [0.3, -0.2, 1.0 - 9.81 * time], atol=1e-12)
    np.testing.assert_array_equal(res.final.angular_momentum, start.angular_momentum)
    rotation = axis_angle(spin, np.linalg.norm(spin) * time)
    np.testing.assert_allclose(res.final.orientation[0], rotation, atol=1e-10)


def test_zero_spin_keeps_orientation_exactly():
    scene = Scene()
    start = State.release(scene, [0, 0, 1.0], [1.0, 0, 0], orientation=axis_angle([1, 1, 0], 0.3))
    res = simulate(scene, start, t_max=0.2)
    np.testing.assert_array_equal(res.final.orientation, start.orientation)
    assert np.isfinite(res.final.position).all()


@pytest.mark.parametrize("die", [Die(), Die.loaded(face=6, fraction=0.3)], ids=["fair", "loaded"])
def test_angular_momentum_conserved_in_flight(die):
    scene = Scene(die=die)
    start = State.release(scene, [0, 0, 5.0], [0, 0, 0], [40.0, 25.0, -30.0],
                          random_rotations(np.random.default_rng(3), 1))
    res = simulate(scene, start, t_max=0.5, record_every=100, record=("orientations",))
    np.testing.assert_array_equal(res.final.angular_momentum, start.angular_momentum)
    # rotational energy of the torque-free body drifts only at the scheme's first order
    inertia = die.inertia_body
    momentum = start.angular_momentum[0]
    body_l = np.einsum("nji,j->ni", res.orientations[0], momentum)
    energy = 0.5 * np.einsum("ni,ni->n", body_l, np.linalg.solve(inertia, body_l.T).T)
    assert np.ptp(energy) / energy[0] < (1e-10 if die.is_isotropic else 0.02)


def test_corner_distances_stay_rigid():
    scene = Scene()
    res = simulate(scene, random_throws(scene, 4), t_max=0.5, record_every=50, record=("nodes",))
    nodes = res.nodes
    dists = np.linalg.norm(nodes[:, :, :, None] - nodes[:, :, None, :], axis=-1)
    reference = np.linalg.norm(scene.die.vertices_body[:, None] - scene.die.vertices_body[None],
                               axis=-1)
    np.testing.assert_allclose(dists, np.broadcast_to(reference, dists.shape), atol=1e-12)


# --- ground ------------------------------------------------------------------------------

@pytest.mark.parametrize("angle", [0.0, 15.0])
def test_resting_height_is_half_the_size_less_the_static_sink(angle):
    ground = Ground.tilted(angle)
    scene = Scene(ground=ground)
    normal = np.array(ground.normal)
    # released flat on the table, a hair above it, no spin
    tilt = axis_angle([0, 1, 0], np.radians(angle))
    start = State.release(scene, normal * (scene.die.size / 2 + 1e-4), [0, 0, 0],
                          orientation=tilt)
    res = simulate(scene, start, t_max=2.0)
    assert res.settled[0] and res.face[0] == 1
    sink = scene.die.mass * scene.gravity * np.cos(np.radians(angle)) / (4 * ground.stiffness)
    height = res.final.position[0] @ normal
    assert height == pytest.approx(scene.die.size / 2 - sink, abs=1e-3 * sink)


def _flat_on(angle: float, scene: Scene) -> State:
    """A still die resting flat (at its static sink) on a table tilted by ``angle`` degrees."""
    normal = np.array(scene.ground.normal)
    sink = scene.die.mass * scene.gravity * np.cos(np.radians(angle)) / (
        4 * scene.ground.stiffness)
    return State.release(scene, normal * (scene.die.size / 2 - sink), [0, 0, 0],
                         orientation=axis_angle([0, 1, 0], np.radians(angle)))


def test_stick_slip_holds_a_die_on_a_slope_the_listing_friction_lets_creep():
    # 15 degrees: tan 15 = 0.27 < mu = 0.4, so Coulomb friction holds the die
    held = Scene(ground=Ground.tilted(15.0))
    moved = simulate(held, _flat_on(15.0, held), t_max=1.0, until="t_max")
    assert np.linalg.norm(moved.final.position - _flat_on(15.0, held).position) < 1e-6
    assert np.linalg.norm(moved.final.velocity) < 1e-9
    creeping = held.with_(friction_law=FrictionLaw.REGULARIZED, friction_vmin=0.05)
    crept = simulate(creeping, _flat_on(15.0, creeping), t_max=1.0, until="t_max")
    assert np.linalg.norm(crept.final.velocity) > 0.05


@pytest.mark.parametrize("law", list(FrictionLaw))
def test_a_die_slides_down_a_steep_slope_at_coulombs_acceleration(law):
    # 30 degrees: tan 30 = 0.58 > mu, so it slides with a = g (sin - mu cos)
    scene = Scene(ground=Ground.tilted(30.0), friction_law=law)
    moved = simulate(scene, _flat_on(30.0, scene), t_max=1.0, until="t_max")
    a = np.radians(30.0)
    expected = scene.gravity * (np.sin(a) - scene.ground.friction * np.cos(a))
    assert np.linalg.norm(moved.final.velocity) == pytest.approx(expected, rel=2e-3)


def test_a_die_pausing_on_an_edge_is_not_at_rest():
    # balanced on an edge (centre straight above it) a die is quiet for a while, then falls
    scene = Scene()
    tilt = axis_angle([1, 0, 0], np.pi / 4)
    start = State.release(scene, [0, 0, scene.die.size / 2 * np.sqrt(2) - 2e-6], [0, 0, 0],
                          orientation=tilt, angular_velocity=[1e-3, 0, 0])
    res = simulate(scene, start, t_max=3.0)
    assert res.settled[0]
    assert res.final.position[0, 2] == pytest.approx(scene.die.size / 2, abs=1e-4)
    assert res.rest_time[0] > 0.1


def test_frictionless_die_keeps_sliding():
    scene = Scene(ground=Ground(friction=0.0), rotation=False)
    start = State.release(scene, [0, 0, scene.die.size / 2 + 0.01], [0.7, -0.2, 0])
    res = simulate(scene, start, t_max=3.0)
    np.testing.assert_array_equal(res.final.velocity[0, :2], [0.7, -0.2])
    assert not res.settled[0]


def test_undamped_ground_never_settles():
    scene = Scene(ground=Ground(damping=0.0), rotation=False)
    start = State.release(scene, [0, 0, scene.die.size / 2 + 0.01], [0.0, 0, 0])
    res = simulate(scene, start, t_max=3.0, record_every=100)
    assert not res.settled[0]
    # it keeps bouncing back to (nearly) its release height
    assert res.x_cm[0, -len(res.t) // 3:, 2].max() > scene.die.size / 2 + 0.009


def test_energy_never_rises_beyond_tolerance_at_the_automatic_step():
    scene = Scene()
    res = simulate(scene, random_throws(scene, 64, seed=7), t_max=3.0)
    assert np.isfinite(res.energy_rise).all()
    assert res.energy_rise.max() < 1.0  # in units of scene.energy_tol * (KE0 + m g edge)
    assert not res.unstable.any()
    assert res.settled.mean() > 0.9


def test_contact_laws_differ_only_for_corners_above_ground():
    die = Die.paper()
    fall = {"t_max": 0.3, "until": "t_max"}
    results = [
        simulate(Scene(die=die, ground=Ground(stiffness=1e4, damping=0.0, friction=0.1,
                                              contact_law=law), gravity=9.8, dt=1e-4),
                 State.release(Scene(die=die), [0, 0, 3.0], [1.0, 0, -1.0], [0.3, 0.2, 0.1]),
                 **fall)
        for law in ContactLaw
    ]
    np.testing.assert_array_equal(results[0].final.position, results[1].final.position)


# --- step size and stability ----------------------------------------------------------------

def test_effective_mass_and_critical_step():
    scene = Scene()
    # sticking friction's tangential springs (2/7 S) couple sliding with rocking: m/8
    assert scene.effective_mass == pytest.approx(scene.die.mass / 8, rel=1e-12)
    for without_springs in (scene.with_(friction_law=FrictionLaw.REGULARIZED),
                            scene.with_(ground=Ground(friction=0.0))):
        assert without_springs.effective_mass == pytest.approx(scene.die.mass / 6, rel=1e-12)
    assert Scene(rotation=False).effective_mass == pytest.approx(scene.die.mass / 4)
    s, d, m = scene.ground.stiffness, scene.ground.damping, scene.die.mass / 8
    assert scene.critical_dt == pytest.approx(2 * (np.sqrt(d * d + s * m) - d) / s)  # midpoint
    paper = scene.with_(scheme=Scheme.PAPER)
    assert paper.critical_dt == pytest.approx((np.sqrt(d * d + 4 * s * m) - d) / s)
    assert scene.step == pytest.approx(scene.safety * scene.critical_dt)


@pytest.mark.parametrize("scheme", list(Scheme))
@pytest.mark.parametrize(("factor", "blows_up"), [(0.95, False), (1.05, True)])
def test_critical_step_by_experiment(factor, blows_up, scheme):
    # a die resting on its four corners, pressed in to 1.5x its static sink: a linear oscillator
    # (light damping: with the table's D = 6.4 the clip at zero force bounds the growth at 1.05x)
    base = Scene(rotation=False, ground=Ground(friction=0.0, damping=0.4), scheme=scheme)
    scene = base.with_(dt=factor * base.critical_dt, allow_unstable=True)
    sink = scene.die.mass * scene.gravity / (4 * scene.ground.stiffness)
    start = State.release(scene, [0, 0, scene.die.size / 2 - 1.5 * sink], [0, 0, 0])
    res = simulate(scene, start, t_max=0.2, until="t_max")
    assert bool(res.unstable[0]) is blows_up
    assert bool(res.max_penetration[0] > 100 * sink) is blows_up


def test_step_above_critical_needs_opt_in():
    base = Scene()
    with pytest.raises(ValueError, match="dt must be <= the critical step"):
        base.with_(dt=1.01 * base.critical_dt)
    assert base.with_(dt=1.01 * base.critical_dt, allow_unstable=True).step > base.critical_dt


# --- loaded die -----------------------------------------------------------------------------

def test_loaded_die_mass_distribution():
    die = Die.loaded(face=6, fraction=0.2, depth=0.8)
    assert die.com[2] == pytest.approx(-0.2 * 0.8 * die.size / 2)
    assert not die.is_fair
    inertia = die.inertia_body
    assert inertia[0, 0] == pytest.approx(inertia[1, 1]) and inertia[2, 2] < inertia[0, 0] * 1.01
    nodes = Die.from_node_masses(np.full(8, 0.0045 / 8))
    np.testing.assert_allclose(nodes.inertia_body, np.eye(3) * 0.0045 * 0.016**2 / 2)


def test_heavily_loaded_die_shows_its_light_face():
    scene = Scene(die=Die.loaded(face=6, fraction=0.5, depth=0.9))
    res = simulate(scene, random_throws(scene, 96, seed=11, height=0.08), t_max=4.0)
    assert res.settled.mean() > 0.9
    assert np.mean(res.face[res.settled] == 1) > 0.4


# --- determinism ---------------------------------------------------------------------------

def test_batched_equals_single_and_threads_do_not_matter():
    scene = Scene()
    throws = random_throws(scene, 6, seed=5)
    batched = simulate(scene, throws, t_max=1.0, num_threads=2)
    one_thread = simulate(scene, throws, t_max=1.0, num_threads=1)
    for name in ("position", "velocity", "angular_momentum", "orientation"):
        np.testing.assert_array_equal(getattr(batched.final, name),
                                      getattr(one_thread.final, name))
    for i in range(throws.batch_size):
        single = State(*(a[i:i + 1] for a in throws._arrays()))
        res = simulate(scene, single, t_max=1.0)
        np.testing.assert_array_equal(res.final.orientation[0], batched.final.orientation[i])
        np.testing.assert_array_equal(res.final.position[0], batched.final.position[i])
        assert res.rest_time[0] == batched.rest_time[i]
        assert res.impacts[0] == batched.impacts[i]


def test_outcome_record():
    scene = Scene()
    res = simulate(scene, random_throws(scene, 8, seed=2), t_max=3.0)
    assert res.face.shape == (8,) and set(res.face) <= set(range(1, 7))
    assert res.settled.dtype == bool and res.unstable.dtype == bool
    assert (res.impacts >= 1).all()
    assert np.all(res.rest_time[res.settled] < 3.0) and np.all(res.rest_time >= 0)
    assert np.isfinite(res.final.position).all()
    assert np.all(res.max_penetration < 0.03 * scene.die.size * 3)


# --- bad input -----------------------------------------------------------------------------

@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: Die(edge=0.0), "edge must be a finite number > 0"),
        (lambda: Die(mass=-1.0), "mass must be a finite number > 0"),
        (lambda: Die(mass=float("nan")), "mass"),
        (lambda: Ground(stiffness=0.0), "stiffness must be a finite number > 0"),
        (lambda: Ground(damping=-0.1), "damping must be a finite number >= 0"),
        (lambda: Ground(friction=-0.1), "friction must be a finite number >= 0"),
        (lambda: Ground(normal=(0, 0, 0)), "normal must be a non-zero vector"),
        (lambda: Ground(normal=(0, 0)), r"normal must have shape \(3,\)"),
        (lambda: Ground(normal=(0, float("inf"), 1)), "normal must be finite"),
        (lambda: Die.loaded(fraction=1.5), r"fraction must be in \[0.0, 1.0\)"),
        (lambda: Scene(safety=2.0), "safety must be in"),
        (lambda: State.release(Scene(), [0, 0, np.nan], [0, 0, 0]), "position must be finite"),
        (lambda: State.release(Scene(), [0, 0, 1], [0, 0]), "velocity must have shape"),
        (lambda: State.release(Scene(), [0, 0, 1], [0, 0, 0], orientation=2 * np.eye(3)),
         "orientation must be rotation matrices"),
        (lambda: simulate(Scene(), State.release(Scene(), [0, 0, 1], [0, 0, 0]), t_max=-1),
         "t_max must be a finite number > 0"),
    ],
)
def test_bad_input_names_the_parameter(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_rotation_vectors_invert_axis_angle():
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(50, 3))
    angles = rng.uniform(0.0, np.pi, 50)
    rot = np.stack([axis_angle(a, t) for a, t in zip(axes, angles, strict=True)])
    vectors = matrix_to_rotation_vector(rot)
    assert np.allclose(np.linalg.norm(vectors, axis=1), angles, atol=1e-12)
    assert np.allclose(vectors / angles[:, None], axes / np.linalg.norm(axes, axis=1)[:, None],
                       atol=1e-9)
    assert np.array_equal(matrix_to_rotation_vector(np.eye(3)), np.zeros(3))


def test_rotation_vectors_become_the_rotations_they_name():
    rng = np.random.default_rng(4)
    rot = random_rotations(rng, 50)
    vectors = matrix_to_rotation_vector(rot)
    assert np.allclose(rotation_vector_to_matrix(vectors), rot, atol=1e-12)
    assert np.allclose(rotation_vector_to_matrix(vectors.reshape(5, 10, 3)),
                       rot.reshape(5, 10, 3, 3), atol=1e-12)
    assert np.array_equal(rotation_vector_to_matrix(np.zeros(3)), np.eye(3))

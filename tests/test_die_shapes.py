"""Dice of every shape: mass properties, numbering, reading, tipping heights, bad input."""

import math

import numpy as np
import pytest

import dice_env
from dice_env.model import die as die_module
from dice_env.model import polyhedra
from dice_env.model.die import STANDARD_SIZES, Die
from dice_env.model.rotations import axis_angle, random_rotations

PHI = (1 + math.sqrt(5)) / 2
# The d6 as stated in dice_env/model/die.py: corner signs in the order of the paper's cube.m,
# outward normals of faces 1-6 (opposite faces sum to 7, 1-2-3 counter-clockwise).
CUBE_CORNERS = np.array([[1, 1, 1], [1, -1, 1], [-1, -1, 1], [-1, 1, 1],
                         [1, 1, -1], [1, -1, -1], [-1, -1, -1], [-1, 1, -1]], dtype=np.float64)
CUBE_NORMALS = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0], [0, -1, 0], [-1, 0, 0], [0, 0, -1]],
                        dtype=np.float64)
# Platonic solids: generator, volume / a^3, isotropic moment I / (m a^2) (a: the edge)
PLATONIC = {
    "d4": (polyhedra.tetrahedron, 1 / (6 * math.sqrt(2)), 1 / 20),
    "d6": (lambda: CUBE_CORNERS, 1.0, 1 / 6),
    "d8": (polyhedra.octahedron, math.sqrt(2) / 3, 1 / 10),
    "d12": (polyhedra.dodecahedron, (15 + 7 * math.sqrt(5)) / 4, (95 + 39 * math.sqrt(5)) / 300),
    "d20": (polyhedra.icosahedron, 5 * (3 + math.sqrt(5)) / 12, (3 + math.sqrt(5)) / 20),
}
# Today's cube: tipping heights of the arc sampling this module generalises (4001 points).
CUBE_TIPPING = {
    "fair": (Die(), [0.01131125900924198] * 6),
    "loaded": (Die.loaded(face=6, fraction=0.3), [0.009953403554295623] * 5
               + [0.012668693594051966]),
    "nodes": (Die.from_node_masses(np.arange(1, 9) * 1e-3),
              [0.007539445701884979, 0.007539445701884979, 0.008796524423994397,
               0.008796524423994397, 0.010053603146103814, 0.012567760590322651]),
}


def edge_length(vertices: np.ndarray) -> float:
    gaps = np.linalg.norm(vertices[:, None] - vertices[None], axis=-1)
    return float(gaps[gaps > 0].min())


def bring(direction: np.ndarray, target: np.ndarray, spin: float = 0.0) -> np.ndarray:
    """A rotation taking ``direction`` to ``target``, then turning by ``spin`` about ``target``."""
    axis = np.cross(direction, target)
    if np.linalg.norm(axis) < 1e-12:
        axis = np.cross(direction, [1.0, 0.0, 0.0] if abs(direction[0]) < 0.9 else [0, 1.0, 0])
    angle = math.acos(np.clip(direction @ target, -1, 1))
    return axis_angle(target, spin) @ axis_angle(axis, angle)


def reading(die: Die) -> np.ndarray:
    return -die.face_normals if die.reads_down else die.face_normals


def sampled_tipping(die: Die, n: int = 50_000, seed: int = 0) -> np.ndarray:
    """Brute force: random up directions moved onto the tie of their two top faces."""
    rng = np.random.default_rng(seed)
    a, corners = reading(die), die.vertices_body
    up = rng.normal(size=(n, 3))
    top = np.argsort(-(up @ a.T), axis=1)[:, :2]
    d = a[top[:, 0]] - a[top[:, 1]]
    up -= (np.einsum("ni,ni->n", up, d) / np.einsum("ni,ni->n", d, d))[:, None] * d
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    score = up @ a.T
    rows = np.arange(n)
    tie = score[rows, top[:, 0]] >= score.max(axis=1) - 1e-12
    height = (-(up @ corners.T)).max(axis=1)
    out = np.full(die.n_faces, np.inf)
    for column in (0, 1):
        np.minimum.at(out, top[tie, column], height[tie])
    return out


# --- mass properties --------------------------------------------------------------------

@pytest.mark.parametrize("name", PLATONIC)
def test_platonic_mass_properties_match_the_closed_forms(name):
    make, volume_k, inertia_k = PLATONIC[name]
    points = 0.37 * make() + [0.1, -0.2, 0.3]  # any scale and place
    a = edge_length(points)
    volume, centroid, per_mass = polyhedra.mass_properties(points, polyhedra.convex_faces(points))
    assert volume == pytest.approx(volume_k * a**3, rel=1e-12)
    np.testing.assert_allclose(centroid, [0.1, -0.2, 0.3], atol=1e-14)
    np.testing.assert_allclose(per_mass, inertia_k * a * a * np.eye(3), rtol=0, atol=1e-14 * a * a)
    die = Die.standard(name, size=0.02, mass=0.003)
    a = edge_length(np.array(die.vertices))
    assert die.volume == pytest.approx(volume_k * a**3, rel=1e-12)
    assert die.is_isotropic  # exactly: ω = L / I in the kernel
    assert die.inertia_body[0, 0] == pytest.approx(inertia_k * 0.003 * a * a, rel=1e-12)


def test_cuboid_mass_properties_match_the_closed_form():
    x, y, z = 0.01, 0.02, 0.035
    die = Die.cuboid((x, y, z), mass=0.004)
    expected = 0.004 / 12 * np.diag([y * y + z * z, x * x + z * z, x * x + y * y])
    np.testing.assert_allclose(die.inertia_body, expected, rtol=1e-12, atol=0)
    assert die.volume == pytest.approx(x * y * z, rel=1e-12)
    assert die.size == x and die.name == "cuboid" and not die.is_fair
    np.testing.assert_array_equal(die.face_normals, CUBE_NORMALS)  # numbered like the d6
    np.testing.assert_array_equal(die.vertices, CUBE_CORNERS * [x / 2, y / 2, z / 2])
    np.testing.assert_allclose(die.resting_heights, [z / 2, x / 2, y / 2, y / 2, x / 2, z / 2])
    assert Die.cuboid((x, y, z)).mass == pytest.approx(Die().mass * x * y * z / 0.016**3)


def test_the_d10_is_axisymmetric_and_its_default_mass_follows_the_density():
    die = Die.standard("d10")
    inertia = die.inertia_body
    assert inertia[0, 0] == pytest.approx(inertia[1, 1], rel=1e-12)
    np.testing.assert_array_equal(inertia - np.diag(np.diag(inertia)), 0)
    assert die.is_fair and not die.is_isotropic
    for name in STANDARD_SIZES:
        d = Die.standard(name)
        assert d.size == STANDARD_SIZES[name]
        assert d.mass == pytest.approx(4.5e-3 * d.volume / 0.016**3, rel=1e-12)


# --- the d6 of today --------------------------------------------------------------------

def test_standard_d6_is_the_default_die_bit_for_bit():
    assert Die.standard("d6") == Die() and hash(Die.standard("d6")) == hash(Die())
    assert Die.standard("d6", size=0.02, mass=0.01) == Die(edge=0.02, mass=0.01)
    assert Die.cuboid((0.02, 0.02, 0.02), mass=0.01) == Die(edge=0.02, mass=0.01)
    die = Die()
    np.testing.assert_array_equal(die.vertices_body, CUBE_CORNERS * 0.008)
    np.testing.assert_array_equal(die.face_normals, CUBE_NORMALS)
    np.testing.assert_array_equal(die.inertia_body, np.eye(3) * (0.0045 * 0.016 * 0.016 / 6.0))
    assert die.labels.tolist() == [1, 2, 3, 4, 5, 6] and not die.reads_down
    assert die.size == 0.016 and die.resting_heights.tolist() == [0.008] * 6


@pytest.mark.parametrize("case", CUBE_TIPPING)
def test_cube_tipping_heights_are_todays(case):
    die, today = CUBE_TIPPING[case]
    # the arcs are now sampled evenly in angle: a slightly tighter bound, 4e-8 of today's
    np.testing.assert_allclose(die.tipping_heights, today, rtol=5e-8)
    assert (die.tipping_heights >= np.array(today)).all()
    assert (Die().tipping_heights <= math.sqrt(2) * 0.008).all()


# --- numbering and reading --------------------------------------------------------------

@pytest.mark.parametrize(("name", "n"), [("d4", 4), ("d6", 6), ("d8", 8), ("d10", 10),
                                         ("d12", 12), ("d20", 20)])
def test_standard_dice_faces_labels_and_opposite_sums(name, n):
    die = Die.standard(name)
    assert die.n_faces == n and die.labels.tolist() == list(range(1, n + 1))
    assert len(die.vertices) - len(die.edges) + n == 2  # Euler
    normals = die.face_normals
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1, rtol=1e-15)
    if name == "d4":
        assert die.reads_down
        # face k lies opposite corner k
        np.testing.assert_allclose(normals @ np.array(die.vertices).T,
                                   np.where(np.eye(4, dtype=bool), -3, 1) * die.size / 4,
                                   atol=1e-15)
        return
    assert not die.reads_down
    opposite = np.argmin(normals @ normals.T, axis=1)
    np.testing.assert_allclose(normals[opposite], -normals, atol=1e-14)
    assert set(die.labels + die.labels[opposite]) == {n + 1}


def test_d10_and_d8_put_the_odd_labels_around_the_upper_apex():
    d10 = Die.standard("d10")
    up = np.flatnonzero(d10.face_normals[:, 2] > 0) + 1
    assert sorted(up) == [1, 3, 5, 7, 9]
    azimuth = np.mod(np.arctan2(d10.face_normals[:, 1], d10.face_normals[:, 0]) + 1e-9, 2 * np.pi)
    digits = np.argsort(azimuth)  # label - 1 going counter-clockwise from azimuth 0
    assert digits.tolist() == [0, 7, 4, 1, 6, 9, 2, 5, 8, 3]
    d8 = Die.standard("d8")
    assert sorted(np.flatnonzero(d8.face_normals[:, 2] > 0) + 1) == [1, 3, 5, 7]


@pytest.mark.parametrize("name", list(STANDARD_SIZES))
def test_each_face_brought_up_reads_its_label(name):
    die = Die.standard(name)
    up = np.array([0.0, 0.0, 1.0])
    target = -up if die.reads_down else up  # the d4 is read by the face down
    rng = np.random.default_rng(1)
    orientations = np.array([bring(n, target, rng.uniform(0, 2 * np.pi))
                             for n in die.face_normals])
    assert die.face_read(orientations, up).tolist() == die.labels.tolist()
    # tilted 0.2 rad away: still the same face (every face's neighbours lie further)
    tilt = axis_angle([1.0, 0.3, 0.0], 0.2)
    assert die.face_read(tilt @ orientations, up).tolist() == die.labels.tolist()


def test_d4_reads_the_corner_up():
    die = Die.standard("d4")
    corners = np.array(die.vertices)
    up = np.array([0.0, 0.0, 1.0])
    orientations = np.array([bring(c / np.linalg.norm(c), up, 0.7) for c in corners])
    assert die.face_read(orientations, up).tolist() == [1, 2, 3, 4]


def test_the_d6_reads_the_face_most_along_up():
    q = random_rotations(np.random.default_rng(4), 500)
    up = np.array([0.1, -0.2, 1.0]) / np.linalg.norm([0.1, -0.2, 1.0])
    expected = np.argmax(np.einsum("nij,fj,i->nf", q, CUBE_NORMALS, up), axis=1) + 1
    np.testing.assert_array_equal(Die().face_read(q, up), expected)


# --- resting and tipping ----------------------------------------------------------------

@pytest.mark.parametrize("name", PLATONIC)
def test_platonic_resting_and_tipping_heights(name):
    die = Die.standard(name)
    # lying on a face: the inradius (size/2, the d4's size/4); tipping: balanced on an edge,
    # the midradius
    inradius = die.size / (4 if name == "d4" else 2)
    np.testing.assert_allclose(die.resting_heights, inradius, rtol=1e-12)
    corners = np.array(die.vertices)
    edges = die.edges
    midradius = np.linalg.norm((corners[edges[:, 0]] + corners[edges[:, 1]]) / 2, axis=1).min()
    assert (die.tipping_heights <= midradius).all()
    np.testing.assert_allclose(die.tipping_heights, midradius, rtol=1e-3)


@pytest.mark.parametrize("die", [
    Die.standard("d4"), Die.standard("d8"), Die.standard("d10"), Die.standard("d12"),
    Die.standard("d20"), Die.standard("d20").load(face=20, fraction=0.3),
    Die.standard("d4").load(face=2, fraction=0.4, depth=0.6),
    Die.cuboid((0.01, 0.016, 0.027)).load(face=3, fraction=0.2),
], ids=["d4", "d8", "d10", "d12", "d20", "d20-loaded", "d4-loaded", "cuboid-loaded"])
def test_tipping_heights_bound_a_brute_force_minimum(die):
    sampled = sampled_tipping(die)
    bound = die.tipping_heights
    assert np.isfinite(sampled).all()
    assert (bound <= sampled).all()
    np.testing.assert_allclose(bound, sampled, rtol=0.01)


# --- loaded dice --------------------------------------------------------------------------

@pytest.mark.parametrize("name", list(STANDARD_SIZES))
def test_every_shape_loads_toward_a_face(name):
    fair = Die.standard(name)
    face = fair.n_faces  # the highest label
    die = fair.load(face=face, fraction=0.2, depth=0.5)
    assert die.mass == fair.mass and die.vertices == fair.vertices and not die.is_fair
    distance = np.array(fair.vertices)[fair.faces[face - 1][0]] @ fair.face_normals[face - 1]
    np.testing.assert_allclose(die.com, 0.2 * 0.5 * distance * fair.face_normals[face - 1],
                               atol=1e-18)
    assert np.all(np.linalg.eigvalsh(die.inertia_body) > 0)
    # the heavy face lies low: the face read when it is down is read lowest (the d4: itself)
    low = face if die.reads_down else 1 + int(np.argmin(
        fair.face_normals @ fair.face_normals[face - 1]))
    assert np.argmin(die.resting_heights) + 1 == low


def test_loading_matches_a_point_weight_added_to_the_solid():
    die = Die.standard("d12", mass=0.004)
    loaded = die.load(face=5, fraction=0.25, depth=0.7)
    p = np.asarray(loaded.com) / 0.25
    # about the weight's own axis point: the solid's (0.75 m) plus the weight (0.25 m)
    about_origin = 0.75 * die.inertia_body + 0.25 * 0.004 * (p @ p * np.eye(3) - np.outer(p, p))
    c = np.asarray(loaded.com)
    np.testing.assert_allclose(loaded.inertia_body + 0.004 * (c @ c * np.eye(3) - np.outer(c, c)),
                               about_origin, rtol=1e-12)


# --- any convex vertex set -----------------------------------------------------------------

def test_from_vertices_builds_the_hull_and_centres_it():
    rng = np.random.default_rng(5)
    cube = CUBE_CORNERS * 0.008
    die = Die.from_vertices(cube[rng.permutation(8)] + [0.01, 0.0, -0.02])
    assert die.n_faces == 6 and die.size == pytest.approx(0.016)
    np.testing.assert_allclose(np.array(die.vertices).mean(axis=0), 0, atol=1e-17)
    np.testing.assert_allclose(die.inertia_body, Die().inertia_body, rtol=1e-12)
    assert die.mass == pytest.approx(Die().mass, rel=1e-12)
    # labels follow the hull's face order
    labels = [3, 1, 2, 6, 5, 4]
    relabelled = Die.from_vertices(cube, labels=labels)
    plain = Die.from_vertices(cube)
    np.testing.assert_array_equal(relabelled.face_normals[np.array(labels) - 1],
                                  plain.face_normals)
    # a triangular prism: two triangles and three rectangles merged from their triangles
    prism = Die.from_vertices([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]],
                              mass=1.0, reads_down=True)
    assert sorted(map(len, prism.faces)) == [3, 3, 4, 4, 4] and prism.reads_down
    assert prism.volume == pytest.approx(0.5)


@pytest.mark.parametrize("n", [4, 12, 40, polyhedra.MAX_VERTICES])
def test_hull_of_random_points_on_a_sphere_agrees_with_scipy(n):
    spatial = pytest.importorskip("scipy.spatial")
    rng = np.random.default_rng(n)
    points = rng.normal(size=(n, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    faces = polyhedra.convex_faces(points)
    reference = spatial.ConvexHull(points)
    assert sorted(map(sorted, faces)) == sorted(map(sorted, reference.simplices.tolist()))
    volume, centroid, _ = polyhedra.mass_properties(points, faces)
    assert volume == pytest.approx(reference.volume, rel=1e-12)
    normals = polyhedra.face_normals(points, faces)
    assert (np.einsum("fi,fi->f", normals, points[[f[0] for f in faces]] - centroid) > 0).all()


def test_dice_are_hashable_and_frozen():
    dice = {Die.standard(name): name for name in STANDARD_SIZES}
    assert dice[Die.standard("d20")] == "d20"
    assert Die.standard("d20") != Die.standard("d20", mass=0.001)
    with pytest.raises(AttributeError):
        Die().mass = 1.0
    assert repr(Die()) == "Die('d6', size=0.016, mass=0.0045)"


def test_no_cube_only_names():
    # every die is data: its size, vertices, edges, normals and reading, no d6-only aliases
    for name in ("edge", "half_edge", "corners_body"):
        assert not hasattr(Die(), name)
    for name in ("FACE_NORMALS", "CORNER_SIGNS", "EDGES", "face_up"):
        assert not hasattr(die_module, name) and not hasattr(dice_env, name)


# --- bad input ----------------------------------------------------------------------------

CUBE = CUBE_CORNERS.tolist()


@pytest.mark.parametrize(("make", "match"), [
    (lambda: Die.from_vertices([*CUBE, [0.1, 0.2, 0.3]]), r"vertices\[8\] lies inside the hull"),
    (lambda: Die.from_vertices([*CUBE, [0.0, 0.0, 1.0]]),
     r"vertices\[8\] lies on an edge or inside a face"),
    (lambda: Die.from_vertices([*CUBE, [1.0, 1.0, 0.0]]),
     r"vertices\[8\] lies on an edge or inside a face"),
    (lambda: Die.from_vertices([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 3, 0]]),
     "vertices must not all lie in one plane"),
    (lambda: Die.from_vertices([[0, 0, 0], [1, 0, 0], [0, 1, 0]]), "vertices must hold 4 to"),
    (lambda: Die.from_vertices(np.random.default_rng(0).normal(size=(65, 3))),
     "vertices must hold 4 to 64 points"),
    (lambda: Die.from_vertices([*CUBE, CUBE[3]]), r"vertices\[3\] and vertices\[8\] coincide"),
    (lambda: Die.from_vertices([[0, 0, 0], [1, 0, 0], [0, 1, np.nan], [0, 0, 1]]),
     "vertices must be finite"),
    (lambda: Die.from_vertices(np.zeros((4, 2))), r"vertices must have shape \(N, 3\)"),
    (lambda: Die.from_vertices(CUBE, labels=[1, 2, 3, 4, 5]), "labels must be a permutation"),
    (lambda: Die.from_vertices(CUBE, labels=[1, 2, 3, 4, 5, 5]), "labels must be a permutation"),
    (lambda: Die.from_vertices(CUBE, labels=[0, 1, 2, 3, 4, 5]), "labels must be a permutation"),
    (lambda: Die.from_vertices(CUBE, labels=[1.0, 2, 3, 4, 5, 6]),
     "labels must be a permutation"),
    (lambda: Die.from_vertices(CUBE, mass=0.0), "mass must be a finite number > 0"),
    (lambda: Die.from_vertices(CUBE, reads_down="yes"), "reads_down must be a bool"),
    (lambda: Die.standard("d7"), "name must be one of 'd4', 'd6'"),
    (lambda: Die.standard("d20", size=0.0), "size must be a finite number > 0"),
    (lambda: Die.standard("d20", size=-1.0), "size must be a finite number > 0"),
    (lambda: Die.standard("d12", mass=-1e-3), "mass must be a finite number > 0"),
    (lambda: Die.standard("d8", mass=np.inf), "mass must be a finite number > 0"),
    (lambda: Die.cuboid((0.01, 0.0, 0.02)), "sides must be three finite numbers > 0"),
    (lambda: Die.cuboid((0.01, 0.02)), "sides must be three finite numbers > 0"),
    (lambda: Die.cuboid((0.01, -0.02, 0.02)), "sides must be three finite numbers > 0"),
    (lambda: Die.standard("d20").load(face=21), r"face must be an int in \[1, 20\]"),
    (lambda: Die.standard("d4").load(face=0), r"face must be an int in \[1, 4\]"),
    (lambda: Die.standard("d10").load(face=3, fraction=1.0), "fraction must be in"),
    (lambda: Die.standard("d10").load(face=3, depth=-0.1), "depth must be in"),
    (lambda: Die(com=(0.0, 0.0, 0.008)), "com must lie inside the die"),
])
def test_bad_input_names_the_parameter(make, match):
    with pytest.raises(ValueError, match=match):
        make()

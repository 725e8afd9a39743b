"""Drilled pips: cap formulas, the layout, exact mass properties against quasi-Monte Carlo."""

import math

import numpy as np
import pytest
from scipy.stats import qmc

import studies
from dice_env.model.die import Die
from dice_env.model.pips import DRILLINGS, Pips, cap_properties, drill, layout

DRILLED = Pips(radius=1.5e-3, depth=1.0e-3)
SHALLOW = Pips(radius=2.0e-3, depth=0.4e-3, offset=0.6)


def uniform_inertia(die: Die) -> np.ndarray:
    return die.mass * die.size**2 / 6 * np.eye(3)


def test_no_pips_is_todays_die_bit_for_bit():
    assert Die.standard("d6", pips=None) == Die.standard("d6") == Die()
    assert Die.standard("d6", size=0.02, mass=0.01, pips=None) == Die.standard("d6", 0.02, 0.01)


def test_hemisphere_matches_the_textbook():
    r = 2.0
    volume, below, axial, transverse = cap_properties(r, r)
    assert volume == pytest.approx(2 * math.pi * r**3 / 3, rel=1e-14)
    assert below == pytest.approx(3 * r / 8, rel=1e-14)
    assert axial == pytest.approx(2 / 5 * volume * r * r, rel=1e-14)
    assert transverse == pytest.approx(83 / 320 * volume * r * r, rel=1e-14)


@pytest.mark.parametrize(("radius", "depth"), [(1.5, 1.0), (2.0, 0.1), (1.0, 1.0)])
def test_cap_against_quadrature_in_spherical_shells(radius, depth):
    """Shells of the sphere about its own centre, cut by the face: an independent slicing."""
    big = (radius**2 + depth**2) / (2 * depth)
    x, w = np.polynomial.legendre.leggauss(400)
    rho = (big - depth) + depth * (x + 1) / 2  # shells that reach below the face plane
    w = w * depth / 2
    # the shell of radius rho lies in the cap for polar cosine c >= (big - depth) / rho
    lo = (big - depth) / rho
    shell = 2 * math.pi * rho**2
    moments = [  # integrals over c in [lo, 1] of 1, c, c^2
        (1 - lo), (1 - lo**2) / 2, (1 - lo**3) / 3]
    volume = np.sum(w * shell * moments[0])
    z_mean = np.sum(w * shell * rho * moments[1]) / volume  # from the sphere's centre
    zz = np.sum(w * shell * rho**2 * moments[2])
    rr = np.sum(w * shell * rho**2 * moments[0])
    axial = rr - zz  # x^2 + y^2 = rho^2 (1 - c^2)
    transverse = axial / 2 + zz - volume * z_mean**2
    v, below, a, t = cap_properties(radius, depth)
    assert v == pytest.approx(volume, rel=1e-12)
    assert below == pytest.approx(z_mean - (big - depth), rel=1e-12)  # face at big - depth
    assert a == pytest.approx(axial, rel=1e-12)
    assert t == pytest.approx(transverse, rel=1e-10)


def test_layout_counts_handedness_and_symmetry():
    f = 0.5
    pips = layout(f)
    assert [len(p) for p in pips.values()] == [1, 2, 3, 4, 5, 6]
    die = Die.standard("d6")
    for label, points in pips.items():
        normal = die.face_normals[label - 1]
        np.testing.assert_array_equal(points @ normal, np.ones(len(points)))  # on the face
        np.testing.assert_allclose(points.mean(axis=0), normal)  # centred on the face
        if label > 1:  # central symmetry on the face: the pattern is its own reflection
            reflected = 2 * normal - points
            assert {tuple(p) for p in reflected} == {tuple(p) for p in points}
    # with 1 up, 2 left (+x), 3 right (+y): the 2 runs down from the left, the 3 up
    np.testing.assert_array_equal(pips[2], [[1, -f, f], [1, f, -f]])
    np.testing.assert_array_equal(pips[3][[0, 2]], [[f, 1, -f], [-f, 1, f]])
    corner = np.ones(3)  # the 1-2-3 corner: no pip of the 2 or the 3 points at it
    for label in (2, 3):
        assert np.all(np.abs(pips[label] - corner).max(axis=1) > 1 - f)


def qmc_drilled(die: Die, pips: Pips, replicates: int = 8, m: int = 18
                ) -> tuple[np.ndarray, np.ndarray]:
    """Scrambled-Sobol estimates of (com, inertia about it), one per replicate.

    Points fill the cube; a point is removed when it lies in a cavity, tested as 'in the
    sphere through the pip's rim and bottom, and inside the cube' (no cap formula used).
    """
    half = die.size / 2
    big = (pips.radius**2 + pips.depth**2) / (2 * pips.depth)
    centres = np.concatenate(list(layout(pips.offset).values()))
    normals = np.where(np.abs(centres) == 1.0, centres, 0.0)
    spheres = centres * half + (big - pips.depth) * normals
    coms, inertias = [], []
    for seed in range(replicates):
        points = (qmc.Sobol(3, scramble=True, seed=seed).random_base2(m) - 0.5) * die.size
        keep = np.ones(len(points), dtype=bool)
        for sphere in spheres:
            keep &= np.einsum("ni,ni->n", points - sphere, points - sphere) > big * big
        solid = points[keep]
        com = solid.mean(axis=0)
        rel = solid - com
        second = rel.T @ rel / len(solid)  # E[r r^T] about the com
        coms.append(com)
        inertias.append(die.mass * (np.trace(second) * np.eye(3) - second))
    return np.array(coms), np.array(inertias)


@pytest.mark.parametrize("pips", [DRILLED, SHALLOW])
def test_drilled_die_against_quasi_monte_carlo(pips):
    """2 million scrambled-Sobol points in 8 replicates; agreement within 5 standard errors.

    The standard error of the mean of 8 replicates is about 1.5e-7 m on the com (0.4 % of its
    z offset of 39 µm) and 2e-5 of the uniform moment on the inertia (the drilling changes the
    moments by about 7e-3 and the products by 7e-4).
    """
    die = Die.standard("d6", mass=0.0045, pips=pips)
    coms, inertias = qmc_drilled(die, pips)
    n = len(coms)
    scale = np.asarray(uniform_inertia(die))[0, 0]
    for exact, samples, floor in ((np.asarray(die.com), coms, 1e-10),
                                  (die.inertia_body, inertias, 1e-7 * scale)):
        mean = samples.mean(axis=0)
        error = samples.std(axis=0, ddof=1) / math.sqrt(n)
        assert np.all(np.abs(mean - exact) <= 5 * error + floor), (mean, exact, error)
    # the inertia really changed, by far more than the estimate's error
    assert np.abs(die.inertia_body - uniform_inertia(die)).max() > 1e-3 * scale


def test_com_moves_toward_the_one_two_three_corner_five_three_one():
    die = Die.standard("d6", pips="drilled16")
    com = np.asarray(die.com)
    assert com[2] > 0  # toward face 1 (+z), the face with fewest cavities
    np.testing.assert_allclose(com / com[2], [3 / 5, 1 / 5, 1.0], rtol=1e-12)
    volume, below, _, _ = cap_properties(DRILLED.radius, DRILLED.depth)
    expected_z = 5 * volume * (die.size / 2 - below) / (die.size**3 - 21 * volume)
    assert com[2] == pytest.approx(expected_z, rel=1e-12)


def test_paint_of_the_dies_own_density_is_the_uniform_die():
    size, mass = 0.019, 0.009
    paint = Pips(radius=2e-3, depth=1e-3, paint_density=mass / size**3)
    assert Die.standard("d6", size=size, mass=mass, pips=paint) == Die.standard("d6", size, mass)
    casino = Die.standard("d6", pips="casino19")
    assert not any(casino.com) and casino.is_fair


@pytest.mark.parametrize("fraction", [0.0, 0.25, 0.5, 0.9])
def test_paint_density_moves_the_com_proportionally(fraction):
    size, mass = 0.016, 0.0045
    drilled = Die.standard("d6", size=size, mass=mass, pips=DRILLED)
    paint = Pips(DRILLED.radius, DRILLED.depth, paint_density=fraction * mass / size**3)
    painted = Die.standard("d6", size=size, mass=mass, pips=paint)
    np.testing.assert_allclose(painted.com, (1 - fraction) * np.asarray(drilled.com),
                               rtol=1e-9, atol=1e-20)
    assert painted.mass == drilled.mass == mass


def test_presets_build_and_are_documented():
    for name, preset in DRILLINGS.items():
        die = Die.standard("d6", pips=name)
        assert die.size == (preset.size or 0.016)
        assert preset.source
    assert Die.standard("d6", pips="drilled16").mass == Die().mass
    casino = Die.standard("d6", pips="casino19")
    assert casino.size == pytest.approx(0.01905)


def test_drill_keeps_the_geometry():
    plain = Die.standard("d6")
    drilled = Die.standard("d6", pips=DRILLED)
    assert drilled.vertices == plain.vertices and drilled.faces == plain.faces
    assert drilled.mass == plain.mass
    com, inertia = drill(plain.size, plain.mass, DRILLED)
    assert drilled.com == tuple(com) and np.array_equal(drilled.inertia_body, inertia)


def test_paint_as_dense_as_the_body_leaves_the_uniform_die():
    plain = Die.standard("d6")
    body = plain.mass / plain.size**3
    assert drill(plain.size, plain.mass, Pips(DRILLED.radius, DRILLED.depth,
                                              paint_density=body)) is None
    assert Die.standard("d6", pips=Pips(DRILLED.radius, DRILLED.depth,
                                        paint_density=body)) == plain


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"name": "d8", "pips": DRILLED}, "d6 only"),
    ({"pips": "ivory"}, "pips must be one of"),
    ({"pips": 3}, "pips must be None"),
    ({"pips": Pips(radius=2.5e-3, depth=1e-3)}, "pips overlap"),
    ({"pips": Pips(radius=1.5e-3, depth=1e-3, offset=0.8)}, "face's edge"),
    ({"size": 0.016, "mass": 1e-6, "pips": Pips(1.5e-3, 1e-3, paint_density=2000.0)},
     "paint"),
])
def test_bad_pips_are_refused(kwargs, match):
    error = TypeError if kwargs.get("pips") == 3 else ValueError
    with pytest.raises(error, match=match):
        Die.standard(**kwargs)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"radius": 0.0, "depth": 1e-3}, "radius"),
    ({"radius": 1e-3, "depth": 2e-3}, "depth"),
    ({"radius": 1e-3, "depth": 0.0}, "depth"),
    ({"radius": 1e-3, "depth": 1e-3, "offset": 1.0}, "offset"),
    ({"radius": 1e-3, "depth": 1e-3, "offset": 0.0}, "offset"),
    ({"radius": 1e-3, "depth": 1e-3, "paint_density": -1.0}, "paint_density"),
    ({"radius": 1e-3, "depth": 1e-3, "shape": "cylinder"}, "shape"),
])
def test_bad_pips_fields_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Pips(**kwargs)


def test_page_is_written(tmp_path):
    numbers = studies.run("pips", tmp_path)
    text = (tmp_path / "pips.md").read_text()
    assert "python -m studies pips" in text
    assert 2e-3 < numbers["drilled16_com_over_edge"] < 4e-3
    for name in DRILLINGS:
        assert name in text

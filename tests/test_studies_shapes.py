"""Every standard die (fairness, loaded bias, free flight) and the square-cuboid prediction."""

import math

import numpy as np
import pytest

from dice_env import Die, Scene, throws
from studies import cuboids as cb
from studies import run as run_study
from studies import shapes as sh
from studies.__main__ import main as studies_main

FLIGHT = sh.flight_dice()


@pytest.mark.parametrize(("name", "face", "favoured"), [
    ("d4", 1, 1), ("d4", 3, 3), ("d6", 1, 6), ("d6", 2, 5), ("d8", 1, 8), ("d10", 1, 10),
    ("d10", 4, 7), ("d12", 1, 12), ("d20", 1, 20), ("d20", 20, 1)])
def test_favoured_face_is_the_face_read_with_the_weight_down(name, face, favoured):
    assert sh.favoured_face(Die.standard(name), face) == favoured


def test_hand_throws_are_the_same_hand_for_every_die():
    for name in ("d4", "d20"):
        scene = Scene(die=Die.standard(name))
        state = throws.hand_throws(scene, 300, np.random.default_rng(0))
        unit = 0.016  # the default d6's edge: the ranges are in its units for every die
        speed = np.linalg.norm(state.velocity, axis=1) / unit
        assert speed.min() >= 30 - 1e-9 and speed.max() <= 150 + 1e-9
        clearance = (state.position[:, 2] - throws.touching_height(scene, state.orientation)) / unit
        assert clearance.min() >= 5 - 1e-9 and clearance.max() <= 20 + 1e-9
        assert np.all(state.velocity[:, 2] <= 0)


@pytest.mark.parametrize("name", list(FLIGHT))
def test_free_flight_changes_momentum_by_gravity_alone_and_keeps_energy(name):
    die = FLIGHT[name]
    for step_by_step in (False, True):
        err = sh.free_flight(die, n=2, t=0.05, step_by_step=step_by_step)
        assert err["velocity"] < 1e-10
        assert err["momentum"] < 1e-12
        assert err["height"] < 1e-3
        # isotropic: exact up to rounding; otherwise the first-order rotation's small drift
        assert err["energy"] < (1e-10 if die.is_isotropic else 5e-4)


def test_rotational_energy_drift_is_first_order_in_the_step():
    die = FLIGHT["cuboid 8x16x24 mm"]
    coarse, fine = (sh.free_flight(die, n=2, t=0.1, safety=s)["rotation"] for s in (0.3, 0.15))
    assert 0 < fine < coarse
    assert coarse / fine == pytest.approx(2.0, rel=0.05)


def test_faces_of_a_small_batch_are_counted():
    scene = Scene(die=Die.standard("d20"))
    faces = throws.throw_faces(scene, throws.hand_throws(scene, 120, np.random.default_rng(1)),
                           batch=50)
    assert faces.ended + faces.undecided == 120 and faces.undecided == 0
    assert faces.counts.shape == (20,) and faces.counts.sum() == faces.ended
    assert 0.0 <= faces.p_value <= 1.0


@pytest.mark.parametrize(("name", "n"), [
    ("d6", 300), ("d12", 300),
    pytest.param("d4", 120, marks=pytest.mark.slow)])  # the light d4's tiny step: ~15 s
def test_loaded_die_shows_the_predicted_face_more(name, n):
    die = Die.standard(name).load(1, fraction=0.3, depth=0.9)
    scene = Scene(die=die)
    faces = throws.throw_faces(scene, throws.hand_throws(scene, n, np.random.default_rng(4)))
    favoured = sh.favoured_face(die, 1)
    assert faces.intervals[favoured - 1, 0] > 1 / die.n_faces
    assert int(np.argmax(faces.counts)) + 1 == favoured


def test_square_cuboid_keeps_the_volume_and_has_square_faces_one_and_six():
    for ratio in (0.45, 1.0, 2.7):
        die = cb.square_cuboid(ratio)
        assert die.volume == pytest.approx(0.016**3, rel=1e-12)
        assert die.mass == pytest.approx(0.0045, rel=1e-12)
        half = np.abs(np.asarray(die.vertices)).max(axis=0)
        assert half[0] == pytest.approx(half[1]) and half[2] / half[0] == pytest.approx(ratio)
        np.testing.assert_allclose(die.face_normals[0], [0, 0, 1], atol=1e-12)
        np.testing.assert_allclose(die.face_normals[5], [0, 0, -1], atol=1e-12)
    cube = cb.square_cuboid(1.0)
    assert cube.name == "d6" and cube.size == pytest.approx(0.016, rel=1e-12)
    with pytest.raises(ValueError, match="ratio"):
        cb.square_cuboid(0.0)


def test_solid_angle_reference():
    assert cb.solid_angle_share(1.0) == pytest.approx(1 / 3, rel=1e-12)
    shares = [cb.solid_angle_share(r) for r in cb.RATIOS]
    assert np.all(np.diff(shares) < 0)
    assert cb.solid_angle_share(1e-6) == pytest.approx(1.0, abs=1e-5)


def test_cuboids_quick_study(tmp_path):
    n = cb.run(tmp_path, quick=True)
    assert n["undecided"] == 0
    assert n["cube_lo"] <= 1 / 3 <= n["cube_hi"]
    assert n["p_0.45"] > 0.7 and n["p_2.7"] < 0.1
    text = (tmp_path / "cuboids.md").read_text()
    assert "prediction" in text and "inside" in text
    assert (tmp_path / "figures" / "cuboids.png").stat().st_size > 10_000


def test_sample_size_is_checked_where_given(tmp_path):
    with pytest.raises(ValueError, match="throws"):
        sh.run(tmp_path, throws=10)
    with pytest.raises(ValueError, match="throws"):
        cb.run(tmp_path, throws=2.5)
    with pytest.raises(ValueError, match="throws"):
        run_study("paper", tmp_path, throws=100)
    with pytest.raises(SystemExit):
        studies_main(["fairness", "--throws", "100", "--out", str(tmp_path)])


@pytest.mark.slow
def test_shapes_quick_study(tmp_path):
    n = sh.run(tmp_path, quick=True)
    for name in sh.DICE:
        assert n[f"{name}_undecided"] == 0
        assert n[f"{name}_p"] > 1e-3
        assert n[f"{name}_loaded_excess"] > 0
    assert n["flight_velocity"] < 1e-10 and n["flight_momentum"] < 1e-12
    assert math.isfinite(n["flight_energy"])
    text = (tmp_path / "shapes.md").read_text()
    assert "Chi-square" in text and "Free flight" in text
    assert (tmp_path / "figures" / "shapes_faces.png").stat().st_size > 10_000

"""Throw generators, intervals and the fairness study at reduced size."""

import numpy as np
import pytest

from dice_env import Die, Scene, throws
from dice_env.intervals import wilson
from studies import fairness as fz


def test_wilson_interval_known_value():
    lo, hi = wilson(50, 100)
    assert lo == pytest.approx(0.4038, abs=1e-4) and hi == pytest.approx(0.5962, abs=1e-4)
    lo, hi = wilson(0, 240)
    assert lo == 0.0 and 0 < hi < 0.02
    both = wilson([0, 240, 7], [240, 240, 0])  # batched; no throws: (0, 1)
    assert both.shape == (3, 2) and both[1, 1] == 1.0 and both[2].tolist() == [0.0, 1.0]
    k = np.arange(11)  # every interval holds its proportion and lies in [0, 1]
    low, high = wilson(k, 10).T
    assert np.all((0 <= low) & (low <= k / 10) & (k / 10 <= high) & (high <= 1))


def test_face_down_is_opposite_the_face_read():
    q = throws.random_orientations(np.random.default_rng(0), 500)
    normal = np.array([0.0, 0.0, 1.0])
    die = Die()
    np.testing.assert_array_equal(fz.face_down(die, q, normal), 7 - die.face_read(q, normal))


def test_energy_throws_carry_the_requested_energy():
    scene = Scene()
    rng = np.random.default_rng(1)
    excess = np.array([0.0, 0.1, 1.0, 10.0, 100.0])
    state = throws.energy_throws(scene, excess, rng)
    base = throws.touching_height(scene, state.orientation) - scene.die.size / 2
    expected = excess + base / scene.die.size
    np.testing.assert_allclose(fz.throw_energy(scene, state), expected, rtol=1e-9, atol=1e-12)
    # lowest corner exactly on the plane for the gentle release
    corners = state.position[0][:, None] + state.orientation[0] @ scene.die.vertices_body.T
    assert corners[2].min() == pytest.approx(0.0, abs=1e-12)
    assert np.all(state.velocity[:, 2] <= 0)


def test_vigorous_throws_respect_their_ranges():
    scene = Scene()
    state = throws.vigorous_throws(scene, 400, np.random.default_rng(2))
    a = scene.die.size
    speed = np.linalg.norm(state.velocity, axis=1) / a
    assert speed.min() >= 30 - 1e-9 and speed.max() <= 150 + 1e-9
    assert np.all(state.velocity[:, 2] <= 0)
    clearance = (state.position[:, 2] - throws.touching_height(scene, state.orientation)) / a
    assert clearance.min() >= 5 - 1e-9 and clearance.max() <= 20 + 1e-9
    spin = np.linalg.norm(state.angular_velocity, axis=1)
    assert spin.min() >= 10 - 1e-9 and spin.max() <= 100 + 1e-9


def test_quick_study(tmp_path):
    n = fz.run(tmp_path, quick=True)
    assert n["fair_unsettled"] < 0.01 and n["loaded_unsettled"] < 0.01
    assert n["fair_p"] > 1e-3
    assert n["loaded_p6"] > n["loaded_p1"]
    assert n["down_gentle"] > 0.8 and n["up_gentle"] < 0.02
    assert n["down_vigorous"] < 0.3
    text = (tmp_path / "fairness.md").read_text()
    assert "Chi-square" in text and "Kapitaniak" in text
    for name in ("fairness_faces", "fairness_memory_vs_energy"):
        assert (tmp_path / "figures" / f"{name}.png").stat().st_size > 10_000


@pytest.mark.slow
def test_full_fair_die_is_uniform(tmp_path):
    n = fz.run(tmp_path, quick=False)
    assert n["fair_throws"] >= 99_000
    assert n["fair_p"] > 1e-3
    assert n["loaded_p"] < 1e-6

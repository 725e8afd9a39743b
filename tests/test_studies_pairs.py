"""Two dice thrown together: the hand, the 2d6 reference, the tests of the study and its page."""

import json
from dataclasses import asdict

import numpy as np
import pytest

from dice_env import Die, Scene, throws
from dice_env.model.surroundings import tray
from dice_env.simulation.group import DieContact, simulate_group
from studies import collisions as co
from studies import craps as cr
from studies import pairs as pr
from studies import run as run_study


def pairs_of(table):
    table = np.asarray(table)
    n = len(table.ravel())
    return pr.Pairs(table=table, met=np.ones(n, bool), counted=np.ones(n, bool), voided={},
                    impacts=np.zeros((n, 2)), time=np.zeros(n), met_table=table)


def test_the_triangle_is_two_independent_fair_dice():
    p = pr.triangle()
    assert p.sum() == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_allclose(p, np.convolve(np.full(6, 1 / 6), np.full(6, 1 / 6)), atol=1e-15)
    assert p[0] == pytest.approx(1 / 36) and p[5] == pytest.approx(6 / 36)  # totals 2 and 7
    np.testing.assert_array_equal(pr.TOTALS, np.arange(2, 13))


def test_totals_are_summed_from_the_table():
    table = np.zeros((6, 6), np.int64)
    table[2, 3] = 5  # 3 + 4
    table[5, 5] = 2  # 6 + 6
    table[0, 0] = 1  # 1 + 1
    totals = pairs_of(table).totals
    assert totals.tolist() == [1, 0, 0, 0, 0, 5, 0, 0, 0, 0, 2]


def test_a_perfect_table_fits_the_triangle_and_is_uniform():
    pairs = pairs_of(np.full((6, 6), 50))
    assert pairs.total_test() == (pytest.approx(0.0, abs=1e-12), pytest.approx(1.0))
    assert pairs.uniformity(0)[1] == pytest.approx(1.0)
    assert pairs.uniformity(1)[1] == pytest.approx(1.0)


def test_independence_flags_a_dependent_table_and_passes_an_independent_one():
    rng = np.random.default_rng(0)
    die1 = rng.integers(0, 6, 3000)
    apart = rng.integers(0, 6, 3000)
    follows = np.where(rng.random(3000) < 0.1, die1, apart)  # die 2 copies die 1 one time in 10
    independent = np.bincount(die1 * 6 + apart, minlength=36).reshape(6, 6)
    dependent = np.bincount(die1 * 6 + follows, minlength=36).reshape(6, 6)
    _, p, dof = pr.independence(independent)
    assert dof == 25 and p > 0.05
    _, p_dependent, _ = pr.independence(dependent)
    assert p_dependent < 1e-6
    # each die alone is still uniform: only the pair test sees the dependence
    assert pairs_of(dependent).uniformity(1)[1] > 1e-3


def test_independence_leaves_out_empty_rows_and_refuses_a_single_row():
    table = np.zeros((6, 6), np.int64)
    table[1:3, :] = 20
    assert pr.independence(table) == (pytest.approx(0.0), pytest.approx(1.0), 5)
    with pytest.raises(ValueError, match="table must hold counts in at least two rows"):
        pr.independence(np.eye(6)[:1] * 10)


def test_the_hand_holds_the_dice_in_rows_apart_with_one_velocity():
    two = throws.layout(2, throws.HAND.spacing)
    np.testing.assert_allclose(two, [[0, -0.015, 0], [0, 0.015, 0]], atol=1e-15)
    twelve = throws.layout(12, throws.HAND.spacing)
    assert np.unique(twelve[:, 0]).size == 3 and np.unique(twelve[:, 1]).size == 4
    np.testing.assert_allclose(twelve.mean(axis=0), 0.0, atol=1e-15)
    scene = Scene(walls=tray())
    state = throws.group_throws(scene, (scene.die,) * 2, 400, np.random.default_rng(1))
    assert state.batch_size == 400 and state.n_dice == 2
    np.testing.assert_allclose(state.position[:, 1] - state.position[:, 0], [[0, 0.03, 0]] * 400,
                               atol=1e-12)
    spread = (state.velocity[:, 1] - state.velocity[:, 0]).std(axis=0)
    np.testing.assert_allclose(spread, np.sqrt(2) * throws.HAND.noise, rtol=0.15)
    assert not np.allclose(state.orientation[:, 0], state.orientation[:, 1])
    with pytest.raises(ValueError, match="n_dice"):
        throws.layout(0, throws.HAND.spacing)


def test_a_mixed_set_of_twelve_dice_leaves_the_hand_apart():
    scene = Scene(walls=tray(), t_max=0.002)
    dice = (Die(),) * 11 + (Die.standard("d20"),)
    state = throws.group_throws(scene, dice, 3, np.random.default_rng(2))
    simulate_group(scene, dice, state)  # refuses dice released overlapping


def test_quick_study_writes_its_page(tmp_path):
    n = pr.run(tmp_path, quick=True)
    assert n["throws"] == pr.QUICK and 0 < n["counted"] <= pr.QUICK
    assert 0.0 <= n["voided"] < 0.5 and n["met"] > 0.2  # the dice do meet
    assert 0.0 <= n["total_p"] <= 1.0 and 0.0 <= n["independence_p"] <= 1.0
    assert n["rate"] > 0 and n["seconds"] > 0
    text = (tmp_path / "pairs.md").read_text()
    assert f"--throws {pr.QUICK}" in text and "would take" in text
    assert "Independence" in text and "## Conclusion" in text and "nan" not in text
    assert (tmp_path / "figures" / "pairs.png").stat().st_size > 10_000


@pytest.mark.parametrize("name, least", [("pairs", pr.MIN_THROWS), ("collisions", co.MIN_THROWS),
                                         ("craps", cr.MIN_THROWS)])
@pytest.mark.parametrize("throws", [None, 0, 2.5, True, "100"])  # None: one below the least
def test_a_bad_sample_size_is_refused_before_any_work(tmp_path, name, least, throws):
    with pytest.raises(ValueError, match=f"throws must be an int >= {least}"):
        run_study(name, tmp_path, throws=least - 1 if throws is None else throws)
    assert not any(tmp_path.iterdir())


def test_chunks_kept_are_read_back_and_match_a_run_without_them(tmp_path):
    scene = throws.tray_scene()
    dice = (scene.die, scene.die)
    fresh, seconds, cpu = pr.chunked_pairs(scene, dice, 5, seed=5, chunk=3)
    assert seconds > 0 and cpu > 0 and len(fresh.counted) == 5
    kept, _, _ = pr.chunked_pairs(scene, dice, 5, seed=5, keep=tmp_path, chunk=3)
    assert sorted(p.name for p in tmp_path.glob("*.npz")) == [
        "pairs-5-00000-3.npz", "pairs-5-00001-2.npz"]
    (tmp_path / "pairs-5-00001-2.npz").unlink()  # a run stopped after its first chunk
    again, _, _ = pr.chunked_pairs(scene, dice, 5, seed=5, keep=tmp_path, chunk=3)
    for other in (kept, again):
        assert other.voided == fresh.voided and sum(fresh.voided.values()) >= 0
        for name, array in fresh.arrays().items():
            np.testing.assert_array_equal(other.arrays()[name], array, err_msg=name)
    spec = json.loads((tmp_path / "spec.json").read_text())
    assert spec["contact"] == json.loads(json.dumps(asdict(DieContact())))  # its friction law too
    (tmp_path / "spec.json").write_text(json.dumps(spec | {"contact": {"friction_law": 9}}))
    with pytest.raises(ValueError, match=r"keep=.*contact"):
        pr.chunked_pairs(scene, dice, 5, seed=5, keep=tmp_path, chunk=3)
    (tmp_path / "spec.json").write_text(json.dumps(spec))
    with pytest.raises(ValueError, match=r"keep=.*chunk 3 there, 2 asked"):
        pr.chunked_pairs(scene, dice, 5, seed=5, keep=tmp_path, chunk=2)


def test_joined_pairs_add_their_counts_and_keep_every_throw():
    rng = np.random.default_rng(3)
    parts = [pr.Pairs(table=rng.integers(0, 9, (6, 6)), met=rng.random(n) < 0.5,
                      counted=rng.random(n) < 0.9,
                      voided=dict(zip(pr.VOID_REASONS, rng.integers(0, 4, 4).tolist(),
                                      strict=True)),
                      impacts=rng.integers(0, 9, (n, 2)), time=rng.random(n),
                      met_table=rng.integers(0, 9, (6, 6))) for n in (4, 7)]
    joined = pr.Pairs.joined([p.arrays() for p in parts])
    np.testing.assert_array_equal(joined.table, parts[0].table + parts[1].table)
    np.testing.assert_array_equal(joined.met_table, parts[0].met_table + parts[1].met_table)
    np.testing.assert_array_equal(joined.time, np.concatenate([p.time for p in parts]))
    assert joined.impacts.shape == (11, 2) and joined.counted.dtype == bool
    assert joined.voided == {k: parts[0].voided[k] + parts[1].voided[k] for k in pr.VOID_REASONS}

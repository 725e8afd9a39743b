"""Weldon's dice (the comparison maths, the quick study) and the validation page."""

import json
import math
import shutil

import numpy as np
import pytest
from scipy import stats

from dice_env import Scene, throws
from studies import cuboids as cb
from studies import validation as va
from studies import weldon as wd
from studies.__main__ import main as studies_main

VERDICTS = {"agrees", "differs", "not resolvable at this sample"}


def test_weldons_numbers_are_his():
    assert sum(wd.WELDON_COUNTS) == 26_306
    assert wd.WELDON.n == 315_672
    assert round(wd.WELDON.p * wd.WELDON.n) == 106_602
    assert wd.WELDON.p == pytest.approx(0.3377, abs=5e-5)
    assert wd.WELDON.se == pytest.approx(0.0008, abs=5e-5)
    assert wd.EFFECT == pytest.approx(0.0044, abs=5e-5)


def test_binomial_reference():
    p = wd.binomial_probabilities(1 / 3)
    assert p.sum() == pytest.approx(1.0, abs=1e-12)
    assert p[0] == pytest.approx((2 / 3) ** 12, rel=1e-12)
    assert p[4] == pytest.approx(math.comb(12, 4) * (1 / 3) ** 4 * (2 / 3) ** 8, rel=1e-12)


def test_tails_are_pooled_until_every_cell_expects_five():
    groups = wd.pooled_cells(np.array([0.5, 1.0, 10.0, 20.0, 10.0, 2.0, 1.0]))
    assert groups == [range(0, 3), range(3, 4), range(4, 7)]
    assert wd.pooled_cells(np.array([1.0, 1.0])) == [range(0, 2)]  # one cell left


def test_goodness_of_fit_matches_scipy_on_the_pooled_cells():
    counts = np.array(wd.WELDON_COUNTS)
    fair = wd.binomial_probabilities(1 / 3)
    test = wd.chi2_fit(counts, fair)
    expected = counts.sum() * fair
    assert test.cells[-1] == (10, 12) and test.dof == 10  # 11 and 12 expect < 5 together
    pooled_obs = np.append(counts[:10], counts[10:].sum())
    pooled_exp = np.append(expected[:10], expected[10:].sum())
    reference = stats.chisquare(pooled_obs, pooled_exp)
    assert test.statistic == pytest.approx(reference.statistic, rel=1e-12)
    assert test.p_value == pytest.approx(reference.pvalue, rel=1e-9)
    assert test.p_value < 1e-3  # Weldon's dice are not fair dice
    assert wd.chi2_fit(counts, wd.binomial_probabilities(wd.WELDON.p)).p_value > 0.1
    exact = wd.chi2_fit(np.round(1000 * fair), np.round(1000 * fair) / np.round(1000 * fair)
                        .sum())
    assert exact.statistic == pytest.approx(0.0, abs=1e-12) and exact.p_value == 1.0


def test_homogeneity_matches_scipy_contingency():
    a = np.array([3, 10, 30, 40, 12, 4, 1])
    b = np.array([30, 120, 280, 390, 140, 30, 10])
    test = wd.chi2_homogeneity(a, b)
    pooled = np.array([[a[g[0]:g[1] + 1].sum() for g in test.cells],
                       [b[g[0]:g[1] + 1].sum() for g in test.cells]])
    reference = stats.chi2_contingency(pooled, correction=False)
    assert test.statistic == pytest.approx(reference.statistic, rel=1e-12)
    assert test.dof == reference.dof and test.p_value == pytest.approx(reference.pvalue)
    same = wd.chi2_homogeneity(a, 10 * a)
    assert same.statistic == pytest.approx(0.0, abs=1e-12)


def test_estimates_and_their_intervals():
    est = wd.Estimate.binomial(40, 100)
    assert est.se == pytest.approx(math.sqrt(0.4 * 0.6 / 100))
    lo, hi = est.interval
    assert hi - lo == pytest.approx(2 * 1.959964 * est.se)
    per = wd.Estimate.per_throw(np.array([4, 4, 4, 4]))
    assert per.p == pytest.approx(1 / 3) and per.se == 0.0 and per.n == 48
    spread = wd.Estimate.per_throw(np.array([2, 6]))
    assert spread.se == pytest.approx(np.std([2, 6], ddof=1) / (12 * math.sqrt(2)))
    with pytest.raises(ValueError, match="successes"):
        wd.Estimate.binomial(5, 4)
    with pytest.raises(ValueError, match="successes"):
        wd.Estimate.per_throw(np.array([3]))


def test_verdicts_on_constructed_estimates():
    weldon = wd.WELDON
    precise = wd.Estimate(weldon.p + 0.0005, 0.0005, 10**6)
    assert wd.compare(precise, weldon).verdict == "agrees"
    wide = wd.Estimate(weldon.p + 0.002, 0.01, 2000)
    assert wd.compare(wide, weldon).verdict == "not resolvable at this sample"
    far = wd.Estimate(0.36, 0.002, 50_000)
    result = wd.compare(far, weldon)
    assert result.verdict == "differs" and result.difference == pytest.approx(0.36 - weldon.p)
    assert wd.compare(wide, weldon).half_width == pytest.approx(
        1.959964 * math.hypot(0.01, weldon.se))


def test_trials_to_resolve_is_where_the_interval_meets_the_effect():
    n = wd.trials_to_resolve(1 / 3, wd.WELDON)
    half = lambda m: 1.959964 * math.hypot(math.sqrt(2 / 9 / m), wd.WELDON.se)  # noqa: E731
    assert half(n) < wd.EFFECT <= half(n - 1)
    assert 40_000 < n < 70_000
    assert wd.trials_to_resolve(1 / 3, wd.Estimate(0.34, 0.01, 100)) is None


def test_power_and_the_throws_that_resolve_weldons_distribution():
    counts = np.array(wd.WELDON_COUNTS)
    truth, fair = counts / counts.sum(), wd.binomial_probabilities(1 / 3)
    test = wd.chi2_fit(counts, fair)
    assert wd.power(10, truth, fair, test) < wd.power(10_000, truth, fair, test)
    n = wd.throws_to_resolve(truth, fair, test)
    assert wd.power(n, truth, fair, test) >= 0.8 > wd.power(n - 1, truth, fair, test)
    one_cell = wd.Chi2(0.0, 0, 1.0, ((0, 12),))
    assert wd.power(100, truth, fair, one_cell) == 0.0
    assert wd.throws_to_resolve(truth, fair, one_cell) is None


def test_distribution_verdict():
    rejected = wd.Chi2(30.0, 5, 1e-5, ((0, 1),) * 6)
    kept = wd.Chi2(3.0, 5, 0.7, ((0, 1),) * 6)
    assert wd.distribution_verdict(rejected, 0.1) == "differs"
    assert wd.distribution_verdict(kept, 0.3) == "not resolvable at this sample"
    assert wd.distribution_verdict(kept, 0.95) == "agrees"


def test_memory_verdict_on_constructed_counts():
    low, high = {"n": 1000, "down": 400}, {"n": 1000, "down": 170}
    assert va.memory_verdict(low, high) == "agrees"
    assert va.memory_verdict({"n": 30, "down": 8}, {"n": 30, "down": 6}) == \
        "not resolvable at this sample"
    assert va.memory_verdict({"n": 1000, "down": 100}, high) == "differs"
    assert va.within(0.45, 0.4, 0.5) == "agrees" and va.within(0.55, 0.4, 0.5) == "differs"


def test_cup_releases_twelve_dice_apart_above_the_table():
    scene = Scene(die=wd.variant_die("drilled16"))
    cups = throws.cup_throws(scene, 5, np.random.default_rng(0))
    assert len(cups) == wd.DICE and all(s.batch_size == 5 for s in cups)
    centres = np.stack([s.position for s in cups], axis=1)  # (5, 12, 3)
    gaps = np.linalg.norm(centres[:, :, None] - centres[:, None], axis=-1)
    gaps[:, np.arange(12), np.arange(12)] = np.inf
    assert gaps.min() > math.sqrt(3) * scene.die.size  # apart in any orientation
    assert (centres[..., 2] > math.sqrt(3) / 2 * scene.die.size).all()


def test_chunks_kept_are_read_back_and_match_a_run_without_them(tmp_path):
    scene = Scene(die=wd.variant_die("drilled16"))
    fresh = wd.chunked_together(scene, 3, seed=5, chunk=2)
    kept = wd.chunked_together(scene, 3, seed=5, keep=tmp_path, chunk=2)
    assert sorted(p.name for p in tmp_path.glob("*.npz")) == [
        "together-5-00000-2.npz", "together-5-00001-1.npz"]
    (tmp_path / "together-5-00001-1.npz").unlink()  # a run stopped after its first chunk
    again = wd.chunked_together(scene, 3, seed=5, keep=tmp_path, chunk=2)
    for other in (kept, again):
        assert other.thrown == fresh.thrown == 3
        np.testing.assert_array_equal(other.successes, fresh.successes)
        np.testing.assert_array_equal(other.faces, fresh.faces)
    with pytest.raises(ValueError, match="keep"):
        wd.chunked_together(scene, 3, seed=5, keep=tmp_path, chunk=3)


def test_sliding_friction_is_the_tables():
    assert va.sliding_friction(Scene()) == pytest.approx(Scene().ground.friction, abs=0.02)


@pytest.fixture(scope="module")
def weldon_quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("weldon")
    return out, wd.run(out, quick=True)


def test_weldon_quick_study(weldon_quick):
    out, numbers = weldon_quick
    assert 0 < numbers["alone_p"] < 1 and numbers["together_throws"] >= 1
    saved = json.loads((out / "weldon.json").read_text())
    assert saved["meta"]["quick"] and saved["meta"]["sizes"] == wd.QUICK
    for entry in saved["alone"].values():
        assert {entry["vs_weldon_p"]["verdict"], entry["vs_fair_p"]["verdict"]} <= VERDICTS
    assert saved["alone"]["casino19"]["com_um"] == [0.0, 0.0, 0.0]
    text = (out / "weldon.md").read_text()
    assert "Nothing is fitted to Weldon's numbers" in text and "**" in text
    assert (out / "figures" / "weldon.png").stat().st_size > 10_000


def test_weldon_throws_is_checked_where_given(tmp_path):
    with pytest.raises(ValueError, match="throws"):
        wd.run(tmp_path, throws=1)
    with pytest.raises(SystemExit):
        studies_main(["validation", "--throws", "10", "--out", str(tmp_path)])


def test_cuboid_page_is_read_back(tmp_path):
    numbers = cb.run(tmp_path, quick=True)
    page = cb.read_page(tmp_path / "cuboids.md")
    assert page.command == "python -m studies cuboids --quick"
    assert page.throws == cb.QUICK and page.seed == 2026
    assert list(page.table) == [label for label, _, _ in cb.CONDITIONS]
    first = page.table[cb.CONDITIONS[0][0]]
    assert list(first) == list(cb.QUICK_RATIOS)
    assert first[1.0][0] == pytest.approx(numbers["cube_p"], abs=5e-4)
    assert first[1.0][1:] == pytest.approx((numbers["cube_lo"], numbers["cube_hi"]), abs=5e-4)
    (tmp_path / "other.md").write_text("# something else\n")
    with pytest.raises(ValueError, match="path"):
        cb.read_page(tmp_path / "other.md")


def test_validation_page_quick(tmp_path, weldon_quick):
    shutil.copy(weldon_quick[0] / "weldon.json", tmp_path / "weldon.json")
    numbers = va.run(tmp_path, quick=True)
    text = (tmp_path / "validation.md").read_text()
    for title in ("## Weldon's dice", "## The initially-down face",
                  "## Restitution and friction", "## Square-cuboid dice"):
        section = text.split(title)[1].split("\n## ")[0]
        assert "**Real dice.**" in section and "**Simulator.**" in section
        assert any(f"**{v}**" in section or f"**Verdict: {v}" in section
                   for v in (*VERDICTS, "prediction"))
    summary = text.split("| experiment | real dice | simulator | verdict |")[1].split("\n\n")[0]
    rows = summary.strip().splitlines()[1:]
    assert len(rows) == 8 and all(row.endswith("** |") for row in rows)
    assert (tmp_path / "cuboids.md").exists()  # run because it was absent
    assert numbers["restitution"] == pytest.approx(0.45, abs=0.01)
    assert numbers["friction"] == pytest.approx(0.4, abs=0.02)


def test_excess_per_offset_recovers_a_line_through_the_origin():
    offsets, se = np.array([40.0, 70.0, 190.0]), np.array([0.004, 0.008, 0.008])
    slope, slope_se = wd.excess_per_offset(offsets, 2e-5 * offsets, se)
    assert slope == pytest.approx(2e-5, rel=1e-12)
    assert slope_se == pytest.approx(1 / math.sqrt(np.sum((offsets / se) ** 2)), rel=1e-12)
    offset, low, high = wd.offset_for_weldon(slope, slope_se)
    assert offset == pytest.approx(wd.EFFECT / 2e-5) and low < offset < high
    assert math.isinf(wd.offset_for_weldon(1e-5, 1e-5)[2])
    with pytest.raises(ValueError, match="offsets"):
        wd.excess_per_offset(np.zeros(2), np.zeros(2), np.ones(2))

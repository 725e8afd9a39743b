"""Two d6 thrown together keep the faces of the physics they were checked on.

The reference is 20,000 seeded throws of the pairs study's hand into the tray, made with the
group kernel before its speed changes (``tests/pair_distribution.py``); these tests throw new
seeds and compare (two-sample chi-square): the totals, the 36 (die 1, die 2) cells, and the
independence of the two faces, with and without ``DieContact``'s islands.
"""

import numpy as np
import pytest
from pair_distribution import pair_table, reference, totals, two_sample

from studies.pairs import independence

SIGNIFICANT = 1e-3  # p-value below which a difference counts as found
QUICK, FULL = 2_000, 20_000


def _compare(table: np.ndarray) -> None:
    """Assert ``table`` (6, 6) agrees with the reference: totals, cells, independence."""
    stored = reference()
    assert two_sample(totals(stored), totals(table)) > SIGNIFICANT, "totals differ"
    assert two_sample(stored, table) > SIGNIFICANT, "(die 1, die 2) faces differ"
    assert independence(table)[1] > SIGNIFICANT, "the two faces are dependent"


def test_the_comparison_finds_a_die_showing_six_half_again_as_often_in_the_quick_sample():
    rng = np.random.default_rng(0)
    stored = reference()
    share = stored / stored.sum()
    biased = share.copy()
    biased[5] *= 1.5  # die 1 shows six half again as often
    biased /= biased.sum()
    fair = rng.multinomial(QUICK, share.ravel()).reshape(6, 6)
    loaded = rng.multinomial(QUICK, biased.ravel()).reshape(6, 6)
    assert two_sample(stored, fair) > SIGNIFICANT
    assert two_sample(stored, loaded) < SIGNIFICANT


@pytest.mark.parametrize("islands", [False, True])
def test_a_few_thousand_pairs_keep_the_reference_faces(islands):
    table = pair_table(QUICK, 1, chunk=1_000, islands=islands)
    assert table.sum() > 0.99 * QUICK
    _compare(table)


@pytest.mark.slow
@pytest.mark.parametrize("islands", [False, True])
def test_twenty_thousand_pairs_keep_the_reference_faces(islands):
    table = pair_table(FULL, 2, islands=islands)
    assert table.sum() > 0.99 * FULL
    _compare(table)

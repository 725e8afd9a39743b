"""Two d6 from the pairs study's hand into the tray: the faces of seeded throws, as counts.

``python tests/pair_distribution.py`` rewrites ``tests/data/pair_distribution.json`` from the
code as it stands (the physics the group tests compare against); do so only on purpose, from
the commit whose distribution is the reference, and say so in its commit.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from scipy import stats

from dice_env.provenance import code_version
from dice_env.throws import group_throws, tray_scene
from studies.pairs import throw_pairs

PATH = Path(__file__).with_name("data") / "pair_distribution.json"
REFERENCE_SEED, THROWS, CHUNK = 49, 20_000, 2_000


def pair_table(throws: int, seed: int, chunk: int = CHUNK, islands: bool = True) -> np.ndarray:
    """Counted throws (6, 6) by (die 1, die 2) face, in chunks seeded ``(seed, i)``.

    ``islands``: as :class:`~dice_env.simulation.group.DieContact`'s.
    """
    scene = tray_scene()
    dice = (scene.die, scene.die)
    table = np.zeros((6, 6), np.int64)
    for i, start in enumerate(range(0, throws, chunk)):
        state = group_throws(scene, dice, min(chunk, throws - start),
                             np.random.default_rng([seed, i]))
        table += throw_pairs(scene, dice, state, islands=islands).table
    return table


def totals(table: np.ndarray) -> np.ndarray:
    """Counts (11,) of the totals 2..12 of a (6, 6) table of faces."""
    faces = np.add.outer(np.arange(1, 7), np.arange(1, 7))
    return np.bincount(faces.ravel(), weights=np.asarray(table).ravel(),
                       minlength=13)[2:].astype(np.int64)


def two_sample(a: np.ndarray, b: np.ndarray) -> float:
    """p-value of the chi-square test that counts ``a`` and ``b`` share one distribution."""
    counts = np.array([np.ravel(a), np.ravel(b)])
    return float(stats.chi2_contingency(counts[:, counts.sum(axis=0) > 0],
                                        correction=False)[1])


def reference() -> np.ndarray:
    """The stored reference table (6, 6)."""
    return np.array(json.loads(PATH.read_text())["table"])


if __name__ == "__main__":
    table = pair_table(THROWS, REFERENCE_SEED)
    PATH.parent.mkdir(exist_ok=True)
    PATH.write_text(json.dumps({
        "what": "two d6 from the pairs study's hand into the tray, until decided: counted "
                "throws by (die 1, die 2) face", "throws": THROWS, "seed": REFERENCE_SEED,
        "chunk": CHUNK, "commit": code_version(),
        "table": table.tolist()}, indent=1) + "\n")
    print(f"wrote {PATH}: {int(table.sum())} counted of {THROWS}")

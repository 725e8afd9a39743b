"""Two fair dice thrown together into a tray: the total against 2d6's triangle, and independence.

``run(out, quick, throws)`` writes ``out/pairs.md`` and ``out/figures/pairs.png`` (see that page).
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import matplotlib.pyplot as plt
import numba
import numpy as np
from scipy import stats

from dice_env.intervals import wilson
from dice_env.markdown import bracket, markdown_table
from dice_env.model.die import Die
from dice_env.model.scene import Scene
from dice_env.model.surroundings import TRAY
from dice_env.simulation.chunks import prepare
from dice_env.simulation.group import (
    DieContact,
    GroupResult,
    GroupState,
    group_step,
    simulate_group,
)
from dice_env.throws import (
    HAND,
    T_TRAY,
    batches,
    group_throws,
    tray_scene,
)
from studies.common import (
    DOCS,
    SEED,
    checked_throws,
    draw_figures,
    error_bars,
    join,
    kept_chunks,
    progress,
    save_figure,
    write_text,
)
from studies.docs_numbers import generated
from studies.templates import write_study

# Throws of the pair in the full and the quick run, per kernel call, per seeded chunk.
FULL, QUICK, BATCH, CHUNK = 100_000, 60, 500, 2_000
COMMAND = "python -m studies pairs"  # writes docs/generated/pairs-*.md
JSON = "docs/pairs.json"  # every number of the page, written by the full study
FILES = ("pairs-intro", "pairs-throw", "pairs-voided-throws-not", "pairs-total-against-2d6",
         "pairs-two-faces", "pairs-conclusion")
MIN_THROWS = 20  # the 6 x 6 table needs some in every row and column
SIGNIFICANT = 0.01  # p-value below which a test counts as a detected departure
TOTALS = np.arange(2, 13)


def triangle() -> np.ndarray:
    """P(total = k) for k = 2..12 of two independent fair d6: ``(6 - |k - 7|) / 36``."""
    return (6 - np.abs(TOTALS - 7)) / 36


def independence(table: np.ndarray) -> tuple[float, float, int]:
    """Chi-square test of independence of ``table``'s non-empty rows and columns: (chi2, p, dof)."""
    table = np.asarray(table)
    table = table[table.sum(axis=1) > 0][:, table.sum(axis=0) > 0]
    if min(table.shape) < 2:
        raise ValueError(f"table must hold counts in at least two rows and two columns, got "
                         f"{table.shape} non-empty")
    chi2, p, dof, _ = stats.chi2_contingency(table, correction=False)
    return float(chi2), float(p), int(dof)


def total_test(totals: np.ndarray) -> tuple[float, float]:
    """Chi-square of ``totals`` (11,) of 2..12 against :func:`triangle` (10 dof): (chi2, p)."""
    chi2, p = stats.chisquare(totals, np.sum(totals) * triangle())
    return float(chi2), float(p)


@dataclass
class Pairs:
    """The outcome of a set of two-dice throws.

    ``table`` (6, 6): counted throws by (die 1, die 2) face; ``met`` (B,): the dice touched
    each other; ``counted`` (B,): both dice decided and read, no instability, no sink;
    ``voided``: the number of throws for each reason (a throw may have several);
    ``impacts`` (B, 2) and ``time`` (B,): each throw's impacts and time to its end (s).
    """

    table: np.ndarray
    met: np.ndarray
    counted: np.ndarray
    voided: dict[str, int]
    impacts: np.ndarray
    time: np.ndarray
    met_table: np.ndarray

    @property
    def n(self) -> int:
        """Number of counted throws."""
        return int(self.table.sum())

    @property
    def totals(self) -> np.ndarray:
        """Counted throws by total 2..12, (11,)."""
        faces = np.add.outer(np.arange(1, 7), np.arange(1, 7))
        return np.bincount(faces.ravel(), weights=self.table.ravel(), minlength=13)[2:] \
            .astype(np.int64)

    def total_test(self) -> tuple[float, float]:
        """Chi-square of the totals against :func:`triangle` (10 dof): (chi2, p)."""
        return total_test(self.totals)

    def uniformity(self, die: int) -> tuple[float, float]:
        """Chi-square of die ``die``'s (0 or 1) faces against uniform (5 dof): (chi2, p)."""
        chi2, p = stats.chisquare(self.table.sum(axis=1 - die))
        return float(chi2), float(p)

    def arrays(self) -> dict[str, np.ndarray]:
        """The fields as arrays (``voided``: the counts in :data:`VOID_REASONS`' order)."""
        return {f.name: np.asarray(getattr(self, f.name))
                for f in fields(self) if f.name != "voided"} | {
            "voided": np.array([self.voided.get(k, 0) for k in VOID_REASONS], np.int64)}

    @classmethod
    def joined(cls, parts: list[dict[str, np.ndarray]]) -> Pairs:
        """The pairs of several :meth:`arrays`: per-throw arrays joined, counts added."""
        added = ("table", "met_table")
        return cls(**{k: np.sum([p[k] for p in parts], axis=0) for k in added},
                   **{f.name: np.concatenate([p[f.name] for p in parts])
                      for f in fields(cls) if f.name not in (*added, "voided")},
                   voided=dict(zip(VOID_REASONS, (int(c) for c in np.sum(
                       [p["voided"] for p in parts], axis=0)), strict=True)))


def simulate_in_batches(scene: Scene, dice: tuple[Die, ...], state: GroupState,
                        bar: object = None, batch: int = BATCH, **keywords: object) -> GroupResult:
    """:func:`simulate_group` (no recording; ``keywords`` go to it) in batches, joined."""
    return join([simulate_group(scene, dice, chunk, **keywords)
                   for chunk in batches(state, batch, bar)])


def throw_pairs(scene: Scene, dice: tuple[Die, ...], state: GroupState, bar: object = None,
                batch: int = BATCH, islands: bool = True) -> Pairs:
    """Throw ``state`` until the faces are decided, in batches of ``batch``; count them.

    ``islands``: as :class:`~dice_env.simulation.group.DieContact`'s.
    """
    result = simulate_in_batches(scene, dice, state, bar, batch, until="decided",
                                 contact=DieContact(islands=islands))
    reasons = void_reasons(result)
    counted = not_void(reasons)
    met = result.overlap > 0
    return Pairs(table=_table(result.face, counted), met=met, counted=counted,
                 voided={k: int(v.sum()) for k, v in reasons.items()}, impacts=result.impacts,
                 time=result.steps * group_step(scene, dice),
                 met_table=_table(result.face, counted & met))


def chunked_pairs(scene: Scene, dice: tuple[Die, ...], throws: int, seed: int,
                  keep: Path | None = None, bar: object = None,
                  chunk: int = CHUNK) -> tuple[Pairs, float, float]:
    """``throws`` hand throws in chunks of ``chunk`` seeded ``(seed, i)``, joined.

    Returns the pairs and the wall-clock and CPU seconds their throwing took. ``keep``: a folder
    keeping the chunks, read back when present (:mod:`dice_env.simulation.chunks`): same result.
    """
    if keep is not None:
        prepare(keep, {"dice": [d.name for d in dice], "hand": asdict(HAND), "chunk": chunk,
                       "scene": hashlib.sha1(repr(scene).encode()).hexdigest(),
                       "contact": asdict(DieContact())})

    def throw(i: int, size: int) -> dict[str, np.ndarray]:
        state = group_throws(scene, dice, size, np.random.default_rng([seed, i]))
        start, cpu = time.perf_counter(), time.process_time()
        pairs = throw_pairs(scene, dice, state)
        return pairs.arrays() | {"seconds": np.float64(time.perf_counter() - start),
                                 "cpu": np.float64(time.process_time() - cpu)}

    parts = kept_chunks(throw, throws, chunk, keep, f"pairs-{seed}", bar)
    return (Pairs.joined(parts), float(sum(p["seconds"] for p in parts)),
            float(sum(p["cpu"] for p in parts)))


VOID_REASONS = ("not decided within the time limit", "unstable (energy rose)", "a die sunk",
                "a die leaning on the other (not read)")


def void_reasons(result: GroupResult) -> dict[str, np.ndarray]:
    """The throws (B,) of ``result`` that cannot be counted, by :data:`VOID_REASONS`."""
    return dict(zip(VOID_REASONS, (~(result.decided | result.settled), result.unstable,
                                   result.sunk.any(axis=1), ~result.read.all(axis=1)),
                    strict=True))


def not_void(reasons: dict[str, np.ndarray]) -> np.ndarray:
    """The throws (B,) that none of ``reasons`` (as :func:`void_reasons` gives them) voids."""
    return ~np.any(list(reasons.values()), axis=0)


def _table(face: np.ndarray, which: np.ndarray) -> np.ndarray:
    """Counts of (die 1, die 2) faces over the throws ``which``, (6, 6)."""
    return np.bincount((face[which, 0] - 1) * 6 + face[which, 1] - 1,
                       minlength=36).reshape(6, 6)


def run(out: Path = DOCS, quick: bool = False, throws: int | None = None,
        keep: Path | None = None, seed: int = SEED) -> dict[str, float]:
    """Regenerate ``pairs.md`` and its figure under ``out``; return the headline numbers.

    ``throws``: throws of the pair (default :data:`FULL`, :data:`QUICK` with ``quick``);
    ``keep``: a folder for the chunks (:func:`chunked_pairs`).
    """
    n = checked_throws(throws, MIN_THROWS, QUICK if quick else FULL)
    scene = tray_scene()
    dice = (scene.die, scene.die)
    bar = progress(n, "two-dice throws", "throw")
    pairs, seconds, cpu = chunked_pairs(scene, dice, n, seed, keep, bar)
    bar.close()
    numbers = _numbers(pairs, seconds, cpu)
    data = page_data(pairs, numbers, seed)
    draw_figures(FIGURES, data, out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "pairs.json", json.dumps(data, indent=1) + "\n")
    write_study(out, "pairs", list(FILES), {"d": json.loads(json.dumps(data))})
    return numbers


def _numbers(pairs: Pairs, seconds: float, cpu: float) -> dict[str, float]:
    chi2, p = pairs.total_test()
    ind = independence(pairs.table)
    met_ind = independence(pairs.met_table)
    shares = pairs.totals / pairs.n
    thrown = len(pairs.counted)
    return {
        "throws": thrown, "counted": pairs.n, "voided": 1 - pairs.n / thrown,
        "met": float(pairs.met.mean()), "seconds": seconds, "rate": thrown / seconds,
        "cpu_seconds": cpu,
        "total_chi2": chi2, "total_p": p, "p7": float(shares[5]),
        "max_dev": float(np.abs(shares - triangle()).max()),
        "independence_chi2": ind[0], "independence_p": ind[1],
        "met_independence_p": met_ind[1],
        "die1_p": pairs.uniformity(0)[1], "die2_p": pairs.uniformity(1)[1],
        "impacts": float(pairs.impacts[pairs.counted].mean()),
        "time_median": float(np.median(pairs.time[pairs.counted])),
    }


def figure(d: dict, path: Path) -> None:
    """Draw ``figures/pairs.png`` from the page's numbers ``d`` (``pairs.json``)."""
    table, totals, n = _counts(d)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), layout="constrained")
    share = totals / n
    ci = wilson(totals, n)
    ax = axes[0]
    ax.bar(TOTALS, share, color="C0", label="simulated (95% interval)")
    ax.errorbar(TOTALS, share, yerr=error_bars(share, ci), fmt="none", color="k", capsize=3)
    ax.plot(TOTALS, triangle(), "o--", color="C3", label="2d6: (6 - |k - 7|) / 36")
    ax.set(xticks=TOTALS, xlabel="total of the two dice", ylabel="share of counted throws")
    ax.set_title(f"{n} counted throws, chi-square p = {total_test(totals)[1]:.3g}", fontsize=10)
    ax.legend(fontsize=8)
    expected = np.outer(table.sum(axis=1), table.sum(axis=0)) / n
    residual = (table - expected) / np.sqrt(expected)
    ax = axes[1]
    image = ax.imshow(residual, cmap="RdBu_r", vmin=-3, vmax=3, origin="lower",
                      extent=(0.5, 6.5, 0.5, 6.5))
    for (i, j), count in np.ndenumerate(table):
        ax.text(j + 1, i + 1, str(count), ha="center", va="center", fontsize=8)
    ax.set(xlabel="die 2 face", ylabel="die 1 face")
    ax.set_title(f"(die 1, die 2) counts; colour: (observed - expected) / sqrt(expected), "
                 f"independence p = {independence(table)[1]:.3g}", fontsize=9)
    fig.colorbar(image, ax=ax, shrink=0.8)
    save_figure(fig, path)


FIGURES = {"pairs": figure}  # the page's figure, drawn by run from its numbers


def _half_width(n: int) -> float:
    """Half-width of the 95% interval of P(7) = 1/6 after ``n`` counted throws."""
    return 1.959964 * float(np.sqrt(triangle()[5] * (1 - triangle()[5]) / n))


def page_data(pairs: Pairs, n: dict, seed: int) -> dict:
    """Every number of the page (JSON-ready), kept as ``pairs.json``."""
    return {"command": f"python -m studies pairs --throws {len(pairs.counted)}", "seed": seed,
            "chunk": CHUNK, "throws": len(pairs.counted), "seconds": n["seconds"],
            "cpu": n["cpu_seconds"], "threads": numba.get_num_threads(), "rate": n["rate"],
            "met": n["met"], "impacts": n["impacts"], "time_median": n["time_median"],
            "voided": {k: int(v) for k, v in pairs.voided.items()},
            "table": pairs.table.astype(int).tolist(),
            "met_counted": int(pairs.met_table.sum()),
            "total_chi2": n["total_chi2"], "total_p": n["total_p"],
            "independence_chi2": n["independence_chi2"], "independence_p": n["independence_p"],
            "independence_dof": independence(pairs.table)[2],
            "met_independence_p": n["met_independence_p"],
            "die1_p": n["die1_p"], "die2_p": n["die2_p"]}


def _counts(d: dict) -> tuple[np.ndarray, np.ndarray, int]:
    """The page's (6, 6) table, its totals 2..12 and the number of counted throws."""
    table = np.asarray(d["table"], np.int64)
    faces = np.add.outer(np.arange(1, 7), np.arange(1, 7))
    totals = np.bincount(faces.ravel(), weights=table.ravel(), minlength=13)[2:].astype(np.int64)
    return table, totals, int(table.sum())


@generated("pairs-intro", COMMAND, d=JSON)
def intro_text(d: dict) -> str:
    """The run: command, seed, chunks, throws, time and rate."""
    thrown = d["throws"]
    return f"""\
Generated by `{d['command']}` (module
`studies/pairs.py`, seed {d['seed']}, in chunks of {d['chunk']:,} throws seeded by their index:
`--chunks DIR` keeps them, so that a stopped run continues). This run threw the pair
**{thrown:,}** times in **{d['seconds']:.0f} s** of wall-clock time on
{d['threads']} thread(s) of a shared machine ({d['cpu']:.0f} s of this
process's CPU time), {d['rate']:.1f} throws/s{'' if thrown >= FULL else f"; at that rate the study's default of {FULL:,} throws (`python -m studies pairs`) would take about {FULL / d['rate'] / 3600:.1f} h"}. `benchmarks/dice_together.py` measures
the cost per throw against the number of dice."""  # noqa: E501


@generated("pairs-throw", COMMAND, d=JSON)
def throw_text(d: dict) -> str:
    """The throw (the scene and the hand, from the code) and how the dice met."""
    scene, h = tray_scene(), HAND
    return f"""\
Two default d6 (edge {scene.die.size * 1e3:g} mm, mass {scene.die.mass * 1e3:g} g) leave one
hand together into the {TRAY[0] * 100:g} x {TRAY[1] * 100:g} cm tray
(`dice_env.model.surroundings.tray()`, walls of the table's material), on the default table, with
the automatic step ({scene.step * 1e6:.1f} µs) and the default die–die contact
(`dice_env.simulation.group.DieContact`, {DieContact().law} friction). The hand (`pairs.Hand`,
`pairs.hand_throws`): the dice side by side, {h.spacing * 100:g} cm apart centre to centre,
above the tray's centre at a common height of {h.clearance[0] * 100:g}–{h.clearance[1] * 100:g} cm
above the height where a corner could touch; one hand velocity of
{h.speed[0]:g}–{h.speed[1]:g} m/s in a uniform direction toward the table, plus each die's
own normal noise of {h.noise:g} m/s per component; each die its own uniform orientation and a
spin of {h.spin[0]:g}–{h.spin[1]:g} rad/s about its own uniform
axis (the fairness study's vigorous throw, given to both dice at once). Die 1 is the one at
y < 0. Each throw runs (`simulate_group(..., until="decided")`) until no energy left
in it can change either face, or {T_TRAY:g} s.

**The dice meet:** in {d['met']:.1%} of the throws the two dice touched each other at least
once (`GroupResult.overlap > 0`). A counted throw had on average {d['impacts']:.1f} impacts per
die as `GroupResult.impacts` counts them (each start of a contact with the floor or a wall
faster than the rest speed; touches of the other die are not counted on their own: die–die
impacts are `GroupResult.die_impacts`, studied in `collisions.md`) and was decided after a median
{d['time_median']:.2f} s of simulated time."""


@generated("pairs-voided-throws-not", COMMAND, d=JSON)
def voided_text(d: dict) -> str:
    """The voided throws by reason, and the counted share."""
    thrown, counted = d["throws"], _counts(d)[2]
    voided = markdown_table("reason | throws | share", ((reason, count, f"{count / thrown:.4%}")
                                                       for reason, count in d["voided"].items()))
    return f"""\
{voided}

Counted: **{counted}** of {thrown} throws ({counted / thrown:.4%}); a throw may be voided
for more than one reason."""


@generated("pairs-total-against-2d6", COMMAND, d=JSON)
def totals_text(d: dict) -> str:
    """The totals against 2d6's triangle: the test and each total's share and interval."""
    _, totals, counted = _counts(d)
    ci = wilson(totals, counted)
    table = markdown_table("total | count | share | 95% interval | 2d6 | inside", (
        (k, c, f"{c / counted:.4f}", bracket((lo, hi), 4), f"{t:.4f}",
         "yes" if lo <= t <= hi else "no")
        for k, c, (lo, hi), t in zip(TOTALS, totals, ci, triangle(), strict=True)))
    return f"""\
Chi-square goodness of fit of the totals 2–12 against `(6 - |k - 7|) / 36` (10 degrees of
freedom): chi2 = {d['total_chi2']:.2f}, **p = {d['total_p']:.3g}**.

{table}"""


@generated("pairs-two-faces", COMMAND, d=JSON)
def faces_text(d: dict) -> str:
    """The (die 1, die 2) table and the tests of independence and uniformity."""
    table, _, counted = _counts(d)
    faces = markdown_table("die 1 \\ die 2 | 1 | 2 | 3 | 4 | 5 | 6 | sum", (
        *((f"**{i + 1}**", *row, row.sum()) for i, row in enumerate(table)),
        ("sum", *table.sum(axis=0), counted)))
    return f"""\
{faces}

- Independence (chi-square on the 6 x 6 table, {d['independence_dof']} dof): chi2 = {d['independence_chi2']:.2f},
  **p = {d['independence_p']:.3g}**; on the throws in which the dice touched each other only:
  p = {d['met_independence_p']:.3g}.
- Uniformity of each die (5 dof): die 1 p = {d['die1_p']:.3g}, die 2 p = {d['die2_p']:.3g}."""  # noqa: E501


@generated("pairs-conclusion", COMMAND, d=JSON)
def conclusion_text(d: dict) -> str:
    """The verdicts at :data:`SIGNIFICANT`, the largest gap and the resolution."""
    _, totals, counted = _counts(d)
    thrown, ci, shares = d["throws"], wilson(totals, counted), totals / counted
    worst = int(np.argmax(np.abs(shares - triangle())))
    return f"""\
At the {SIGNIFICANT:.0%} level the distribution of the total {'departs from' if d['total_p'] < SIGNIFICANT else 'agrees with'} 2d6's triangle (p = {d['total_p']:.3g}); the largest gap between a total's share and the triangle is {shares[worst] - triangle()[worst]:+.4f}, at total {TOTALS[worst]}, and {int(sum((triangle() < ci[:, 0]) | (triangle() > ci[:, 1])))} of the 11 totals' 95% intervals miss the triangle's value (by chance alone about {0.05 * 11:.2f} would). The (die 1, die 2) table {'shows a dependence' if d['independence_p'] < SIGNIFICANT else 'shows no detectable dependence'} (p = {d['independence_p']:.3g}), and among the {d['met_counted']} counted throws in which the dice touched each other it {'does' if d['met_independence_p'] < SIGNIFICANT else 'does not'} (p = {d['met_independence_p']:.3g}); {"both dice's faces are consistent with uniform" if min(d['die1_p'], d['die2_p']) >= SIGNIFICANT else "a die's faces depart from uniform"} (die 1: p = {d['die1_p']:.3g}, die 2: p = {d['die2_p']:.3g}). Resolution: with {counted} counted throws the 95% interval of P(7) is about ±{_half_width(counted):.4f} around 1/6, so a smaller bias of the seven would go unseen here{f'; {FULL:,} throws would narrow it to ±{_half_width(FULL):.4f}.' if thrown < FULL else '.'}"""  # noqa: E501

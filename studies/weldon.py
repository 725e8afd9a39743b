"""Weldon's dice (1894): twelve pip-drilled dice, the chance of a 5 or a 6.

``run`` writes ``weldon.md``, ``weldon.json`` (read by the validation page) and
``figures/weldon.png``: the cups' dice thrown together (:func:`throw_together`) and each alone
(:func:`throw_alone`), the pip :data:`VARIANTS` alone. Nothing is fitted to Weldon's numbers.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import matplotlib.pyplot as plt
import numba
import numpy as np
from scipy import optimize, stats

from dice_env.intervals import Z95
from dice_env.markdown import estimate, markdown_table
from dice_env.model.checks import check_int
from dice_env.model.die import Die
from dice_env.model.pips import Pips
from dice_env.model.scene import Scene
from dice_env.simulation.chunks import prepare
from dice_env.simulation.group import DieContact, GroupState, simulate_group
from dice_env.simulation.simulate import State
from dice_env.throws import CUP, CUP_BLOCK, Faces, cup_throws, throw_faces
from studies.common import (
    DOCS,
    SEED,
    checked_throws,
    draw_figures,
    kept_chunks,
    progress,
    save_figure,
    write_text,
)
from studies.docs_numbers import generated
from studies.templates import write_study

# Weldon's throws of twelve dice with 0..12 showing a 5 or a 6 (Pearson 1900, Kemp & Kemp 1991)
WELDON_COUNTS = (185, 1149, 3265, 5475, 6114, 5194, 3067, 1331, 403, 105, 14, 4, 0)
DICE = 12
SUCCESS = (5, 6)
FAIR = 1 / 3
MIN_EXPECTED = 5.0  # chi-square cells are pooled until each expects at least this many
SIGNIFICANCE = 0.05
RESOLVING_POWER = 0.8  # a test "resolves" a difference it detects with this probability
# Twelve-dice throws of the full and quick runs: together, alone (reference die), each variant
FULL = {"together": 240, "alone": 4500, "variant": 1200}
QUICK = {"together": 3, "alone": 12, "variant": 6}
BATCH_TOGETHER = 125  # twelve-dice throws per kernel call
CHUNK_TOGETHER = 250  # twelve-dice throws per seeded chunk (see chunked_together)
T_MAX_TOGETHER = 2.0  # s of simulated time; a throw not decided by then is not counted


# ---- comparison maths --------------------------------------------------------------------

@dataclass(frozen=True)
class Estimate:
    """A probability ``p`` with its standard error ``se`` from ``n`` trials."""

    p: float
    se: float
    n: int

    @classmethod
    def binomial(cls, successes: int, trials: int) -> Estimate:
        """``successes`` of ``trials`` independent trials: ``se = sqrt(p (1 - p) / n)``."""
        trials = check_int("trials", trials, 1)
        if not 0 <= successes <= trials:
            raise ValueError(f"successes must be in [0, trials={trials}], got {successes!r}")
        p = successes / trials
        return cls(p, math.sqrt(p * (1 - p) / trials), trials)

    @classmethod
    def per_throw(cls, successes: np.ndarray, dice: int = DICE) -> Estimate:
        """The share of successes among ``dice`` dice per throw (T,), the throw as the unit.

        The error is the spread between throws, valid whether or not a throw's dice interact.
        """
        successes = np.asarray(successes, dtype=np.float64)
        if successes.ndim != 1 or successes.size < 2:
            raise ValueError(f"successes must be a 1-d array of >= 2 throws, got shape "
                             f"{successes.shape}")
        se = float(successes.std(ddof=1)) / (dice * math.sqrt(successes.size))
        return cls(float(successes.mean()) / dice, se, int(successes.size * dice))

    @property
    def interval(self) -> tuple[float, float]:
        """The 95% interval ``p ± 1.96 se``."""
        return self.p - Z95 * self.se, self.p + Z95 * self.se


WELDON = Estimate.binomial(sum(k * c for k, c in enumerate(WELDON_COUNTS)),
                           DICE * sum(WELDON_COUNTS))
EFFECT = WELDON.p - FAIR  # Weldon's excess over a fair die


@dataclass(frozen=True)
class Comparison:
    """``a - b`` with its 95% half-width and the verdict of :func:`compare`."""

    difference: float
    half_width: float
    verdict: str


def compare(a: Estimate, b: Estimate, effect: float = EFFECT) -> Comparison:
    """Compare two independent estimates against the size of the ``effect`` looked for.

    "differs" when ``|a - b|`` exceeds the combined 95% half-width; else "not resolvable at this
    sample" when that half-width exceeds ``|effect|``; else "agrees".
    """
    half = Z95 * math.hypot(a.se, b.se)
    difference = a.p - b.p
    verdict = ("differs" if abs(difference) > half else
               "not resolvable at this sample" if half > abs(effect) else "agrees")
    return Comparison(difference, half, verdict)


def trials_to_resolve(p: float, reference: Estimate, effect: float = EFFECT) -> int | None:
    """Fewest trials at ``p`` whose 95% half-width with ``reference``'s is below ``effect``.

    None when the reference's own error is too wide for any.
    """
    room = (abs(effect) / Z95) ** 2 - reference.se**2
    return math.ceil(p * (1 - p) / room) if room > 0 else None


def binomial_probabilities(p: float, dice: int = DICE) -> np.ndarray:
    """P(k successes of ``dice``) for k = 0..dice."""
    return stats.binom.pmf(np.arange(dice + 1), dice, p)


def pooled_cells(expected: np.ndarray, minimum: float = MIN_EXPECTED) -> list[range]:
    """Groups of neighbouring cells with at least ``minimum`` expected each (tails pool first)."""
    groups = [range(k, k + 1) for k in range(expected.size)]
    while len(groups) > 1:
        sums = [expected[g.start:g.stop].sum() for g in groups]
        if min(sums) >= minimum:
            break
        if sums[0] <= sums[-1]:
            groups[:2] = [range(groups[0].start, groups[1].stop)]
        else:
            groups[-2:] = [range(groups[-2].start, groups[-1].stop)]
    return groups


@dataclass(frozen=True)
class Chi2:
    """A chi-square test: statistic, degrees of freedom, p-value and the pooled cells."""

    statistic: float
    dof: int
    p_value: float
    cells: tuple[tuple[int, int], ...]  # (first, last) success counts of each cell

    @property
    def testable(self) -> bool:
        """At least two cells, so one degree of freedom or more."""
        return self.dof >= 1


def _pool(counts: np.ndarray, groups: list[range]) -> np.ndarray:
    return np.array([counts[..., g.start:g.stop].sum(axis=-1) for g in groups]).T


def _chi2(observed: np.ndarray, expected: np.ndarray, groups: list[range]) -> Chi2:
    dof = len(groups) - 1
    statistic = float(((observed - expected) ** 2 / expected).sum()) if dof >= 1 else 0.0
    p_value = float(stats.chi2.sf(statistic, dof)) if dof >= 1 else 1.0
    return Chi2(statistic, dof, p_value, tuple((g.start, g.stop - 1) for g in groups))


def chi2_fit(counts: np.ndarray, probabilities: np.ndarray, minimum: float = MIN_EXPECTED) -> Chi2:
    """Goodness of fit of ``counts`` (per number of successes) to ``probabilities``."""
    counts = np.asarray(counts, dtype=np.float64)
    expected = counts.sum() * np.asarray(probabilities, dtype=np.float64)
    groups = pooled_cells(expected, minimum)
    return _chi2(_pool(counts, groups), _pool(expected, groups), groups)


def chi2_homogeneity(a: np.ndarray, b: np.ndarray, minimum: float = MIN_EXPECTED) -> Chi2:
    """Test that two samples of counts (per number of successes) share one distribution."""
    table = np.array([a, b], dtype=np.float64)
    share = table.sum(axis=0) / table.sum()
    groups = pooled_cells(table.sum(axis=1).min() * share, minimum)
    pooled = _pool(table, groups).T
    expected = np.outer(pooled.sum(axis=1), pooled.sum(axis=0)) / pooled.sum()
    return _chi2(pooled, expected, groups)


def _effect_size(truth: np.ndarray, null: np.ndarray, test: Chi2) -> float:
    """Noncentrality per throw on ``test``'s cells: ``sum((truth - null)^2 / null)``."""
    truth_c, null_c = (np.array([np.sum(x[a:b + 1]) for a, b in test.cells]) for x in (truth, null))
    return float(np.sum((truth_c - null_c) ** 2 / null_c))


def power(throws: int, truth: np.ndarray, null: np.ndarray, test: Chi2,
          alpha: float = SIGNIFICANCE) -> float:
    """Power of ``test``'s chi-square, on ``throws`` throws, against ``truth`` when ``null``."""
    if not test.testable:
        return 0.0
    critical = stats.chi2.isf(alpha, test.dof)
    return float(stats.ncx2.sf(critical, test.dof, throws * _effect_size(truth, null, test)))


def throws_to_resolve(truth: np.ndarray, null: np.ndarray, test: Chi2,
                      target: float = RESOLVING_POWER, alpha: float = SIGNIFICANCE) -> int | None:
    """The fewest throws on which ``test``'s cells tell ``truth`` from ``null`` with ``target``.

    None when they cannot (no degree of freedom, or no difference on those cells).
    """
    size = _effect_size(truth, null, test) if test.testable else 0.0
    if size <= 0:
        return None
    critical = stats.chi2.isf(alpha, test.dof)
    high = 1.0
    while stats.ncx2.sf(critical, test.dof, high) < target:
        high *= 2
    needed = optimize.brentq(lambda lam: stats.ncx2.sf(critical, test.dof, lam) - target, 0.0, high)
    return math.ceil(needed / size)


def distribution_verdict(test: Chi2, power_against_fair: float) -> str:
    """The verdict of a test of a simulated distribution against Weldon's.

    "differs" when it rejects at :data:`SIGNIFICANCE`; "not resolvable at this sample" when it
    cannot be tested or ``power_against_fair`` < :data:`RESOLVING_POWER`; else "agrees".
    """
    if test.testable and test.p_value < SIGNIFICANCE:
        return "differs"
    if not test.testable or power_against_fair < RESOLVING_POWER:
        return "not resolvable at this sample"
    return "agrees"


# ---- the throws ----------------------------------------------------------------------------


@dataclass
class Together:
    """Twelve-dice throws thrown together: successes per counted throw and what was left out.

    Counted: decided, every die read (none leaning), none unstable or sunk. ``faces`` (6,):
    face counts over the counted throws' dice.
    """

    successes: np.ndarray
    faces: np.ndarray
    thrown: int
    leaning: int
    undecided: int
    seconds: float

    @property
    def counts(self) -> np.ndarray:
        """Counted throws with 0..12 successes."""
        return np.bincount(self.successes, minlength=DICE + 1)


def throw_together(scene: Scene, cups: list[State], bar: object = None,
                   batch: int = BATCH_TOGETHER) -> Together:
    """Throw each cup's twelve dice together (``until="decided"``) on ``scene``'s table."""
    dice = (scene.die,) * len(cups)
    n = cups[0].batch_size
    kept, leaning, undecided = [], 0, 0
    start_time = time.perf_counter()
    for start in range(0, n, batch):
        group = GroupState.of([State(*(getattr(s, f.name)[start:start + batch]
                                       for f in fields(State))) for s in cups])
        res = simulate_group(scene, dice, group, until="decided", t_max=T_MAX_TOGETHER)
        clean = ~res.unstable & ~res.sunk.any(axis=1)
        read = res.read.all(axis=1)
        ok = res.decided & read & clean
        leaning += int(np.sum(~read & clean))
        undecided += int(np.sum(~res.decided & read & clean))
        kept.append(res.face[ok])
        if bar is not None:
            bar.update(group.batch_size * len(dice))
    faces = np.concatenate(kept) if kept else np.zeros((0, len(dice)), np.int64)
    return Together(np.isin(faces, SUCCESS).sum(axis=1),
                    np.bincount(faces.ravel(), minlength=7)[1:], n, leaning, undecided,
                    time.perf_counter() - start_time)


def chunked_together(scene: Scene, throws: int, seed: int, keep: Path | None = None,
                     bar: object = None, chunk: int = CHUNK_TOGETHER) -> Together:
    """``throws`` cups thrown together, in chunks of ``chunk`` cups seeded ``(seed, i)``.

    With ``keep``, each chunk is kept there and read back instead of thrown
    (:mod:`dice_env.simulation.chunks`); the result does not depend on ``keep``.
    """
    if keep is not None:
        prepare(keep, {"die": scene.die.name, "cup": asdict(CUP), "chunk": chunk,
                       "scene": hashlib.sha1(repr(scene).encode()).hexdigest(),
                       "contact": asdict(DieContact())})

    def throw(i: int, size: int) -> dict[str, np.ndarray]:
        cups = cup_throws(scene, size, np.random.default_rng([seed, i]))
        return {k: np.asarray(v) for k, v in asdict(throw_together(scene, cups)).items()}

    parts = kept_chunks(throw, throws, chunk, keep, f"together-{seed}", bar, DICE)
    return Together(np.concatenate([p["successes"] for p in parts]),
                    np.sum([p["faces"] for p in parts], axis=0),
                    *(int(sum(p[k] for p in parts)) for k in ("thrown", "leaning", "undecided")),
                    float(sum(p["seconds"] for p in parts)))


def throw_alone(scene: Scene, cups: list[State], bar: object = None) -> Faces:
    """Throw every die of ``cups`` alone (``until="decided"``); count the faces."""
    state = State(*(np.concatenate([getattr(s, f.name) for s in cups]) for f in fields(State)))
    return throw_faces(scene, state, bar)


def excess_per_offset(offsets: np.ndarray, excess: np.ndarray, se: np.ndarray
                      ) -> tuple[float, float]:
    """Slope (per µm) of p(5 or 6) - 1/3 against the centre's offset (µm), and its error.

    Weighted least squares (weights ``1 / se^2``) through the origin.
    """
    x, y, s = (np.asarray(v, dtype=np.float64) for v in (offsets, excess, se))
    weights = 1.0 / s**2
    information = float(np.sum(weights * x * x))
    if information <= 0:
        raise ValueError("offsets must hold at least one die with its centre off the middle")
    return float(np.sum(weights * x * y)) / information, 1.0 / math.sqrt(information)


def offset_for_weldon(slope: float, se: float) -> tuple[float, float, float]:
    """The offset (µm) whose excess the slope puts at Weldon's, its 95% low and high (or inf)."""
    return tuple(EFFECT / s if s > 0 else math.inf
                 for s in (slope, slope + Z95 * se, slope - Z95 * se))


# (key, label, the die's pips); the first is the die thrown together.
VARIANTS = (
    ("drilled16", "16 mm die, drilled pips 3 mm wide, 1 mm deep (`drilled16`)", "drilled16"),
    ("hemispheres", "16 mm die, hemispherical pips 3 mm wide (1.5 mm deep)",
     Pips(radius=1.5e-3, depth=1.5e-3)),
    ("large", "16 mm die, hemispherical pips 4 mm wide (2 mm deep)",
     Pips(radius=2.0e-3, depth=2.0e-3)),
    ("casino19", "19 mm casino die, pips filled flush (`casino19`)", "casino19"),
)


def variant_die(pips: Pips | str) -> Die:
    """The d6 with ``pips`` (a preset name or :class:`Pips`)."""
    return Die.standard("d6", pips=pips)


# ---- the study -------------------------------------------------------------------------------

def run(out: Path = DOCS, quick: bool = False, seed: int = SEED,
        throws: int | None = None, keep: Path | None = None) -> dict[str, float]:
    """Regenerate ``weldon.json``, ``figures/weldon.png`` and ``generated/weldon-*.md`` in ``out``.

    The page's files are rendered from the JSON as written; outside docs/ the page
    ``weldon.md`` with them included is written too (:func:`studies.templates.write_study`).

    ``throws``: the twelve-dice throws thrown together (the single-die samples keep their
    sizes); ``keep``: a folder for their chunks (:func:`chunked_together`), to continue a run.
    """
    sizes = dict(QUICK if quick else FULL)
    if checked_throws(throws, 2) is not None:
        sizes["together"] = int(throws)
    command = "python -m studies weldon" + (" --quick" if quick else "") + (
        f" --throws {throws}" if throws is not None else "")
    rng = np.random.default_rng(seed)
    total = DICE * (sizes["together"] + sizes["alone"] + (len(VARIANTS) - 1) * sizes["variant"])
    bar = progress(total, "weldon die-throws", "die")
    scene = Scene(die=variant_die(VARIANTS[0][2]))
    together = chunked_together(scene, sizes["together"], seed, keep, bar)
    alone = {}
    alone_seconds = time.perf_counter()
    for key, _, pips in VARIANTS:
        die_scene = Scene(die=variant_die(pips))
        n = sizes["alone" if key == VARIANTS[0][0] else "variant"]
        alone[key] = throw_alone(die_scene, cup_throws(die_scene, n, rng), bar)
    alone_seconds = time.perf_counter() - alone_seconds
    bar.close()
    numbers = summarise(together, alone)
    numbers["meta"] = {"command": command, "seed": seed, "threads": numba.get_num_threads(),
                       "sizes": sizes, "seconds_together": together.seconds,
                       "seconds_alone": alone_seconds, "quick": quick}
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "weldon.json", json.dumps(numbers, indent=1) + "\n")
    draw_figures(FIGURES, json.loads(json.dumps(numbers)), out)
    write_study(out, "weldon", list(FILES), {"n": json.loads(json.dumps(numbers))})
    return {"together_p": numbers["together"]["p"], "alone_p": numbers["alone"]["drilled16"]["p"],
            "together_throws": float(together.successes.size),
            "large_p": numbers["alone"]["large"]["p"]}


def summarise(together: Together, alone: dict[str, Faces]) -> dict:
    """Every number of the page (JSON-ready): estimates, comparisons, tests, verdicts."""
    weldon_counts = np.array(WELDON_COUNTS)
    fair = binomial_probabilities(FAIR)
    weldon_share = weldon_counts / weldon_counts.sum()
    out = {"weldon": {"counts": list(WELDON_COUNTS), **asdict(WELDON),
                      "interval": WELDON.interval, "effect": EFFECT,
                      "vs_fair": asdict(chi2_fit(weldon_counts, fair)),
                      "vs_own_p": asdict(chi2_fit(weldon_counts, binomial_probabilities(
                          WELDON.p)))}}
    t = together
    counted = t.successes.size
    entry = {"thrown": t.thrown, "counted": counted, "leaning": t.leaning,
             "undecided": t.undecided, "seconds": t.seconds, "counts": t.counts.tolist(),
             "faces": t.faces.tolist()}
    if counted >= 2:
        est = Estimate.per_throw(t.successes)
        vs_weldon = chi2_homogeneity(t.counts, weldon_counts)
        against_fair = power(counted, weldon_share, fair, vs_weldon)
        variance = float(t.successes.var(ddof=1))
        entry.update({
            **asdict(est), "interval": est.interval,
            "vs_weldon_p": asdict(compare(est, WELDON)),
            "vs_fair_p": asdict(compare(est, Estimate(FAIR, 0.0, 0))),
            "vs_weldon": asdict(vs_weldon), "power_against_fair": against_fair,
            "throws_to_resolve": throws_to_resolve(weldon_share, fair, vs_weldon),
            "vs_fair": asdict(chi2_fit(t.counts, fair)),
            "distribution_verdict": distribution_verdict(vs_weldon, against_fair),
            "dispersion": variance / (DICE * est.p * (1 - est.p)) if 0 < est.p < 1 else 1.0,
            "seconds_per_throw": t.seconds / t.thrown})
    out["together"] = entry
    out["alone"] = {}
    for key, label, pips in VARIANTS:
        faces = alone[key]
        est = Estimate.binomial(int(sum(faces.counts[f - 1] for f in SUCCESS)), faces.ended)
        die = variant_die(pips)
        out["alone"][key] = {
            "label": label, **asdict(est), "interval": est.interval,
            "thrown": faces.ended + faces.undecided, "undecided": faces.undecided,
            "counts": faces.counts.tolist(), "com_um": (np.asarray(die.com) * 1e6).tolist(),
            "edge_mm": die.size * 1e3, "mass_g": die.mass * 1e3,
            "vs_weldon_p": asdict(compare(est, WELDON)),
            "vs_fair_p": asdict(compare(est, Estimate(FAIR, 0.0, 0))),
            "trials_to_resolve": trials_to_resolve(est.p, WELDON)}
    return out


def p_text(entry: dict) -> str:
    """An entry's ``p [low, high]`` (four decimals)."""
    return estimate(entry["p"], entry["interval"], 4)


def cells_text(test: dict) -> str:
    """The pooled cells of a test's numbers: ``0–2, 3, 4, 5–12``."""
    return ", ".join(f"{a}" if a == b else f"{a}–{b}" for a, b in test["cells"])


def _test(test: dict) -> str:
    return (f"chi2 = {test['statistic']:.2f}, {test['dof']} d.f., p = {test['p_value']:.3g} "
            f"(cells {cells_text(test)})")


COMMAND = "python -m studies weldon"
JSON = "docs/weldon.json"  # every number of the page, written by the full study
FILES = ("weldon-run", "weldon-experiment", "weldon-cup", "weldon-samples", "weldon-p",
         "weldon-distribution", "weldon-variants", "weldon-sensitivity", "weldon-faces")


@generated("weldon-run", COMMAND, n=JSON)
def run_text(n: dict) -> str:
    """The command, seed and threads of the run."""
    meta = n["meta"]
    return f"""Generated by `{meta['command']}` (module `studies/weldon.py`, seed {meta['seed']},
{meta['threads']} thread(s)); its numbers are in `weldon.json`, which the
validation page (`validation.md`) reads."""


@generated("weldon-experiment", COMMAND, n=JSON)
def experiment_text(n: dict) -> str:
    """Weldon's own numbers and tests."""
    w = n["weldon"]
    return f"""W. F. R. Weldon threw 12 dice 26,306 times and counted, each time, the dice showing a 5 or a
6 (K. Pearson, Phil. Mag. 50, 157 (1900); A. W. Kemp & C. D. Kemp, The American
Statistician 45, 216 (1991)): {w['n']:,} die-throws, p(5 or 6) = {p_text(w)}
(standard error {w['se']:.4f}), {w['effect']:+.4f} above 1/3. His distribution of successes
against the binomial at 1/3: {_test(w['vs_fair'])}; against the binomial at his own p:
{_test(w['vs_own_p'])}. The usual explanation is the drilled pips: the six face is the
lightest, the one the heaviest, so the centre of mass sits toward the 1-2-3 corner
(`docs/pips.md`) and the 4, 5 and 6 come up a little more often."""  # noqa: E501


@generated("weldon-cup", COMMAND, n=JSON)
def cup_text(n: dict) -> str:
    """How the cup releases the dice (``dice_env.throws.CUP``) and where they meet."""
    cup, block = CUP, CUP_BLOCK
    return f"""The sources we have do not say how the dice were thrown. Twelve dice are thrown at once from
a cup (one hand does not hold twelve), poured out side by side: the dice leave in a
{block[0]} × {block[1]} block, centres {cup.spacing:g} edges apart,
{cup.height[0]:g}–{cup.height[1]:g} edges ({cup.height[0] * 1.6:g}–{cup.height[1] * 1.6:g} cm
for the 16 mm die) above clearing the table; the cup moves at
{cup.speed[0]:g}–{cup.speed[1]:g} edges/s in a uniform horizontal direction, each die adds
its own velocity (normal, {cup.scatter:g} edges/s per component),
spins at {cup.spin[0]:g}–{cup.spin[1]:g} rad/s about a uniform axis and has a uniform
orientation. The table is the default wooden one (`Scene()`, no walls), the dice meet with
the default die–die contact (`DieContact()`, {DieContact().law} friction). Each throw runs
until every face is decided (`until="decided"`)."""  # noqa: E501


@generated("weldon-samples", COMMAND, n=JSON)
def samples_text(n: dict) -> str:
    """The two samples: the dice thrown together, and alone."""
    t, meta, ref = n["together"], n["meta"], n["alone"][VARIANTS[0][0]]
    sizes, per_throw = meta["sizes"], t.get("seconds_per_throw", 0.0)
    return f"""- **(a) Together** (`dice_env.simulation.group.simulate_group`): the twelve `drilled16` dice of each
  cup fall and collide. A throw counts when every die is decided and read within
  {T_MAX_TOGETHER:g} s; a die leaning on another ("cocked") is not read, and its throw is
  left out (Weldon's rule for such dice is not recorded). {t['thrown']:,} throws (Weldon's:
  26,306), in seeded chunks of {CHUNK_TOGETHER}: {t['counted']:,} counted, {t['leaning']:,}
  with a leaning die, {t['undecided']:,} not decided in time;
  {t.get('seconds', 0.0) / 60:.0f} min of wall-clock time on {meta['threads']} thread(s),
  {per_throw:.3f} s per throw, so Weldon's 26,306 throws take about
  {per_throw * 26306 / 3600:.1f} h here. {_together_reach(t)}
- **(b) Alone** (`dice_env.simulate`): every die of further cups (same hand) thrown by
  itself, {DICE} × {sizes['alone']} = {ref['n'] + ref['undecided']:,} die-throws of the
  `drilled16` die and {DICE} × {sizes['variant']} of each other die. Independent by
  construction, so it gives the per-die probability only, at a fraction of the cost."""  # noqa: E501


@generated("weldon-p", COMMAND, n=JSON)
def p_table(n: dict) -> str:
    """p(5 or 6) of Weldon, (a) and (b), their verdicts, and the throws that would resolve it."""
    ref = n["alone"][VARIANTS[0][0]]
    return f"""| | die-throws | p(5 or 6) [95%] | − Weldon | verdict vs Weldon | verdict vs 1/3 |
|---|---|---|---|---|---|
{_p_rows(n)}

(a)'s error is the spread of successes between throws (valid if the dice of a throw depend on
each other); (b)'s and Weldon's are binomial. Verdicts: "differs" when the difference exceeds
the combined 95% half-width; "not resolvable at this sample" when it does not but that
half-width exceeds Weldon's excess over 1/3 ({EFFECT:.4f}); "agrees" otherwise. To resolve
{EFFECT:.4f} against Weldon's own error, the `drilled16` die needs about
**{ref['trials_to_resolve'] or 0:,} die-throws** alone (95% half-width of the difference
below {EFFECT:.4f})."""


@generated("weldon-distribution", COMMAND, n=JSON)
def distribution_text(n: dict) -> str:
    """The successes per throw, Weldon's and (a)'s, and the tests between them."""
    w, t = n["weldon"], n["together"]
    successes = markdown_table(
        "successes | Weldon | share | binomial at 1/3 | (a) together",
        ((k, w["counts"][k], f"{w['counts'][k] / sum(w['counts']):.4f}",
          f"{binomial_probabilities(FAIR)[k]:.4f}", t["counts"][k]) for k in range(DICE + 1)))
    return f"{successes}\n\n{_distribution_text(t)}"


@generated("weldon-variants", COMMAND, n=JSON)
def variants_table(n: dict) -> str:
    """Each die thrown alone: its centre of mass, p(5 or 6) and verdicts."""
    return markdown_table(
        "die | edge (mm) | mass (g) | com x, y, z (µm) | die-throws | p(5 or 6) [95%] | − 1/3 | "
        "vs 1/3 | vs Weldon",
        ((v["label"], f"{v['edge_mm']:.2f}", f"{v['mass_g']:.3f}",
          ", ".join(f"{c:.1f}" for c in v["com_um"]), v["n"], p_text(v),
          f"{v['p'] - FAIR:+.4f}", f"**{v['vs_fair_p']['verdict']}**",
          f"**{v['vs_weldon_p']['verdict']}**") for v in n["alone"].values()))


@generated("weldon-sensitivity", COMMAND, n=JSON)
def sensitivity_text(n: dict) -> str:
    """The excess per µm of offset, and the offset Weldon's excess would need."""
    s, r = sensitivity(n), math.hypot(*n["alone"][VARIANTS[0][0]]["com_um"])
    high = "no upper bound" if math.isinf(s["high"]) else f"{s['high']:.0f} µm"
    return (
        "The pip-drilled dice move their centre of mass along one direction (3 : 1 : 5), so one "
        "number, its offset, measures them. A straight line through the origin (weighted least "
        "squares over the three drilled dice, `excess_per_offset`) gives "
        f"{1e3 * s['slope']:+.3f} ± {1e3 * s['se']:.3f} (10⁻³ per µm; 95%: ± "
        f"{1e3 * Z95 * s['se']:.3f}): {s['slope'] * r:+.4f} for `drilled16` ({r:.1f} µm). "
        f"Weldon's excess of {EFFECT:.4f} would need an offset of about {s['offset']:.0f} µm "
        f"(95%: {s['low']:.0f} µm to {high}) on this throw, {s['offset'] / r:.1f} times the "
        "`drilled16` die's. A reading of the model at Weldon's excess, used in no verdict: his "
        "dice's size and pips are not recorded.")


@generated("weldon-faces", COMMAND, n=JSON)
def faces_table(n: dict) -> str:
    """Each face's share, thrown alone, for the drilled and the casino die."""
    return markdown_table(
        "die | 1 | 2 | 3 | 4 | 5 | 6",
        ((v["label"], *(f"{c / sum(v['counts']):.4f}" for c in v["counts"]))
         for key, v in n["alone"].items() if key in ("drilled16", "casino19")))


def _together_reach(t: dict) -> str:
    """What the together throws can tell at their sample, from their verdict."""
    if "p" not in t:
        return "Too few throws were counted for an estimate."
    if t["vs_weldon_p"]["verdict"] == "not resolvable at this sample":
        return ("They show the distribution of successes and whether the dice of one throw "
                "depend on each other (their collisions); at this sample they cannot resolve "
                "p to Weldon's precision.")
    return ("At this sample they resolve p to Weldon's precision, with the dice colliding, and "
            "show the distribution of successes and whether the dice of one throw depend on "
            "each other.")


def _p_rows(n: dict) -> str:
    w, t, ref = n["weldon"], n["together"], n["alone"][VARIANTS[0][0]]
    rows = [f"| Weldon (1894) | {w['n']:,} | {p_text(w)} | | | |"]
    for label, entry in (("(a) together", t), ("(b) alone", ref)):
        if "p" not in entry:
            rows.append(f"| {label}, `drilled16` | {entry['counted'] * DICE} | too few throws "
                        "| | | |")
            continue
        vs = entry["vs_weldon_p"]
        rows.append(f"| {label}, `drilled16` | {entry['n']:,} | {p_text(entry)} | "
                    f"{vs['difference']:+.4f} | **{vs['verdict']}** | "
                    f"**{entry['vs_fair_p']['verdict']}** |")
    return "\n".join(rows)


def sensitivity(n: dict) -> dict[str, float]:
    """:func:`excess_per_offset` over the drilled dice of :func:`summarise`'s numbers.

    ``slope`` (per µm), ``se``, and Weldon's ``offset`` (µm) with its 95% ``low``, ``high``.
    """
    drilled = [v for key, v in n["alone"].items() if key != "casino19"]
    slope, se = excess_per_offset([math.hypot(*v["com_um"]) for v in drilled],
                                  [v["p"] - FAIR for v in drilled], [v["se"] for v in drilled])
    offset, low, high = offset_for_weldon(slope, se)
    return {"slope": slope, "se": se, "offset": offset, "low": low, "high": high}


def _distribution_text(t: dict) -> str:
    if "p" not in t:
        return "Too few counted throws for the tests."
    needed = (f"{RESOLVING_POWER:g} needs about {t['throws_to_resolve']:,} throws"
              if t["throws_to_resolve"] else "its cells cannot tell the two apart")
    return (
        f"- (a) against Weldon's distribution (2 × cells contingency table): "
        f"{_test(t['vs_weldon'])}: **{t['distribution_verdict']}**. At "
        f"{t['counted']} throws this test detects Weldon's distribution against the "
        f"binomial at 1/3 with probability {t['power_against_fair']:.2f}; {needed}.\n"
        f"- (a) against the binomial at 1/3: {_test(t['vs_fair'])}.\n"
        f"- Dependence between the dice of one throw: the variance of successes per throw is "
        f"{t['dispersion']:.2f} times the binomial's (1 for independent dice; its standard "
        f"error is about {math.sqrt(2 / (t['counted'] - 1)):.2f}).")


def figure(n: dict, path: Path) -> None:
    """Draw ``figures/weldon.png`` from the page's numbers ``n`` (``weldon.json``)."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), layout="constrained")
    k = np.arange(DICE + 1)
    weldon = np.array(n["weldon"]["counts"], float)
    axes[0].bar(k - 0.2, weldon / weldon.sum(), 0.4, label="Weldon (26,306 throws)")
    together = np.array(n["together"]["counts"], float)
    if together.sum():
        axes[0].bar(k + 0.2, together / together.sum(), 0.4,
                    label=f"(a) together ({int(together.sum())} throws)")
    axes[0].plot(k, binomial_probabilities(FAIR), "k.--", lw=1, label="binomial at 1/3")
    axes[0].set(xlabel="dice showing 5 or 6 (of 12)", ylabel="share of throws")
    axes[0].legend(fontsize=8)
    rows = [("Weldon", n["weldon"])]
    if "p" in n["together"]:
        rows.append(("(a) together, drilled16", n["together"]))
    rows += [(f"(b) alone, {key}", v) for key, v in n["alone"].items()]
    for y, (label, entry) in enumerate(rows):
        lo, hi = entry["interval"]
        axes[1].errorbar(entry["p"], y, xerr=[[entry["p"] - lo], [hi - entry["p"]]], fmt="o",
                         color="C3" if label == "Weldon" else "C0", capsize=3)
    axes[1].axvline(FAIR, color="k", ls=":", lw=1)
    axes[1].axvline(n["weldon"]["p"], color="C3", ls=":", lw=1)
    axes[1].set_yticks(range(len(rows)), [label for label, _ in rows], fontsize=8)
    axes[1].invert_yaxis()
    axes[1].set_xlabel("p(5 or 6), 95% interval")
    save_figure(fig, path)


FIGURES = {"weldon": figure}  # the page's figure, drawn by run from its numbers

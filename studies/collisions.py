"""Two dice that meet: what their first collision does to them, and to the outcome's randomness.

``run`` writes ``collisions.md`` and ``figures/collisions.png``: the pairs study's throw thrown
together and each die *apart* (alone, moving bit for bit as in the pair until the dice first
touch); the first collision's change of velocity and spin, and how often a
:data:`PERTURBATION` of the release changes the faces, together against apart.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numba
import numpy as np
from scipy import stats

from dice_env.intervals import wilson
from dice_env.markdown import estimate, markdown_table
from dice_env.model.die import Die
from dice_env.model.scene import Scene
from dice_env.model.surroundings import TRAY
from dice_env.simulation.group import (
    DieContact,
    GroupResult,
    GroupState,
    pair_step,
    simulate_group,
)
from dice_env.throws import HAND, T_TRAY, group_throws, tray_scene
from studies.common import (
    DOCS,
    SEED,
    checked_throws,
    draw_figures,
    progress,
    save_figure,
    write_text,
)
from studies.docs_numbers import generated
from studies.pairs import not_void, simulate_in_batches, void_reasons
from studies.templates import write_study

# Every run takes each step (no flight jumps: a group's jumps depend on all its dice), so that
# a die thrown apart moves bit for bit as in the pair until the dice first touch.
COMMAND = "python -m studies collisions"  # writes docs/generated/collisions-*.md
JSON = "docs/collisions.json"  # every number of the page, written by the full study
FILES = ("collisions-intro", "collisions-throw", "collisions-first-collision",
         "collisions-first-collision-2", "collisions-first-collision-3")
FLIGHT = False

FULL, QUICK, MIN_THROWS = 2400, 24, 20  # throws of the pair: full run, quick run, the fewest
PERTURBATION = 1e-6  # m/s added to die 1's release velocity along x in the perturbed throws
QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)
CDF_LEVELS = np.linspace(0.0, 1.0, 101)  # the figure's cumulative curves, kept in the JSON
BOOTSTRAP = 2000  # bootstrap resamples of the entropy's interval
# The first collision's measures: (key, label, unit).
MEASURES = (("spin_change", "change of |angular velocity|", "rad/s"),
            ("spin_turn", "angle the angular velocity turns", "deg"),
            ("speed_change", "change of |velocity|", "m/s"),
            ("velocity_turn", "angle the velocity turns", "deg"))


def pair_scene() -> tuple[Scene, tuple[Die, Die]]:
    """The tray, with the pair's step fixed so that a die alone steps as in the pair."""
    scene = tray_scene()
    dice = (scene.die, scene.die)
    return scene.with_(dt=pair_step(scene, dice)), dice


def alone(state: GroupState) -> GroupState:
    """Each die of each throw as a throw of its own: (N B, 1), die 0 of every throw first."""
    return GroupState(*(np.concatenate([a[:, i:i + 1] for i in range(state.n_dice)])
                        for a in state._arrays()))


def alone_after(scene: Scene, die: Die, state: GroupState, steps: np.ndarray,
                bar: object = None) -> tuple[np.ndarray, np.ndarray]:
    """Each throw's dice thrown alone for ``steps`` (B,) steps: velocity and spin (B, N, 3)."""
    velocity, spin = np.zeros(state.position.shape), np.zeros(state.position.shape)
    for b, n in enumerate(steps):
        one = GroupState(*(a[b, :, None] for a in state._arrays()))
        run = simulate_group(scene.with_(t_max=int(n) * scene.dt), (die,), one,
                             until="t_max", free_flight=FLIGHT)
        velocity[b], spin[b] = run.final.velocity[:, 0], run.final.angular_velocity[:, 0]
        if bar is not None:
            bar.update(1)
    return velocity, spin


def turn(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """The angle (degrees) between the vectors ``before`` and ``after`` (..., 3)."""
    cross = np.linalg.norm(np.cross(before, after), axis=-1)
    return np.degrees(np.arctan2(cross, np.einsum("...i,...i", before, after)))


def measures(velocity: np.ndarray, spin: np.ndarray) -> dict[str, np.ndarray]:
    """:data:`MEASURES` (B, N) from ``[:, 0]`` to ``[:, 1]`` of velocity, spin (B, 2, N, 3)."""
    speed, rate = np.linalg.norm(velocity, axis=-1), np.linalg.norm(spin, axis=-1)
    return {"spin_change": rate[:, 1] - rate[:, 0], "spin_turn": turn(spin[:, 0], spin[:, 1]),
            "speed_change": speed[:, 1] - speed[:, 0],
            "velocity_turn": turn(velocity[:, 0], velocity[:, 1])}


def quantile_interval(x: np.ndarray, q: float, level: float = 0.95) -> tuple[float, float, float]:
    """The ``q`` quantile of ``x`` and its distribution-free ``level`` interval (binomial)."""
    x, n = np.sort(np.ravel(x)), np.size(x)
    if not 0.0 < q < 1.0 or n == 0:
        raise ValueError(f"q must be in (0, 1) and x non-empty, got q={q!r}, {n} values")
    low, high = stats.binom.ppf([(1 - level) / 2, 1 - (1 - level) / 2], n, q).astype(int)
    return float(np.quantile(x, q)), float(x[max(low - 1, 0)]), float(x[min(high, n - 1)])


def entropy_bits(counts: np.ndarray) -> float:
    """The Shannon entropy (bits) of the distribution with ``counts``."""
    p = np.asarray(counts, float) / np.sum(counts)
    p = p[p > 0]
    return float(-(p * np.log2(p)).sum())


def entropy_estimate(codes: np.ndarray, k: int,
                     rng: np.random.Generator) -> tuple[float, float, float]:
    """The bias-corrected entropy (bits) of ``codes`` (0..k-1) and its 95% interval.

    The plug-in ``H`` sits low, its bootstrap resamples' ``H*`` lower by about as much: the
    estimate is ``2 H - mean(H*)``, the interval ``2 H`` less the 97.5% and 2.5% quantiles of H*.
    """
    plug_in = entropy_bits(np.bincount(codes, minlength=k))
    draws = rng.integers(0, len(codes), (BOOTSTRAP, len(codes)))
    values = [entropy_bits(np.bincount(codes[d], minlength=k)) for d in draws]
    return (float(2 * plug_in - np.mean(values)), float(2 * plug_in - np.quantile(values, 0.975)),
            float(2 * plug_in - np.quantile(values, 0.025)))


def mcnemar(a: np.ndarray, b: np.ndarray) -> float:
    """Exact McNemar p-value that the paired booleans ``a`` and ``b`` are true equally often."""
    a, b = np.asarray(a, bool), np.asarray(b, bool)
    only_a, only_b = int((a & ~b).sum()), int((~a & b).sum())
    if only_a + only_b == 0:
        return 1.0
    return float(stats.binomtest(only_a, only_a + only_b, 0.5).pvalue)


@dataclass
class Collisions:
    """The study's throws.

    ``together``, ``nudged``: the pair, and with die 1 perturbed (B throws); ``met`` (B,): the
    dice touched; ``apart`` (2 M, 1): each met throw's dice alone, die 1 of each first;
    ``apart_nudged`` (M, 1): die 1 alone, perturbed; ``window`` (B,): the first contact ended
    before the throw did; ``apart_velocity``, ``apart_spin`` (W, 2, 3): the dice alone at the
    step it ended; ``dt`` the step (s).
    """

    together: GroupResult
    nudged: GroupResult
    met: np.ndarray
    apart: GroupResult
    apart_nudged: GroupResult
    window: np.ndarray
    apart_velocity: np.ndarray
    apart_spin: np.ndarray
    dt: float

    @property
    def first_contact(self) -> dict[str, dict[str, np.ndarray]]:
        """:func:`measures` across the first contact, ``together`` and ``apart`` (W, 2)."""
        w = self.window
        velocity, spin = self.together.meet_velocity[w], self.together.meet_spin[w]
        apart_v = np.stack([velocity[:, 0], self.apart_velocity], axis=1)
        apart_w = np.stack([spin[:, 0], self.apart_spin], axis=1)
        return {"together": measures(velocity, spin), "apart": measures(apart_v, apart_w)}

    @property
    def in_flight(self) -> np.ndarray:
        """(W,) both dice alone kept their spin over the first contact: neither touched a plane.

        A cube's angular velocity is constant in free flight (isotropic inertia, no torque).
        """
        return np.all(self.apart_spin == self.together.meet_spin[self.window, 0], axis=(1, 2))

    @property
    def counted(self) -> np.ndarray:
        """(M,) met throws counted in all four runs (together, nudged, apart, apart nudged)."""
        m = int(self.met.sum())
        ok = [not_void(void_reasons(r))
              for r in (self.together, self.nudged, self.apart, self.apart_nudged)]
        return ok[0][self.met] & ok[1][self.met] & ok[2][:m] & ok[2][m:] & ok[3]

    def faces(self) -> dict[str, np.ndarray]:
        """Faces (C, 2) of the counted met throws: together, nudged, apart, apart nudged."""
        c, m = self.counted, int(self.met.sum())
        apart = np.stack([self.apart.face[:m, 0], self.apart.face[m:, 0]], axis=1)[c]
        nudged = apart.copy()
        nudged[:, 0] = self.apart_nudged.face[c, 0]
        return {"together": self.together.face[self.met][c],
                "nudged": self.nudged.face[self.met][c], "apart": apart,
                "apart_nudged": nudged}


def throw(n: int, seed: int = SEED, bar: object = None) -> Collisions:
    """``n`` throws of the pair, each together and apart, at rest and perturbed."""
    scene, dice = pair_scene()
    state = group_throws(scene, dice, n, np.random.default_rng(seed))
    nudged = state.copy()
    nudged.velocity[:, 0, 0] += PERTURBATION
    together, twin = (simulate_in_batches(scene, dice, s, bar, until="decided", free_flight=FLIGHT)
                      for s in (state, nudged))
    met = together.meet_steps[:, 0] >= 0
    chosen = GroupState(*(a[met] for a in state._arrays()))
    apart = simulate_in_batches(scene, dice[:1], alone(chosen), until="decided",
                                free_flight=FLIGHT)
    apart_nudged = simulate_in_batches(
        scene, dice[:1], GroupState(*(a[met, :1] for a in nudged._arrays())),
        until="decided", free_flight=FLIGHT)
    window = together.meet_steps[:, 1] >= 0
    if bar is not None:
        bar.total = 2 * n + int(window.sum())
        bar.refresh()
    velocity, spin = alone_after(scene, dice[0], GroupState(*(a[window] for a in state._arrays())),
                                 together.meet_steps[window, 1], bar)
    return Collisions(together, twin, met, apart, apart_nudged, window, velocity, spin,
                      scene.dt)


def run(out: Path = DOCS, quick: bool = False, throws: int | None = None,
        seed: int = SEED) -> dict[str, float]:
    """Regenerate ``collisions.md`` and its figure under ``out`` from ``throws`` pair throws."""
    n = checked_throws(throws, MIN_THROWS, QUICK if quick else FULL)
    bar = progress(2 * n, "pair throws, then first contacts alone")
    start, cpu = time.perf_counter(), time.process_time()
    study = throw(n, seed, bar)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    bar.close()
    numbers = _numbers(study, seconds, cpu, np.random.default_rng(seed))
    data = page_data(numbers, seed)
    draw_figures(FIGURES, data, out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "collisions.json", json.dumps(data, indent=1) + "\n")
    write_study(out, "collisions", list(FILES), {"d": data})
    return {k: v for k, v in numbers.items() if isinstance(v, float)}


def _cdf(x: np.ndarray) -> list[float]:
    """The quantiles of ``x`` at :data:`CDF_LEVELS` to 4 significant digits: a figure's curve."""
    return [float(f"{q:.4g}") for q in np.quantile(x, CDF_LEVELS)]


def _rate(hits: np.ndarray) -> tuple[float, float, float, int, int]:
    """Share of ``hits``, its 95% Wilson interval, the hits and the trials."""
    lo, hi = wilson(int(hits.sum()), len(hits))
    return float(hits.mean()), float(lo), float(hi), int(hits.sum()), len(hits)


def _numbers(study: Collisions, seconds: float, cpu: float,
             rng: np.random.Generator) -> dict[str, object]:
    together, w = study.together, study.window
    faces = study.faces()
    changed = {name: faces[name] != faces[nudged] for name, nudged in
               (("together", "nudged"), ("apart", "apart_nudged"))}
    counted = not_void(void_reasons(together)) & not_void(void_reasons(study.nudged))
    quiet = counted & ~study.met & (study.nudged.meet_steps[:, 0] < 0)
    first = study.first_contact
    n = {
        "throws": float(len(study.met)), "met": float(study.met.mean()),
        "counted_met": float(len(faces["together"])), "windows": float(w.sum()),
        "seconds": seconds, "cpu_seconds": cpu,
        "die_impacts": float(together.die_impacts[study.met, 0].mean()),
        "several_impacts": float((together.die_impacts[study.met, 0] > 1).mean()),
        "contact_ms": float(np.median(np.diff(together.meet_steps[w], axis=1)) * study.dt * 1e3),
        "meet_time": float(np.median(together.meet_steps[w, 0]) * study.dt),
        "in_flight": float(study.in_flight.mean()),
        "spin_before": float(np.median(np.linalg.norm(together.meet_spin[w, 0], axis=-1))),
        "speed_before": float(np.median(np.linalg.norm(together.meet_velocity[w, 0], axis=-1))),
        "change_together": _rate(changed["together"][:, 0]),
        "change_either": _rate(changed["together"].any(axis=1)),
        "change_die2": _rate(changed["together"][:, 1]),
        "change_apart": _rate(changed["apart"][:, 0]),
        "change_quiet": _rate((together.face[:, 0] != study.nudged.face[:, 0])[quiet]),
        "quiet": float(quiet.sum()),
        "mcnemar_p": mcnemar(changed["together"][:, 0], changed["apart"][:, 0]),
    }
    n["change_together_share"] = n["change_together"][0]
    n["change_apart_share"] = n["change_apart"][0]
    for case in ("together", "apart"):
        for key, _, _ in MEASURES:
            n[f"{case}_{key}"] = [quantile_interval(first[case][key], q) for q in QUANTILES]
        n[f"{case}_cdf"] = {key: _cdf(first[case][key]) for key, _, _ in MEASURES}
        n[f"{case}_dice"] = int(first[case][MEASURES[0][0]].size)
        f = faces[case]
        n[f"{case}_face_shares"] = (np.bincount(f.ravel() - 1, minlength=6) / f.size).tolist()
        for die in range(2):
            counts = np.bincount(f[:, die] - 1, minlength=6)
            n[f"{case}_entropy{die + 1}"] = entropy_estimate(f[:, die] - 1, 6, rng)
            n[f"{case}_uniform{die + 1}"] = float(stats.chisquare(counts).pvalue)
        joint = (f[:, 0] - 1) * 6 + f[:, 1] - 1
        n[f"{case}_joint"] = entropy_estimate(joint, 36, rng)
    n["spin_change_median"] = n["together_spin_change"][2][0]
    n["spin_turn_median"] = n["together_spin_turn"][2][0]
    return n


def figure(n: dict, path: Path) -> None:
    """Draw ``figures/collisions.png`` from the page's numbers ``n`` (``collisions.json``)."""
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5), layout="constrained")
    for ax, (key, label, unit) in zip(axes.ravel()[:4], MEASURES, strict=True):
        for case, colour in (("together", "C3"), ("apart", "C0")):
            ax.plot(n[f"{case}_cdf"][key], CDF_LEVELS, color=colour,
                    label=f"{case} ({n[f'{case}_dice']} dice)")
        ax.set(xlabel=f"{label} ({unit})", ylabel="share of dice (cumulative)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0, 0].set_title("across the first die–die contact, and the same steps alone", fontsize=9)
    _plot_changes(axes[1, 1], n)
    _plot_faces(axes[1, 2], n)
    save_figure(fig, path)


def _plot_changes(ax: plt.Axes, n: dict) -> None:
    """Bars: the share of throws whose face the :data:`PERTURBATION` changed."""
    bars = [("together: die 1", n["change_together"]), ("together: die 2", n["change_die2"]),
            ("together: either", n["change_either"]), ("apart: die 1", n["change_apart"]),
            ("never met: die 1", n["change_quiet"])]
    for i, (label, (p, lo, hi, _, _)) in enumerate(bars):
        ax.bar(i, p, color="C3" if label.startswith("together") else "C0")
        ax.errorbar(i, p, yerr=[[p - lo], [hi - p]], color="k", capsize=3)
    ax.set_xticks(range(len(bars)), [b[0] for b in bars], rotation=20, fontsize=8)
    ax.set_ylabel("share of throws whose face changed")
    ax.set_title(f"die 1 released {PERTURBATION:g} m/s faster along x (95% intervals)",
                 fontsize=9)


def _plot_faces(ax: plt.Axes, n: dict) -> None:
    """Bars: the faces of the met throws, together and apart, with their entropies."""
    for offset, (case, colour) in zip((-0.2, 0.2), (("together", "C3"), ("apart", "C0")),
                                      strict=True):
        ax.bar(np.arange(1, 7) + offset, n[f"{case}_face_shares"], width=0.4, color=colour,
               label=f"{case}: {n[f'{case}_entropy1'][0]:.3f} / "
               f"{n[f'{case}_entropy2'][0]:.3f} bits")
    ax.axhline(1 / 6, color="k", ls="--", lw=1)
    ax.set(xlabel="face (both dice)", ylabel="share")
    ax.set_title(f"faces of the met throws (max entropy {np.log2(6):.3f} bits)", fontsize=9)
    ax.legend(fontsize=8)


FIGURES = {"collisions": figure}  # the page's figure, drawn by run from its numbers


def _quantile_rows(n: dict) -> str:
    return markdown_table("measure | case | 5% | 25% | median | 75% | 95%", (
        (f"{label} ({unit})", case, *(f"{v:.3g} [{lo:.3g}, {hi:.3g}]" for v, lo, hi in
                                      n[f"{case}_{key}"]))
        for key, label, unit in MEASURES for case in ("together", "apart")))


def _share(value: tuple) -> str:
    """``share [low, high]``, and ``(hits / trials)`` where given."""
    counts = f" ({value[3]} / {value[4]})" if len(value) > 3 else ""
    return estimate(value[0], value[1:3]) + counts


def page_data(n: dict, seed: int) -> dict:
    """Every number of the page (JSON-ready), kept as ``collisions.json``."""
    thrown = int(n["throws"])
    left = ("change_together_share", "change_apart_share", "spin_change_median",
            "spin_turn_median")  # the headline's copies
    return json.loads(json.dumps({
        "command": f"python -m studies collisions --throws {thrown}", "seed": seed,
        "threads": numba.get_num_threads(), "step_us": pair_scene()[0].dt * 1e6,
        **{k: v for k, v in n.items() if k not in left}}))


def _page(d: dict) -> dict[str, str]:
    """The page's generated files (``docs/generated/collisions-*.md``) from its numbers ``d``."""
    n, seed, thrown = d, d["seed"], int(d["throws"])
    entropies = markdown_table(
        "case | die 1 entropy | die 1 uniform p | die 2 entropy | die 2 uniform p | pair entropy",
        ((case, _share(n[f"{case}_entropy1"]), f"{n[f'{case}_uniform1']:.3g}",
          _share(n[f"{case}_entropy2"]), f"{n[f'{case}_uniform2']:.3g}",
          _share(n[f"{case}_joint"])) for case in ("together", "apart")))
    quick_note = "" if thrown >= FULL else (
        f" (fewer than the default {FULL}: `python -m studies collisions`)")
    verdict = ("more often" if n["change_together"][0] > n["change_apart"][0] else "less often") \
        if n["mcnemar_p"] < 0.01 else "not detectably differently"
    spin, turn_q = n["together_spin_change"], n["together_spin_turn"]
    return {
        "collisions-intro": f"""\
Generated by `{d['command']}`{quick_note} (module
`studies/collisions.py`, seed {seed}): {thrown} throws of the pair, each also thrown
with a perturbed release, and the throws in which the dice met once more with each die
alone: {n['seconds']:.0f} s of wall-clock time on {d['threads']} thread(s) of a
shared machine ({n['cpu_seconds']:.0f} s of this process's CPU time).""",
        "collisions-throw": f"""\
The pairs study's throw (`docs/pairs.md`, `pairs.hand_throws`): two default d6 from one hand
into the {TRAY[0] * 100:g} x {TRAY[1] * 100:g} cm tray, {HAND.spacing * 100:g} cm apart,
{HAND.clearance[0] * 100:g}–{HAND.clearance[1] * 100:g} cm above the table, the hand at
{HAND.speed[0]:g}–{HAND.speed[1]:g} m/s toward the table plus {HAND.noise:g} m/s of noise per
die and component, each die spinning at {HAND.spin[0]:g}–{HAND.spin[1]:g} rad/s about its
own uniform axis from its own uniform orientation; until both faces are decided or
{T_TRAY:g} s. Die 1 is the one at y < 0. The step is the pair's ({d['step_us']:.2f} µs,
`pair_step`) in every run, so a die thrown **apart** (alone, `simulate_group` with one die)
moves bit for bit as in the pair until the dice first touch
(`tests/test_group.py::test_a_die_alone_moves_as_in_its_group_until_the_dice_meet`).

The dice met in **{n['met']:.1%}** of the throws. In a throw where they met they struck each
other {n['die_impacts']:.2f} times on average (`GroupResult.die_impacts`: starts of a contact
at a relative speed of the centres above the rest speed); {n['several_impacts']:.1%} of them
struck more than once.""",
        "collisions-first-collision": f"""\
`GroupResult.meet_velocity` and `meet_spin` hold each die's velocity and angular velocity
(world frame) at the step the dice first touch, before any force of that contact, and at the
step it ends, after its last; {int(n['windows'])} first contacts ended before their throw
did. The first contact came a median {n['meet_time']:.3f} s after the release and lasted a
median {n['contact_ms']:.2f} ms; before it the dice moved at a median {n['speed_before']:.2f}
m/s and spun at {n['spin_before']:.1f} rad/s. In {n['in_flight']:.1%} of the first contacts
neither die alone touched the floor or a wall over the same steps (its spin stayed exactly
the same: a cube's spin is constant in flight): those collisions happened in the air; in the
others a die also felt a plane, and the change below includes it. **Apart** is each die
alone over the same steps: what the throw would have done to it without the other die.""",
        "collisions-first-collision-2": f"""\
{_quantile_rows(n)}

How they react: the collision changes a die's spin by a median {spin[2][0]:+.3g} rad/s
(5–95%: {spin[0][0]:+.3g} to {spin[4][0]:+.3g}) and turns its axis by a median
{turn_q[2][0]:.3g}° (95% of dice under {turn_q[4][0]:.3g}°); alone over the same steps the
median change is {n['apart_spin_change'][2][0]:+.3g} rad/s and the axis turns by
{n['apart_spin_turn'][2][0]:.3g}°. The collision changes a die's speed by a median
{n['together_speed_change'][2][0]:+.3g} m/s (alone: {n['apart_speed_change'][2][0]:+.3g})
and turns its velocity by {n['together_velocity_turn'][2][0]:.3g}° (alone:
{n['apart_velocity_turn'][2][0]:.3g}°).

## Randomness: a perturbation of {PERTURBATION:g} m/s

Every throw again with die 1's release velocity {PERTURBATION:g} m/s higher along x, the
rest the same. Over the **{int(n['counted_met'])}** throws where the dice met and every run
was counted (decided, read, stable, not sunk: together, perturbed, and each die alone, plain
and perturbed), share of throws whose face changed (95% Wilson intervals):

| case | share changed |
|---|---|
| together: die 1 (the perturbed die) | {_share(n['change_together'])} |
| together: die 2 (not perturbed; changed through the collisions) | {_share(n['change_die2'])} |
| together: either die | {_share(n['change_either'])} |
| apart: die 1 alone, same throws | {_share(n['change_apart'])} |
| together, throws where the dice met in neither run ({int(n['quiet'])}): die 1 | {_share(n['change_quiet'])} |

Die 1's face changes {verdict} when the dice meet than when the same die is thrown alone
(exact McNemar test on the same throws: p = {n['mcnemar_p']:.3g}). A face that a change of
{PERTURBATION:g} m/s turns is not determined by any hand; the share is the part of the
outcome that is chaos, not aim.

Entropy of the faces (bits, `collisions.entropy_estimate`: the plug-in entropy corrected for
its sampling bias by the bootstrap [95% basic bootstrap interval]; a fair die
{np.log2(6):.3f}, a fair pair {np.log2(36):.3f}; the plug-in estimate of 36 cells from
{int(n['counted_met'])} throws sits about {35 / (2 * max(n['counted_met'], 1) * np.log(2)):.3f}
bits low by sampling alone) and the chi-square p-value of each die's uniformity:

{entropies}""",  # noqa: E501
        "collisions-first-collision-3": f"""\
Caveats: the die–die material is an estimate (`dice_env/simulation/group.py`, restitution 0.5,
{DieContact().law} friction 0.4); a first contact may be a graze; "apart" is the same die
without the other, so after the first contact it follows another path (its later impacts
differ from the pair's).""",
    }


def _renderer(name: str) -> None:
    generated(name, COMMAND, d=JSON)(lambda d: _page(d)[name])


for _name in FILES:
    _renderer(_name)

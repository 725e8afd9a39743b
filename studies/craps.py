"""Setting the dice for a craps throw: how much control over the seven survives the back wall.

``run(out, quick, throws)`` writes ``out/craps.md`` and ``out/figures/craps.png``: two d6 set
(:func:`sevens_set`) or held at random, thrown by the env's hand (:class:`ThrowTask`) against
the craps table's back wall under several hand noises and speeds.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import matplotlib.pyplot as plt
import numba
import numpy as np
from scipy import stats

from dice_env.envs.throw_task import ThrowTask, make_task
from dice_env.intervals import wilson
from dice_env.markdown import estimate, markdown_table
from dice_env.model import materials
from dice_env.model.scene import Scene
from dice_env.model.surroundings import CRAPS, craps
from dice_env.simulation.group import GroupResult
from dice_env.throws import (
    SET_THROW,
    T_TRAY,
    random_orientations,
    sevens_set,
)
from studies.common import (
    DOCS,
    SEED,
    checked_throws,
    draw_figures,
    error_bars,
    progress,
    save_figure,
    write_text,
)
from studies.docs_numbers import generated
from studies.pairs import (
    TOTALS,
    not_void,
    simulate_in_batches,
    triangle,
    void_reasons,
)
from studies.templates import write_study

# Throws per cell in the full and the quick run; the fewest a run takes per cell.
FULL, QUICK, MIN_THROWS = 300, 8, 10
# Hand noise: each release component's standard deviation as a fraction of its maximum, and
# each die's orientation error (rad per axis).
NOISES, QUICK_NOISES = (1e-5, 1e-4, 1e-3, 1e-2), (1e-5, 1e-2)
SPEEDS, QUICK_SPEEDS = (SET_THROW.speed, 2.8), (SET_THROW.speed,)  # forward release speeds (m/s)
COMMAND = "python -m studies craps"  # writes docs/generated/craps-*.md
JSON = "docs/craps.json"  # every number of the page, written by the full study
FILES = ("craps-intro", "craps-throw", "craps-map", "craps-conclusion")
BACK_WALL = 1  # index in Scene.planes: the floor, then craps()'s walls, the back wall first
SIGNIFICANT = 0.01
HANDS = ("set", "random")
_HEADER = ("noise | speed (m/s) | dice | counted / thrown | sevens | P(seven) [95%] | "
           "binomial p (1/6) | Fisher p (set vs random) | met")


def craps_scene() -> Scene:
    """The craps layout with its back and side walls."""
    return materials.scene("craps").with_(walls=craps(), t_max=T_TRAY)


def hand(noise: float) -> ThrowTask:
    """The env's two-dice hand on the craps scene with hand and orientation noise ``noise``."""
    return make_task(num_dice=2, scene=craps_scene(), release_height=SET_THROW.height,
                     max_speed=SET_THROW.max_speed, max_spin=SET_THROW.max_spin, hand_noise=noise,
                     orientation_noise=noise, until="decided")


def throw_cell(noise: float, speed: float, set_hand: bool, n: int, rng: np.random.Generator,
               bar: object = None) -> GroupResult:
    """``n`` throws of one cell: the dice set (:func:`sevens_set`) or in random orientations."""
    task = hand(noise)
    hands = (np.broadcast_to(sevens_set(), (n, 2, 3, 3)) if set_hand
             else random_orientations(rng, 2 * n).reshape(n, 2, 3, 3))
    state, _ = task.release(np.tile(SET_THROW.action(speed), (n, 1)), hands,
                            task.sample_noise(rng, n))
    return simulate_in_batches(task.scene, task.dice, state, bar, until="decided")


def reasons(result: GroupResult) -> dict[str, np.ndarray]:
    """:func:`~studies.pairs.void_reasons`, and a die that missed the back wall."""
    return {"a die did not touch the back wall": ~result.touched[:, :, BACK_WALL].all(axis=1),
            **void_reasons(result)}


def tally(result: GroupResult) -> dict[str, object]:
    """One cell's counted throws, sevens, totals (11,), voided throws by reason, P(7) and so on.

    ``p7``, ``ci``, ``binom_p``: P(7), its Wilson interval, its binomial p against 1/6.
    """
    why = reasons(result)
    counted = not_void(why)
    total = result.face.sum(axis=1)[counted]
    n, sevens = int(counted.sum()), int((total == 7).sum())
    return {"n": n, "sevens": sevens, "totals": np.bincount(total, minlength=13)[2:],
            "voided": {k: int(v.sum()) for k, v in why.items()}, "thrown": len(counted),
            "met": float((result.overlap > 0).mean()), "p7": sevens / n if n else float("nan"),
            "ci": wilson(sevens, n) if n else np.array([np.nan, np.nan]),
            "binom_p": float(stats.binomtest(sevens, n, 1 / 6).pvalue) if n else float("nan")}


def run(out: Path = DOCS, quick: bool = False, throws: int | None = None,
        seed: int = SEED) -> dict[str, float]:
    """Regenerate ``craps.md`` and its figure under ``out``; return the headline numbers.

    ``throws``: throws per cell (default :data:`FULL`, :data:`QUICK` with ``quick``).
    """
    n = checked_throws(throws, MIN_THROWS, QUICK if quick else FULL)
    noises, speeds = (QUICK_NOISES, QUICK_SPEEDS) if quick else (NOISES, SPEEDS)
    rng = np.random.default_rng(seed)
    bar = progress(n * len(noises) * len(speeds) * len(HANDS), "craps throws", "throw")
    start, cpu = time.perf_counter(), time.process_time()
    cells = {(noise, speed, way): tally(throw_cell(noise, speed, way == "set", n, rng, bar))
             for noise in noises for speed in speeds for way in HANDS}
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    bar.close()
    for (noise, speed, way), c in cells.items():
        if way == "set":  # Fisher's exact test of the set dice against the random ones
            r = cells[(noise, speed, "random")]
            table = [[c["sevens"], c["n"] - c["sevens"]], [r["sevens"], r["n"] - r["sevens"]]]
            c["fisher_p"] = float(stats.fisher_exact(table).pvalue)
    data = page_data(cells, noises, speeds, n, seconds, cpu, seed)
    draw_figures(FIGURES, data, out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "craps.json", json.dumps(data, indent=1) + "\n")
    write_study(out, "craps", list(FILES), {"d": json.loads(json.dumps(data))})
    p7 = {f"p7_{way}_{noise:g}_{speed:g}": c["p7"] for (noise, speed, way), c in cells.items()}
    return {"throws_per_cell": float(n), "seconds": seconds, **p7,
            "voided": sum(c["thrown"] - c["n"] for c in cells.values()) / (n * len(cells))}


def figure(d: dict, path: Path) -> None:
    """Draw ``figures/craps.png`` from the page's numbers ``d`` (``craps.json``)."""
    cells = {(c["noise"], c["speed"], c["way"]): c for c in d["cells"]}
    noises, speeds = d["noises"], d["speeds"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8), layout="constrained")
    ax = axes[0]
    for i, speed in enumerate(speeds):
        for way, style in (("set", "-o"), ("random", "--s")):
            p = np.array([cells[(noise, speed, way)]["p7"] for noise in noises])
            ci = np.array([cells[(noise, speed, way)]["ci"] for noise in noises])
            ax.errorbar(np.array(noises) * (1 + 0.06 * i), p, yerr=error_bars(p, ci), fmt=style,
                        color=f"C{i}", capsize=3, label=f"{way}, {speed:g} m/s")
    ax.axhline(1 / 6, color="k", lw=1, ls=":", label="1/6")
    ax.set(xscale="log", ylabel="P(seven) (95% interval)",
           xlabel="hand noise (fraction of the release's scale; rad of orientation)")
    ax.set_title("the all-sevens set against random orientations", fontsize=10)
    ax.legend(fontsize=8)
    ax = axes[1]
    width = 0.8 / (2 * len(speeds))
    for j, (noise, label) in enumerate(((noises[0], "least"), (noises[-1], "most"))):
        for i, speed in enumerate(speeds):
            c = cells[(noise, speed, "set")]
            ax.bar(TOTALS + (2 * j + i - len(speeds) + 0.5) * width,
                   np.array(c["totals"]) / c["n"], width=width,
                   label=f"set, noise {noise:g} ({label}), {speed:g} m/s")
    ax.plot(TOTALS, triangle(), "o--", color="k", label="2d6")
    ax.set(xticks=TOTALS, xlabel="total of the two dice", ylabel="share of counted throws")
    ax.set_title("totals of the set dice", fontsize=10)
    ax.legend(fontsize=7)
    save_figure(fig, path)


FIGURES = {"craps": figure}  # the page's figure, drawn by run from its numbers


def page_data(cells: dict, noises: tuple, speeds: tuple, n: int, seconds: float, cpu: float,
              seed: int) -> dict:
    """Every number of the page (JSON-ready), kept as ``craps.json``."""
    by_cell = [c["voided"] for c in cells.values()]
    return {"command": "python -m studies craps" + ("" if n == FULL else f" --throws {n}"),
            "seed": seed, "throws": n, "seconds": seconds, "cpu": cpu,
            "threads": numba.get_num_threads(), "noises": list(noises), "speeds": list(speeds),
            "voided": {k: int(sum(v[k] for v in by_cell)) for k in by_cell[0]},
            "cells": [{"noise": noise, "speed": speed, "way": way, "n": int(c["n"]),
                       "thrown": int(c["thrown"]), "sevens": int(c["sevens"]),
                       "p7": float(c["p7"]), "ci": [float(x) for x in c["ci"]],
                       "binom_p": c["binom_p"], "fisher_p": c.get("fisher_p"),
                       "met": c["met"], "totals": [int(t) for t in c["totals"]]}
                      for (noise, speed, way), c in cells.items()]}


@generated("craps-intro", COMMAND, d=JSON)
def intro_text(d: dict) -> str:
    """The run: command, seed, throws and time."""
    thrown = sum(c["thrown"] for c in d["cells"])
    return f"""\
Generated by `{d['command']}` (module `studies/craps.py`, seed {d['seed']}): {d['throws']} throws per
cell, {thrown} in all, in {d['seconds']:.0f} s of wall-clock time on {d['threads']}
thread(s) of a shared machine ({d['cpu']:.0f} s of this process's CPU time)."""  # noqa: E501


@generated("craps-throw", COMMAND, d=JSON)
def throw_text(d: dict) -> str:
    """The throw, the set, and the voided throws."""
    scene, thrown = craps_scene(), sum(c["thrown"] for c in d["cells"])
    voided_rows = markdown_table("reason | throws | share",
                                 ((k, v, f"{v / thrown:.2%}") for k, v in d["voided"].items()))
    return f"""\
Two default d6 leave the env's hand (`make_task(num_dice=2, ...)`,
`ThrowTask.release`: side by side across the throw, {SET_THROW.height * 100:g} cm above
the table) on the craps layout (`materials.scene("craps")`: restitution 0.40, friction 0.20,
S = {scene.ground.stiffness:g} N/m) toward the back wall {CRAPS[0]:g} m ahead, between side
walls {CRAPS[1]:g} m apart (`surroundings.craps()`, walls of the default table's material).
The hand moves at the throw speed along x (the table's length) and {SET_THROW.lift:g} m/s up, with
{SET_THROW.backspin:g} rad/s of backspin (about -y, the axis the dice roll on); each die adds its own
hand noise: a standard normal times the noise level times {SET_THROW.max_speed:g} m/s on each velocity
component and times {SET_THROW.max_spin:g} rad/s on each spin component, and a rotation of its
orientation by a standard normal times the noise level (rad) about each axis.

**Set** dice leave the hand in the "all-sevens" set (`dice_env.throws.sevens_set`): die 2 is die 1
turned half a turn about the roll axis, so die 2's top is die 1's bottom and, as long as the
two turn alike about that axis, every face up adds up to seven; a dice setter's come-out set.
**Random** dice each leave in a uniform random orientation. Each throw runs until both faces
are decided or {T_TRAY:g} s.

**Voided**: a throw in which either die never touched the back wall (`GroupResult.touched`:
whether a die had a corner in each plane at some step; plane {BACK_WALL} of `Scene.planes` is
the back wall), or as in the pairs study:

{voided_rows}"""  # noqa: E501


@generated("craps-map", COMMAND, d=JSON)
def map_table(d: dict) -> str:
    """P(seven) in every cell: noise, speed and hand."""
    return markdown_table(_HEADER, (
        (f"{c['noise']:g}", f"{c['speed']:g}", c["way"], f"{c['n']} / {c['thrown']}",
         c["sevens"], estimate(c["p7"], c["ci"]), f"{c['binom_p']:.3g}",
         f"{c['fisher_p']:.3g}" if c["way"] == "set" else "", f"{c['met']:.2f}")
        for c in d["cells"]))


@generated("craps-conclusion", COMMAND, d=JSON)
def conclusion_text(d: dict) -> str:
    """Where the set controls P(seven), where random dice depart from 1/6, and the caveats."""
    cells, n, noises, speeds = d["cells"], d["throws"], d["noises"], d["speeds"]
    detected = [c for c in cells if c["binom_p"] < SIGNIFICANT]
    controlled = sorted({(c["noise"], c["speed"]) for c in detected if c["way"] == "set"})
    random_off = [c for c in detected if c["way"] == "random"]
    lost = [noise for noise in noises
            if all(c["binom_p"] >= SIGNIFICANT for c in cells
                   if c["noise"] == noise and c["way"] == "set")]
    return f"""\
At the {SIGNIFICANT:.0%} level, P(seven) departs from 1/6 for the set dice at (noise, speed)
{', '.join(f'({a:g}, {b:g} m/s)' for a, b in controlled) or 'none of the cells'}, and for
random dice in {len(random_off)} of the {len(noises) * len(speeds)} random cells (none
expected but by chance). At the noise levels {', '.join(f'{x:g}' for x in lost) or 'none'}
the set gives no detectable control at any speed tested. The {len(cells)} tests are not
corrected for multiplicity; a single p-value just under {SIGNIFICANT} is weak evidence.

Caveats: a flat back wall (a casino's has rubber pyramids, made to randomise further); the
wall's material is the default table's; the hand model is the env's, one noise level for
velocity, spin and orientation together; {n} throws per cell resolve a P(seven) to about
±{1.96 * np.sqrt(1 / 6 * 5 / 6 / n):.3f} around 1/6."""

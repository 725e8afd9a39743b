"""Table materials: how felt, wood, glass and a craps table change the throw's outcome.

``run(out, quick, throws)`` writes ``out/materials.md`` and ``out/figures/materials.png``: the
default die on each preset of :mod:`dice_env.model.materials`, the same releases on every one.
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
from dice_env.model import materials
from dice_env.simulation.calibration import measured_restitution
from dice_env.simulation.simulate import UP, State, simulate
from dice_env.throws import BATCH, VIGOROUS, Faces, Vigour, batches, counted, vigorous_throws
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
from studies.cuboids import GENTLE
from studies.docs_numbers import generated
from studies.fairness import T_MAX, throw_energy
from studies.templates import write_study

FULL, QUICK = (10_000, 5_000), (60, 40)  # throws per material: (vigorous, gentle)
COMMAND = "python -m studies materials"  # writes docs/generated/materials-*.md
JSON = "docs/materials.json"  # every number of the page, written by the full study
FILES = ("materials-intro", "materials-presets", "materials-outcomes", "materials-outcomes-2",
         "materials-memory-release-orientation", "materials-against-kapitaniak-et")
KINDS = (("vigorous", VIGOROUS), ("gentle", GENTLE))  # (label, hand) of the two kinds of throw
SIGNIFICANT = 0.01  # p-value below which the materials' memories count as different
HEADER = ("throws | preset | counted | not decided | faces 1–6 | chi2 | p | mean impacts | "
          "time to decision, mean / median (s) | sink (mm)")


@dataclass
class MaterialThrows:
    """One material's throws of one kind.

    ``impacts`` and ``time`` (s, to the decision) per counted throw; ``down``/``up``: counted
    throws resting on the face that was down/up at release; ``sink``: deepest sink per throw (m).
    """

    faces: Faces
    impacts: np.ndarray
    time: np.ndarray
    down: int
    up: int
    sink: np.ndarray

    def memory(self, which: str) -> tuple[float, np.ndarray]:
        """P(resting on the release-``which`` face) and its 95% Wilson interval."""
        hits = self.down if which == "down" else self.up
        return hits / self.faces.ended, wilson(hits, self.faces.ended)


def throw(scene: object, state: State, bar: object = None) -> MaterialThrows:
    """Throw ``state`` on ``scene`` until each face is decided, in batches of ``BATCH``."""
    die = scene.die
    parts = []
    for chunk in batches(state, BATCH, bar):
        res = simulate(scene, chunk, t_max=T_MAX, until="decided")
        rests_on = die.face_read(res.final.orientation, -UP)
        parts.append((counted(res), res.face, res.impacts, res.rest_time,
                      rests_on == die.face_read(chunk.orientation, -UP),
                      rests_on == die.face_read(chunk.orientation, UP), res.max_penetration))
    ok, face, impacts, when, down, up, sink = map(np.concatenate, zip(*parts, strict=True))
    faces = Faces.of(np.bincount(face[ok], minlength=die.n_faces + 1)[1:], len(ok))
    return MaterialThrows(faces, impacts[ok], when[ok], int(down[ok].sum()), int(up[ok].sum()),
                          sink)


def run(out: Path = DOCS, quick: bool = False, throws: int | None = None,
        seed: int = SEED) -> dict[str, float]:
    """Regenerate ``materials.md`` and its figure under ``out``; return the headline numbers.

    ``throws``: vigorous throws per material (the gentle ones are half as many).
    """
    throws = checked_throws(throws, 2)
    sizes = (throws, throws // 2) if throws is not None else QUICK if quick else FULL
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    base = materials.scene("wood")
    releases = {label: vigorous_throws(base, n, rng, hand)
                for (label, hand), n in zip(KINDS, sizes, strict=True)}
    restitution = {name: measured_restitution(materials.scene(name))
                   for name in materials.MATERIALS}
    bar = progress(len(materials.MATERIALS) * sum(sizes), "material throws", "throw")
    results = {name: {label: throw(materials.scene(name, t_max=T_MAX), state, bar)
                      for label, state in releases.items()}
               for name in materials.MATERIALS}
    bar.close()
    seconds = time.perf_counter() - start
    energy = {label: float(np.median(throw_energy(base, state)))
              for label, state in releases.items()}
    data = page_data(results, restitution, energy, sizes, seconds, seed)
    draw_figures(FIGURES, data, out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "materials.json", json.dumps(data, indent=1) + "\n")
    write_study(out, "materials", list(FILES), {"d": json.loads(json.dumps(data))})
    numbers = {"seconds": seconds}
    for name, kinds in results.items():
        numbers[f"{name}_restitution"] = restitution[name]
        for label, result in kinds.items():
            numbers[f"{name}_{label}_p"] = result.faces.p_value
            numbers[f"{name}_{label}_down"] = result.memory("down")[0]
            numbers[f"{name}_{label}_impacts"] = float(result.impacts.mean())
    return numbers


def memory_differs(results: dict, label: str, which: str = "down") -> float:
    """Chi-square p-value that P(release-``which`` face) is one on all materials (conservative)."""
    hits = np.array([getattr(kinds[label], which) for kinds in results.values()])
    ended = np.array([kinds[label].faces.ended for kinds in results.values()])
    return float(stats.chi2_contingency(np.stack([hits, ended - hits]))[1])


def figure(d: dict, path: Path) -> None:
    """Draw ``figures/materials.png`` from the page's numbers ``d`` (``materials.json``)."""
    rows = {(r["throws"], r["preset"]): r for r in d["rows"]}
    names = list(d["restitution"])
    x = np.arange(len(names))
    fig, axes = plt.subplots(1, 3, figsize=(14, 4), layout="constrained")
    for k, (label, _) in enumerate(KINDS):
        shift = (k - 0.5) * 0.3
        axes[0].bar(x + shift, [rows[label, n]["impacts"] for n in names], 0.3, label=label)
        for which, marker in (("down", "o"), ("up", "s")):
            p, lo, hi = np.array([rows[label, n][which] for n in names]).T
            axes[1].errorbar(x + shift, p, yerr=error_bars(p, np.stack([lo, hi], axis=1)),
                             fmt=marker, capsize=3, color=f"C{k}",
                             label=f"{label}: rests on release-{which} face")
    for k, name in enumerate(names):
        row = rows["vigorous", name]
        shares = np.array(row["counts"]) / row["counted"]
        axes[2].errorbar(np.arange(1, 7) + (k - 1.5) * 0.15, shares,
                         yerr=error_bars(shares, wilson(np.array(row["counts"]), row["counted"])),
                         fmt="o", capsize=2, label=name)
    axes[0].set_ylabel("mean impacts to the decision")
    axes[1].set_ylabel("probability (95% interval)")
    axes[1].axhline(1 / 6, color="k", ls=":", lw=1)
    for ax in axes[:2]:
        ax.set_xticks(x, names)
        ax.legend(fontsize=8)
    axes[2].axhline(1 / 6, color="k", ls=":", lw=1)
    axes[2].set(xlabel="face up (vigorous throws)", ylabel="share (95% interval)")
    axes[2].legend(fontsize=8)
    save_figure(fig, path)


FIGURES = {"materials": figure}  # the page's figure, drawn by run from its numbers


def _hand(v: Vigour) -> str:
    return (f"released {v.clearance[0]:g}–{v.clearance[1]:g} edges above touching, "
            f"{v.speed[0]:g}–{v.speed[1]:g} edges/s toward the table, {v.spin[0]:g}–"
            f"{v.spin[1]:g} rad/s about a uniform axis, orientation uniform")


def _kapitaniak(d: dict) -> str:
    """Whether the bouncier tables give more impacts and less memory, as a sentence."""
    restitution = d["restitution"]
    order = sorted(restitution, key=restitution.get)
    lines = []
    for label, _ in KINDS:
        rows = {r["preset"]: r for r in d["rows"] if r["throws"] == label}
        impacts = [rows[n]["impacts"] for n in order]
        down = [rows[n]["down"][0] for n in order]
        extremes = int(np.argmax(down)) == 0 and int(np.argmin(down)) == len(down) - 1
        p = d["memory_p"][label]
        memory = (f"the least bouncy keeps {'the most' if extremes else 'not the most'} "
                  f"memory and the most bouncy {'the least' if extremes else 'not the least'}"
                  if p < SIGNIFICANT else
                  f"the materials' memories do not differ at the {SIGNIFICANT:.0%} level, "
                  f"p = {p:.3g}")
        lines.append(f"- {label} throws, materials from the least to the most bouncy "
                     f"({', '.join(order)}): mean impacts "
                     f"{', '.join(f'{i:.1f}' for i in impacts)} "
                     f"({_monotonic(impacts, 'rising')}); P(release-down) "
                     f"{', '.join(f'{d:.3f}' for d in down)} "
                     f"({_monotonic(-np.array(down), 'falling')}; {memory}).")
    return "\n".join(lines)


def _monotonic(values: list[float] | np.ndarray, word: str) -> str:
    """``word`` + " throughout" if ``values`` rise strictly, else which steps break it."""
    steps = np.diff(values)
    if np.all(steps > 0):
        return f"{word} throughout"
    return f"{word} in {int(np.sum(steps > 0))} of {len(steps)} steps"


def _row(label: str, name: str, r: MaterialThrows) -> dict:
    """The numbers of ``name``'s throws of kind ``label`` (JSON-ready)."""
    f = r.faces
    down, up = r.memory("down"), r.memory("up")
    return {"throws": label, "preset": name, "counted": int(f.ended),
            "undecided": int(f.undecided), "shares": [float(s) for s in f.shares],
            "counts": [int(c) for c in f.counts],
            "chi2": float(f.chi2), "p": float(f.p_value), "impacts": float(r.impacts.mean()),
            "time": [float(r.time.mean()), float(np.median(r.time))],
            "sink_mm": [float(np.quantile(r.sink, 0.99) * 1e3), float(r.sink.max() * 1e3)],
            "down": [float(down[0]), *(float(x) for x in down[1])],
            "up": [float(up[0]), *(float(x) for x in up[1])]}


def page_data(results: dict, restitution: dict, energy: dict, sizes: tuple, seconds: float,
              seed: int) -> dict:
    """Every number of the page (JSON-ready), kept as ``materials.json``."""
    return {"command": COMMAND, "seed": seed, "seconds": seconds,
            "threads": numba.get_num_threads(), "sizes": list(sizes),
            "energy": {k: float(v) for k, v in energy.items()},
            "restitution": {k: float(v) for k, v in restitution.items()},
            "memory_p": {label: memory_differs(results, label) for label, _ in KINDS},
            "rows": [_row(label, name, kinds[label])
                     for label, _ in KINDS for name, kinds in results.items()]}


@generated("materials-intro", COMMAND, d=JSON)
def intro_text(d: dict) -> str:
    """The run: command, seed, time and throws."""
    return f"""\
Generated by `{d['command']}` (module `studies/materials.py`,
seed {d['seed']}); the presets are in `dice_env/model/materials.py` (`materials.ground("felt")`,
`materials.scene("glass")`). The run took **{d['seconds']:.0f} s** on {d['threads']}
thread(s) ({d['sizes'][0]} vigorous and {d['sizes'][1]} gentle throws per material)."""


@generated("materials-presets", COMMAND, d=JSON)
def presets_text(d: dict) -> str:
    """The presets (from the code) and their measured restitution."""
    presets = markdown_table(
        "preset | e target | e measured | mu | S (N/m) | D (N s/m) | step (µs) | source",
        ((name, f"{m.restitution:.2f}", f"{d['restitution'][name]:.4f}", f"{m.friction:.2f}",
          f"{m.stiffness:.0e}", f"{materials.ground(name).damping:.4g}",
          f"{materials.scene(name).step * 1e6:.1f}", m.source)
         for name, m in materials.MATERIALS.items()))
    die = materials.scene("wood").die
    return f"""\
Restitution e (normal, flat landing) and sliding friction mu of a plastic die on each surface,
with their sources; "estimate" marks a value no measurement gives directly, and the reason.
The damping D gives the target e for the default die ({die.mass * 1e3:g} g), from the
clipped spring-dashpot relation of `dice_env.model.defaults`; e measured is what the simulator
produces (`calibration.measured_restitution`: the die dropped flat at 1 m/s, rebound speed
over impact speed, `tests/test_materials.py` holds it within 0.01 of the target). The step
is the scene's automatic one (it grows as S falls).

{presets}"""


@generated("materials-outcomes", COMMAND, d=JSON)
def outcomes_text(d: dict) -> str:
    """The two throws and the release energies."""
    die = materials.scene("wood").die
    return f"""\
The same releases on every material: **vigorous**, the fairness study's hand throws
({_hand(VIGOROUS)}; median energy {d['energy']['vigorous']:.1f} m g a), and **gentle**, the cuboid
study's ({_hand(GENTLE)}; median {d['energy']['gentle']:.2f} m g a); edges of the default
{die.size * 1e3:g} mm die. Each throw runs until its face is decided (`until="decided"`:
too little energy left to change face) or {T_MAX:g} s; impacts and time are counted up to the
decision. Faces: shares of faces 1–6 among the counted throws, chi-square test of
uniformity (5 degrees of freedom). Sink: the deepest corner below the table surface, 99th
percentile / maximum."""


@generated("materials-outcomes-2", COMMAND, d=JSON)
def outcomes_table(d: dict) -> str:
    """Each material's and throw's outcome."""
    return markdown_table(HEADER, (
        (r["throws"], r["preset"], r["counted"], r["undecided"],
         " ".join(f"{s:.3f}" for s in r["shares"]), f"{r['chi2']:.2f}", f"{r['p']:.3g}",
         f"{r['impacts']:.2f}", f"{r['time'][0]:.3f} / {r['time'][1]:.3f}",
         f"{r['sink_mm'][0]:.2f} / {r['sink_mm'][1]:.2f}") for r in d["rows"]))


@generated("materials-memory-release-orientation", COMMAND, d=JSON)
def memory_text(d: dict) -> str:
    """P(release-down face) and P(release-up face), and the test that the materials differ."""
    memory = markdown_table("throws | preset | P(release-down face) | P(release-up face)", (
        (r["throws"], r["preset"], estimate(r["down"][0], r["down"][1:]),
         estimate(r["up"][0], r["up"][1:])) for r in d["rows"]))
    return f"""\
P(the die rests on the face that was down at release) and P(it rests on the face that was up
at release, i.e. lands upside down), as `docs/fairness.md` measures them, with 95% Wilson
intervals; 1/6 = 0.167 is no memory. Chi-square test that the release-down probability is the
same on all four materials: vigorous p = {d['memory_p']['vigorous']:.3g}, gentle
p = {d['memory_p']['gentle']:.3g} (conservative: the materials share their releases,
which correlates their outcomes and narrows their true differences' spread).

{memory}"""


@generated("materials-against-kapitaniak-et", COMMAND, d=JSON)
def kapitaniak_text(d: dict) -> str:
    """Whether the bouncier tables give more impacts and less memory."""
    return _kapitaniak(d)

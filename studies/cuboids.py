"""Square-cuboid dice, a prediction: the chance of landing on a square face against x/y.

``run(out, quick, throws)`` writes ``out/cuboids.md`` and ``out/figures/cuboids.png``;
:func:`read_page` reads the page's numbers back (the validation page quotes them). The square
faces of ``Die.cuboid((y, y, x))`` are 1 and 6; every cuboid keeps the default die's volume.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import NamedTuple

import matplotlib.pyplot as plt
import numpy as np

from dice_env.intervals import wilson
from dice_env.markdown import estimate, markdown_table
from dice_env.model.defaults import DIE_EDGE, DIE_MASS, RESTITUTION, damping_for_restitution
from dice_env.model.die import Die
from dice_env.model.scene import Ground, Scene
from dice_env.throws import VIGOROUS, Vigour, hand_throws, throw_faces
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
from studies.templates import expand, write_study

# x/y of the shapes thrown (1 is the cube).
COMMAND = "python -m studies cuboids"  # writes docs/generated/cuboids-*.md
JSON = "docs/cuboids.json"  # every number of the page, written by the full study
FILES = ("cuboids-intro", "cuboids-intro-2", "cuboids-intro-3", "cuboids-intro-4")
RATIOS = (0.45, 0.55, 0.65, 0.8, 0.9, 1.0, 1.1, 1.25, 1.5, 1.8, 2.2, 2.7)
QUICK_RATIOS = (0.45, 1.0, 2.7)
FULL, QUICK = 4000, 100  # throws per shape and condition
# Gentle hand throws (in edges, as VIGOROUS): 1.6–6.4 cm up, 0.08–0.4 m/s, 2–20 rad/s.
GENTLE = Vigour(clearance=(1.0, 4.0), speed=(5.0, 25.0), spin=(2.0, 20.0))
# A soft, slippery cloth: a tenth of the wooden table's stiffness, half its friction, the
# damping recomputed for the same restitution.
SOFT_STIFFNESS, SOFT_FRICTION = 1e4, 0.2
SOFT = Ground(stiffness=SOFT_STIFFNESS, friction=SOFT_FRICTION,
              damping=damping_for_restitution(RESTITUTION, SOFT_STIFFNESS, DIE_MASS))
# (label, throws, table); the first is the prediction of record.
CONDITIONS = (("vigorous, wooden table", VIGOROUS, Ground()),
              ("gentle, wooden table", GENTLE, Ground()),
              ("vigorous, soft cloth", VIGOROUS, SOFT),
              ("gentle, soft cloth", GENTLE, SOFT))
SQUARE_FACES = (1, 6)


def square_cuboid(ratio: float, volume: float = DIE_EDGE**3) -> Die:
    """The square cuboid of ``x/y = ratio`` and the given volume (m^3): ``(y, y, x)``."""
    if not (isinstance(ratio, (int, float)) and math.isfinite(ratio) and ratio > 0):
        raise ValueError(f"ratio must be a finite number > 0, got {ratio!r}")
    y = (volume / ratio) ** (1.0 / 3.0)
    return Die.cuboid((y, y, ratio * y))


def solid_angle_share(ratio: float) -> float:
    """Share of all directions the square faces subtend from the centre (a naive reference)."""
    a, d = 0.5, 0.5 * ratio
    omega = 4.0 * math.atan(a * a / (d * math.sqrt(2 * a * a + d * d)))
    return 2.0 * omega / (4.0 * math.pi)


def run(out: Path = DOCS, quick: bool = False, seed: int = SEED,
        throws: int | None = None) -> dict[str, float]:
    """Regenerate ``cuboids.md`` and ``figures/cuboids.png`` under ``out``; the headline numbers.

    ``throws`` per shape and condition (default :data:`FULL`, or :data:`QUICK` with ``quick``).
    """
    n = checked_throws(throws, 20, QUICK if quick else FULL)
    ratios = QUICK_RATIOS if quick else RATIOS
    rng = np.random.default_rng(seed)
    bar = progress(len(ratios) * len(CONDITIONS) * n, "cuboid throws", "throw")
    table = {}
    for label, vigour, ground in CONDITIONS:
        for ratio in ratios:
            scene = Scene(die=square_cuboid(ratio), ground=ground)
            faces = throw_faces(scene, hand_throws(scene, n, rng, vigour), bar)
            hits = int(sum(faces.counts[f - 1] for f in SQUARE_FACES))  # on a square face
            table[label, ratio] = (faces, hits / faces.ended, wilson(hits, faces.ended))
    bar.close()
    data = page_data(table, ratios, n, seed, quick, throws)
    draw_figures(FIGURES, data, out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "cuboids.json", json.dumps(data, indent=1) + "\n")
    write_study(out, "cuboids", list(FILES), {"d": json.loads(json.dumps(data))})
    first = CONDITIONS[0][0]
    _, cube_p, (cube_lo, cube_hi) = table[first, 1.0]
    return {**{f"p_{r:g}": table[first, r][1] for r in ratios}, "cube_p": cube_p,
            "cube_lo": float(cube_lo), "cube_hi": float(cube_hi),
            "undecided": max(f.undecided for f, _, _ in table.values()) / n}


class Page(NamedTuple):
    """A ``cuboids.md``'s numbers; ``table[label][ratio]``: P(square face) and its 95% interval."""

    command: str
    seed: int
    throws: int
    table: dict[str, dict[float, tuple[float, float, float]]]


def read_page(path: Path) -> Page:
    """The numbers of the page ``path`` written by :func:`run` (ValueError if it is not one)."""
    text = expand(Path(path).read_text(), Path(path).parent / "generated")  # files included
    head = re.search(r"Generated by `([^`]+)` \(module `studies/cuboids.py`, seed "
                     r"(\d+)\);\n(\d+) throws per shape and condition", text)
    lines = [line for line in text.splitlines() if line.startswith("| ")]
    if head is None or not lines or not lines[0].startswith("| x/y |"):
        raise ValueError(f"path must be a page written by studies.cuboids, got {path}")
    labels = [c.strip() for c in lines[0].strip("|").split("|")][3:]
    table: dict[str, dict[float, tuple[float, float, float]]] = {label: {} for label in labels}
    for line in lines[1:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        if not re.fullmatch(r"[\d.]+", cells[0]):
            break
        for label, cell in zip(labels, cells[3:], strict=True):
            p, lo, hi = (float(v) for v in re.findall(r"[\d.]+", cell))
            table[label][float(cells[0])] = (p, lo, hi)
    return Page(head.group(1), int(head.group(2)), int(head.group(3)), table)


def figure(d: dict, path: Path) -> None:
    """Draw ``figures/cuboids.png`` from the page's numbers ``d`` (``cuboids.json``)."""
    ratios = d["ratios"]
    fig, ax = plt.subplots(figsize=(8, 5), layout="constrained")
    fine = np.geomspace(ratios[0], ratios[-1], 200)
    ax.plot(fine, [solid_angle_share(r) for r in fine], color="0.5", ls="--", lw=1,
            label="solid-angle share (naive reference)")
    for k, (label, shares) in enumerate(d["shares"].items()):
        p, lo, hi = np.array(shares).T
        ax.plot(ratios, p, "o-", color=f"C{k}", ms=4, label=label)
        ax.fill_between(ratios, lo, hi, color=f"C{k}", alpha=0.2, lw=0)
    ax.axhline(1 / 3, color="k", ls=":", lw=1)
    ax.axvline(1.0, color="k", ls=":", lw=1)
    ax.set_xscale("log")
    ax.set_xticks(ratios)
    ax.set_xticklabels([f"{r:g}" for r in ratios])
    ax.minorticks_off()
    ax.set(xlabel="x / y (height along the square faces' normal / side of the square)",
           ylabel="P(lands on a square face), 95% band", ylim=(0, 1),
           title=f"Square-cuboid dice, {d['throws']} throws per point "
           "(prediction, nothing fitted)")
    ax.legend(fontsize=8)
    save_figure(fig, path)


FIGURES = {"cuboids": figure}  # the page's figure, drawn by run from its numbers


def page_data(table: dict, ratios: tuple[float, ...], n: int, seed: int, quick: bool,
              throws: int | None) -> dict:
    """Every number of the page (JSON-ready), kept as ``cuboids.json``."""
    labels = [label for label, _, _ in CONDITIONS]
    return {"command": "python -m studies cuboids" + (" --quick" if quick else "") + (
                f" --throws {throws}" if throws is not None else ""),
            "seed": seed, "throws": n, "ratios": list(ratios),
            "shares": {label: [[float(table[label, r][1]), *map(float, table[label, r][2])]
                               for r in ratios] for label in labels},
            "undecided": {label: int(sum(table[label, r][0].undecided for r in ratios))
                          for label in labels}}


@generated("cuboids-intro", COMMAND, d=JSON)
def intro_text(d: dict) -> str:
    """The run: command, seed and throws."""
    return f"""\
Generated by `{d['command']}` (module `studies/cuboids.py`, seed {d['seed']});
{d['throws']} throws per shape and condition. **A prediction: nothing is fitted to measured numbers.**"""  # noqa: E501


@generated("cuboids-intro-2", COMMAND, d=JSON)
def conditions_text(d: dict) -> str:
    """The four conditions: two hands, two tables (the module's constants)."""
    v, s, g = VIGOROUS, GENTLE, Ground()
    return f"""\
- **vigorous**: released {v.clearance[0]:g}–{v.clearance[1]:g} edges above touching
  ({v.clearance[0] * 1.6:g}–{v.clearance[1] * 1.6:g} cm), {v.speed[0]:g}–{v.speed[1]:g}
  edges/s toward the table, {v.spin[0]:g}–{v.spin[1]:g} rad/s (the throws of
  `fairness.md`);
- **gentle**: {s.clearance[0]:g}–{s.clearance[1]:g} edges, {s.speed[0]:g}–{s.speed[1]:g}
  edges/s, {s.spin[0]:g}–{s.spin[1]:g} rad/s;
- **wooden table** (the default): S = {g.stiffness:g} N/m, D = {g.damping:.4g} N s/m,
  mu = {g.friction:g} per vertex, restitution {RESTITUTION:g};
- **soft cloth**: S = {SOFT.stiffness:g} N/m (a tenth), mu = {SOFT.friction:g} (half),
  D = {SOFT.damping:.4g} N s/m (the same restitution)."""


@generated("cuboids-intro-3", COMMAND, d=JSON)
def shares_table(d: dict) -> str:
    """P(square face) per shape and condition, against the solid-angle share."""
    labels, rows = list(d["shares"]), []
    for i, r in enumerate(d["ratios"]):
        y, x = np.abs(np.asarray(square_cuboid(r).vertices[0])[[0, 2]]) * 2e3
        rows.append((f"{r:g}", f"{y:.2f} × {x:.2f}", f"{solid_angle_share(r):.3f}",
                     *(estimate(d["shares"][label][i][0], d["shares"][label][i][1:])
                       for label in labels)))
    shares = markdown_table("x/y | y × x (mm) | solid angle | " + " | ".join(labels), rows)
    undecided = ", ".join(f"{label} {k}" for label, k in d["undecided"].items())
    return f"""\
{shares}

Undecided throws (no face within 10 s, unstable or sunk; not counted), per condition over all
shapes: {undecided}."""


@generated("cuboids-intro-4", COMMAND, d=JSON)
def cube_text(d: dict) -> str:
    """Whether the cube's share holds 1/3 in each condition."""
    cube = d["ratios"].index(1.0)
    return "\n".join(
        f"- {label}: {estimate(p, ci)}: 1/3 is "
        f"{'inside' if ci[0] <= 1 / 3 <= ci[1] else 'OUTSIDE'} the interval."
        for label, shares in d["shares"].items() for p, *ci in [shares[cube]])

"""Square-cuboid dice, a prediction: the chance of landing on a square face against x/y.

``run(out, quick, throws)`` writes ``out/cuboids.md`` and ``out/figures/cuboids.png``;
:func:`read_page` reads the page's numbers back (the validation page quotes them). The square
faces of ``Die.cuboid((y, y, x))`` are 1 and 6; every cuboid keeps the default die's volume.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import NamedTuple

import matplotlib.pyplot as plt
import numpy as np

from dice_env.intervals import wilson
from dice_env.model.die import Die
from dice_env.model.scene import Ground, Scene
from dice_env.model.table import DIE_EDGE, DIE_MASS, RESTITUTION, damping_for_restitution
from dice_env.studies.common import DOCS, SEED, checked_throws, progress, save_figure
from dice_env.studies.fairness import VIGOROUS, Vigour
from dice_env.studies.markdown import estimate, markdown_table
from dice_env.studies.numbers import study_page
from dice_env.studies.shapes import Faces, hand_throws, throw_faces

# x/y of the shapes thrown (1 is the cube).
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
    """Share of the full solid angle that the two square faces subtend from the centre.

    A naive reference: each face as likely as the directions it covers.
    """
    a, d = 0.5, 0.5 * ratio
    omega = 4.0 * math.atan(a * a / (d * math.sqrt(2 * a * a + d * d)))
    return 2.0 * omega / (4.0 * math.pi)


def square_share(faces: Faces) -> tuple[float, np.ndarray]:
    """Share of the counted throws that land on a square face, and its 95% Wilson interval."""
    hits = int(sum(faces.counts[f - 1] for f in SQUARE_FACES))
    return hits / faces.ended, wilson(hits, faces.ended)


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
            table[label, ratio] = (faces, *square_share(faces))
    bar.close()
    _plot(table, ratios, n, out / "figures" / "cuboids.png")
    first = CONDITIONS[0][0]
    numbers = {f"p_{r:g}": table[first, r][1] for r in ratios}
    numbers["cube_p"] = table[first, 1.0][1]
    numbers["cube_lo"], numbers["cube_hi"] = (float(v) for v in table[first, 1.0][2])
    numbers["undecided"] = max(f.undecided for f, _, _ in table.values()) / n
    (out / "cuboids.md").write_text(_markdown(table, ratios, n, seed, quick, throws))
    return numbers


class Page(NamedTuple):
    """The numbers of a ``cuboids.md``: its command, seed, throws per point and its table.

    ``table[label][ratio]`` is ``(p, lo, hi)``: P(square face) and its 95% interval.
    """

    command: str
    seed: int
    throws: int
    table: dict[str, dict[float, tuple[float, float, float]]]


def read_page(path: Path) -> Page:
    """The numbers of the page ``path`` written by :func:`run`.

    Raises ValueError when the page does not have the form :func:`run` writes.
    """
    text = Path(path).read_text()
    head = re.search(r"Generated by `([^`]+)` \(module `dice_env/studies/cuboids.py`, seed "
                     r"(\d+)\);\n(\d+) throws per shape and condition", text)
    lines = [line for line in text.splitlines() if line.startswith("| ")]
    if head is None or not lines or not lines[0].startswith("| x/y |"):
        raise ValueError(f"path must be a page written by dice_env.studies.cuboids, got {path}")
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


def _plot(table: dict, ratios: tuple[float, ...], n: int, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(8, 5), layout="constrained")
    fine = np.geomspace(ratios[0], ratios[-1], 200)
    ax.plot(fine, [solid_angle_share(r) for r in fine], color="0.5", ls="--", lw=1,
            label="solid-angle share (naive reference)")
    for k, (label, _, _) in enumerate(CONDITIONS):
        p = np.array([table[label, r][1] for r in ratios])
        ci = np.array([table[label, r][2] for r in ratios])
        ax.plot(ratios, p, "o-", color=f"C{k}", ms=4, label=label)
        ax.fill_between(ratios, ci[:, 0], ci[:, 1], color=f"C{k}", alpha=0.2, lw=0)
    ax.axhline(1 / 3, color="k", ls=":", lw=1)
    ax.axvline(1.0, color="k", ls=":", lw=1)
    ax.set_xscale("log")
    ax.set_xticks(ratios)
    ax.set_xticklabels([f"{r:g}" for r in ratios])
    ax.minorticks_off()
    ax.set(xlabel="x / y (height along the square faces' normal / side of the square)",
           ylabel="P(lands on a square face), 95% band", ylim=(0, 1),
           title=f"Square-cuboid dice, {n} throws per point (prediction, nothing fitted)")
    ax.legend(fontsize=8)
    save_figure(fig, path)


def _markdown(table: dict, ratios: tuple[float, ...], n: int, seed: int, quick: bool,
              throws: int | None) -> str:
    command = "python -m dice_env.studies cuboids" + (" --quick" if quick else "") + (
        f" --throws {throws}" if throws is not None else "")
    labels = [label for label, _, _ in CONDITIONS]
    rows = []
    for r in ratios:
        y, x = np.abs(np.asarray(square_cuboid(r).vertices[0])[[0, 2]]) * 2e3
        rows.append((f"{r:g}", f"{y:.2f} × {x:.2f}", f"{solid_angle_share(r):.3f}",
                     *(estimate(*table[label, r][1:3]) for label in labels)))
    undecided = {label: sum(table[label, r][0].undecided for r in ratios) for label in labels}
    cube_lines = "\n".join(
        f"- {label}: {estimate(p, ci)}: 1/3 is "
        f"{'inside' if ci[0] <= 1 / 3 <= ci[1] else 'OUTSIDE'} the interval."
        for label in labels for _, p, ci in [table[label, 1.0]])
    shares = markdown_table("x/y | y × x (mm) | solid angle | " + " | ".join(labels), rows)
    return study_page("cuboids", globals(), command=command, cube_lines=cube_lines, g=Ground(), n=n,
                      s=GENTLE, seed=seed, shares=shares, undecided=undecided, v=VIGOROUS)

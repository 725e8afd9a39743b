"""Every standard die: fairness, loaded variants (:func:`favoured_face`), and free flight.

``run(out, quick, throws)`` writes ``out/shapes.md`` and ``out/figures/shapes_faces.png``.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from dice_env.markdown import estimate, markdown_table
from dice_env.model.defaults import DIE_EDGE
from dice_env.model.die import STANDARD_SIZES, Die
from dice_env.model.scene import Scene
from dice_env.simulation.simulate import UP, State, simulate
from dice_env.throws import (
    VIGOROUS,
    Faces,
    hand_throws,
    random_directions,
    random_orientations,
    throw_faces,
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
from studies.templates import write_study

COMMAND = "python -m studies shapes"  # writes docs/generated/shapes-*.md
JSON = "docs/shapes.json"  # every number of the page, written by the full study
FILES = ("shapes-intro", "shapes-intro-2", "shapes-intro-3", "shapes-intro-4", "shapes-free-flight")
DICE = tuple(STANDARD_SIZES)
# Throws per die, fair and loaded, in the full and the quick run.
FULL = {"fair": 100_000, "loaded": 20_000}
QUICK = {"fair": 600, "loaded": 600}
LOAD = {"face": 1, "fraction": 0.1, "depth": 0.8}  # the loaded dice (Die.load's arguments)
FLIGHT_HEIGHT, FLIGHT_TIME = 1.0, 0.3  # free flight: released 1 m up, 0.3 s without contact
FLIGHT_COLUMNS = ("velocity", "momentum", "energy", "rotation", "height")


def favoured_face(die: Die, face: int) -> int:
    """The label read when face ``face`` lies flat on the table (its normal pointing down).

    Where a weight toward ``face`` should make the die show more often: the opposite face
    on a die read up, ``face`` itself on a die read down (the d4).
    """
    n = die.face_normals[face - 1]
    # a rotation taking n to -up: the half turn about the bisector of n and -up
    axis = n - UP
    if np.linalg.norm(axis) < 1e-9:  # n is up: half a turn about x
        return int(die.face_read(np.diag([1.0, -1.0, -1.0]), UP))
    axis /= np.linalg.norm(axis)
    return int(die.face_read(2.0 * np.outer(axis, axis) - np.eye(3), UP))


@dataclass
class Loaded:
    """A loaded die's throws: its faces and the favoured face's share against ``1/F``."""

    die: Die
    faces: Faces
    favoured: int

    @property
    def share(self) -> float:
        """Share of the favoured face."""
        return float(self.faces.shares[self.favoured - 1])

    @property
    def interval(self) -> np.ndarray:
        """95% Wilson interval of the favoured face's share."""
        return self.faces.intervals[self.favoured - 1]

    @property
    def most_frequent(self) -> int:
        """The label seen most often."""
        return int(np.argmax(self.faces.counts)) + 1


def free_flight(die: Die, n: int = 8, seed: int = 0, step_by_step: bool = False,
                t: float = FLIGHT_TIME, safety: float = 0.15) -> dict[str, float]:
    """Largest relative errors of ``n`` random throws of ``die`` flying ``t`` s with no contact.

    The errors (``velocity``, ``momentum``, ``energy``, ``rotation``, ``height``) are defined on
    docs/shapes.md; ``step_by_step`` turns the analytic contact-free jumps off.
    """
    scene = Scene(die=die, safety=safety)
    rng = np.random.default_rng(seed)
    position = np.tile([0.0, 0.0, FLIGHT_HEIGHT], (n, 1))
    velocity = random_directions(rng, n) * rng.uniform(0.2, 1.0, (n, 1))
    spin = random_directions(rng, n) * rng.uniform(20.0, 100.0, (n, 1))
    start = State.release(scene, position, velocity, spin, random_orientations(rng, n))
    every = max(1, scene.steps_for(t) // 200)
    res = simulate(scene, start, t_max=t, until="t_max", record_every=every,
                   record=("orientations",), free_flight=not step_by_step, num_threads=1)
    if res.max_penetration.max() > 0 or res.impacts.any():
        raise RuntimeError("the free-flight throws touched a plane")
    g = scene.gravity
    elapsed = scene.steps_for(t) * scene.step
    fall = np.array([0.0, 0.0, -g * elapsed])
    dv = np.linalg.norm(res.final.velocity - start.velocity - fall, axis=1)
    momentum = np.linalg.norm(res.final.angular_momentum - start.angular_momentum, axis=1)
    rotation0 = _rotational(die, start.angular_momentum, start.orientation)
    kinetic0 = 0.5 * die.mass * np.sum(start.velocity**2, axis=1) + rotation0
    energy0 = kinetic0 + die.mass * g * start.position[:, 2]
    times = res.t
    velocities = start.velocity[:, None, :] + np.multiply.outer(times, [0.0, 0.0, -g])
    rotations = _rotational(die, start.angular_momentum[:, None, :], res.orientations)
    # the step's exact defect in uniform gravity: E_k = E_0 - m g^2 dt t_k / 2
    energies = (0.5 * die.mass * np.sum(velocities**2, axis=-1) + rotations
                + die.mass * g * res.x_cm[..., 2] + 0.5 * die.mass * g * g * scene.step * times)
    parabola = (start.position[:, None, 2] + start.velocity[:, None, 2] * times
                - 0.5 * g * times**2)
    return {
        "velocity": float((dv / (np.linalg.norm(start.velocity, axis=1) + g * elapsed)).max()),
        "momentum": float((momentum / np.linalg.norm(start.angular_momentum, axis=1)).max()),
        "energy": float((np.abs(energies - energy0[:, None]) / kinetic0[:, None]).max()),
        "rotation": float((np.abs(rotations - rotation0[:, None]) / kinetic0[:, None]).max()),
        "height": float(np.abs(res.x_cm[:, :, 2] - parabola).max() / (0.5 * g * elapsed**2)),
    }


def _rotational(die: Die, ang: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Rotational energy ``L . I_world^-1 L / 2`` from angular momentum and orientation."""
    body_l = np.einsum("...ji,...j->...i", q, ang)
    return 0.5 * np.einsum("...i,ij,...j->...", body_l, np.linalg.inv(die.inertia_body), body_l)


def flight_dice() -> dict[str, Die]:
    """Every shape for the free-flight checks: the standard dice, loaded, and a cuboid."""
    dice = {name: Die.standard(name) for name in DICE}
    dice.update({f"{name} loaded": Die.standard(name).load(**LOAD) for name in DICE})
    dice["cuboid 8x16x24 mm"] = Die.cuboid((0.008, 0.016, 0.024))
    dice["cuboid loaded"] = dice["cuboid 8x16x24 mm"].load(2, 0.2, 0.8)
    return dice


def run(out: Path = DOCS, quick: bool = False, seed: int = SEED, throws: int | None = None,
        faces_of: Callable[[Scene, int, int], Faces] | None = None) -> dict[str, float]:
    """Regenerate ``shapes.md`` and its figure under ``out``; return the headline numbers.

    ``throws``: fair throws per die (default :data:`FULL`'s, or :data:`QUICK`'s with
    ``quick``); the loaded dice get half as many (at least the quick size).
    ``faces_of(scene, n, seed)``: the faces of ``n`` hand throws of ``scene`` (each die its own
    seed from ``SeedSequence(seed)``), e.g. :func:`studies.many_throws.hand_faces`;
    default: thrown here, every die's throws drawn in turn from one generator.
    """
    sizes = dict(QUICK if quick else FULL)
    if checked_throws(throws, 60) is not None:
        sizes = {"fair": int(throws), "loaded": max(QUICK["loaded"], int(throws) // 2)}
    rng = np.random.default_rng(seed)
    seeds = iter(np.random.SeedSequence(seed).generate_state(2 * len(DICE)))
    bar = progress(len(DICE) * (sizes["fair"] + sizes["loaded"]), "shapes throws", "throw")

    def thrown(scene: Scene, n: int) -> Faces:
        if faces_of is None:
            return throw_faces(scene, hand_throws(scene, n, rng), bar)
        faces = faces_of(scene, n, int(next(seeds)))
        bar.update(n)
        return faces

    fair, loaded = {}, {}
    for name in DICE:
        scene = Scene(die=Die.standard(name))
        fair[name] = thrown(scene, sizes["fair"])
        heavy = scene.die.load(**LOAD)
        loaded[name] = Loaded(heavy, thrown(scene.with_(die=heavy), sizes["loaded"]),
                              favoured_face(heavy, LOAD["face"]))
    bar.close()
    flight = {name: (free_flight(die), free_flight(die, step_by_step=True))
              for name, die in flight_dice().items()}
    numbers = {}
    for name in DICE:
        numbers[f"{name}_p"] = fair[name].p_value
        numbers[f"{name}_undecided"] = fair[name].undecided / sizes["fair"]
        numbers[f"{name}_loaded_excess"] = loaded[name].share - 1 / fair[name].counts.size
    for q in ("velocity", "momentum", "energy"):
        numbers[f"flight_{q}"] = max(f[k][q] for f in flight.values() for k in (0, 1))
    data = page_data(fair, loaded, flight, sizes, seed, quick, throws, faces_of is not None)
    draw_figures(FIGURES, data, out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "shapes.json", json.dumps(data, indent=1) + "\n")
    write_study(out, "shapes", list(FILES), {"d": json.loads(json.dumps(data))})
    return numbers


def figure(d: dict, path: Path) -> None:
    """Draw ``figures/shapes_faces.png`` from the page's numbers ``d`` (``shapes.json``)."""
    fig, axes = plt.subplots(2, 3, figsize=(13, 7), layout="constrained")
    for ax, name in zip(axes.ravel(), DICE, strict=True):
        fair, heavy = d["fair"][name], d["loaded"][name]
        f = Faces.of(np.array(fair["counts"]), fair["counted"] + fair["undecided"])
        loaded = Faces.of(np.array(heavy["counts"]), d["sizes"]["loaded"])
        n = f.counts.size
        labels = np.arange(1, n + 1)
        for faces, offset, color, label in ((f, -0.18, "C0", "fair"),
                                            (loaded, 0.18, "C1", "loaded toward 1")):
            ratio = faces.shares * n
            ax.errorbar(labels + offset, ratio, yerr=error_bars(ratio, faces.intervals * n),
                        fmt="o", ms=3, color=color, capsize=2, label=label)
        ax.axhline(1.0, color="k", ls=":", lw=1)
        ax.axvline(heavy["favoured"], color="C1", lw=6, alpha=0.15)
        ax.set(xticks=labels, xlabel="face read", ylabel="share × n (95% interval)")
        ax.set_title(f"{name}: fair p = {f.p_value:.2g} ({f.ended} throws)", fontsize=10)
    axes[0, 0].legend(fontsize=8)
    save_figure(fig, path)


FIGURES = {"shapes_faces": figure}  # the page's figure, drawn by run from its numbers


def page_data(fair: dict[str, Faces], loaded: dict[str, Loaded], flight: dict,
              sizes: dict, seed: int, quick: bool, throws: int | None, chunked: bool) -> dict:
    """Every number of the page (JSON-ready), kept as ``shapes.json``."""
    return {
        "command": "python -m studies shapes" + (" --quick" if quick else "") + (
            f" --throws {throws}" if throws is not None else "") + (
            " --chunks DIR" if chunked else ""),
        "seed": seed, "sizes": sizes, "chunked": chunked,
        "fair": {name: {"counts": [int(c) for c in f.counts],
                        "counted": int(f.ended), "undecided": int(f.undecided),
                        "chi2": float(f.chi2), "p": float(f.p_value),
                        "max_deviation": float(f.max_deviation)} for name, f in fair.items()},
        "loaded": {name: {"com_offset": float(np.linalg.norm(h.die.com) / h.die.size),
                          "counts": [int(c) for c in h.faces.counts],
                          "favoured": int(h.favoured), "counted": int(h.faces.ended),
                          "share": h.share, "interval": [float(x) for x in h.interval],
                          "most_frequent": int(h.most_frequent), "p": float(h.faces.p_value)}
                   for name, h in loaded.items()},
        "flight": {name: [{q: float(flight[name][k][q]) for q in FLIGHT_COLUMNS} for k in (0, 1)]
                   for name in flight}}


@generated("shapes-intro", COMMAND, d=JSON)
def intro_text(d: dict) -> str:
    """The run, the dice, the table and the throws."""
    command, seed, sizes, v, g = d["command"], d["seed"], d["sizes"], VIGOROUS, Scene().ground
    full = FULL["fair"]
    note = ("" if sizes["fair"] >= full else
            f"\nThis page was made with {sizes['fair']} fair throws per die (the command's "
            f"default is {full}).\n") + (
        "\nEach die's throws ran in seeded chunks (`dice_env.simulation.runner`, one seed per "
        "die from the study's seed; `--chunks DIR` keeps them, `--ray ADDRESS` runs them on Ray): "
        "the same numbers here or on any Ray cluster, not those of a run without chunks.\n"
        if d["chunked"] else "")
    return f"""\
Generated by `{command}` (module `studies/shapes.py`, seed {seed}).
{note}
Dice: `Die.standard(name)` at their default sizes and the default density (uniform solids);
table: the default scene's (S = {g.stiffness:g} N/m, D = {g.damping:.4g} N s/m, mu =
{g.friction:g} per vertex, stick-slip friction, automatic step), no walls. Throws: the
vigorous hand throws of `fairness.md`, in the same physical units for every die: orientation
uniform over rotations, released {v.clearance[0] * DIE_EDGE * 100:g}–{v.clearance[1] * DIE_EDGE * 100:g} cm above touching, {v.speed[0] * DIE_EDGE:g}–{v.speed[1] * DIE_EDGE:g} m/s
in a uniform direction toward the table, spin {v.spin[0]:g}–{v.spin[1]:g} rad/s about a
uniform axis. Each throw runs until its face is decided (`simulate(...,
until="decided")`: its energy can no longer tip it, so this is the face it rests on)
or {Scene().t_max:g} s; faces are read against gravity, the d4 by the face down.
"Undecided": throws with no face by then, or flagged unstable or sunk; not counted.

## Fairness: {sizes['fair']} throws per die"""  # noqa: E501


@generated("shapes-intro-2", COMMAND, d=JSON)
def fairness_table(d: dict) -> str:
    """Each standard die's faces against uniform."""
    return markdown_table(
        "die | faces | vertices | size (mm) | mass (g) | counted | undecided | chi2 | p | "
        "largest deviation of share × n from 1",
        ((name, die.n_faces, len(die.vertices), f"{die.size * 1e3:g}", f"{die.mass * 1e3:.3g}",
          f["counted"], f["undecided"], f"{f['chi2']:.1f}", f"**{f['p']:.3g}**",
          f"{f['max_deviation'] * die.n_faces:.3f}")
         for name in DICE for die, f in [(Die.standard(name), d["fair"][name])]))


@generated("shapes-intro-3", COMMAND, d=JSON)
def loaded_heading(d: dict) -> str:
    """The loaded dice's heading, with their throws."""
    return f"## Loaded dice: {d['sizes']['loaded']} throws each"


@generated("shapes-intro-4", COMMAND, d=JSON)
def loaded_table(d: dict) -> str:
    """Each loaded die's predicted face against 1/n, and which show it."""
    n = {name: Die.standard(name).n_faces for name in d["loaded"]}
    loads = markdown_table(
        "die | centre of mass offset (size) | predicted face | counted | its share [95%] | 1/n | "
        "share × n | most frequent | chi2 p",
        ((name, f"{h['com_offset']:.3f}", h["favoured"], h["counted"],
          estimate(h["share"], h["interval"], 4), f"{1 / n[name]:.4f}",
          f"{h['share'] * n[name]:.2f}", h["most_frequent"], f"{h['p']:.3g}")
         for name, h in d["loaded"].items()))
    shown = [name for name, h in d["loaded"].items() if h["interval"][0] > 1 / n[name]]
    hidden = [name for name in d["loaded"] if name not in shown]
    text = f"The predicted face shows more than 1/n beyond its 95% interval on: {', '.join(shown)}."
    if hidden:
        text += (f" Not detectable at this sample: {', '.join(hidden)} (the d4's offset is half"
                 " the others'; `tests/test_studies_shapes.py` loads it with 0.3 of the mass"
                 " at depth 0.9 and finds face 1 read most).")
    return f"{loads}\n\n{text}"


@generated("shapes-free-flight", COMMAND, d=JSON)
def flight_text(d: dict) -> str:
    """Free flight: each shape's largest errors, jumped and stepped."""
    flights = markdown_table(
        "die | isotropic | " + " | ".join(f"{mode}: {q}" for mode in ("jump", "stepped")
                                          for q in FLIGHT_COLUMNS),
        ((name, "yes" if die.is_isotropic else "no",
          *(f"{d['flight'][name][k][q]:.1e}" for k in (0, 1) for q in FLIGHT_COLUMNS))
         for name, die in flight_dice().items()))
    return rf"""Eight throws of each die released {FLIGHT_HEIGHT:g} m up with 0.2–1 m/s and 20–100 rad/s,
flying {FLIGHT_TIME:g} s without touching anything (`free_flight` in the module). Largest
error over the throws (and, for the energy and height, over 200 recorded instants), each
relative to its scale: velocity \|u − u0 − g t\| / (\|u0\| + g t); angular momentum
\|L − L0\| / \|L0\|; energy (kinetic plus m g z from the recorded state, plus the
symplectic Euler step's exact defect in uniform gravity, m g² dt t / 2) \|E − E0\| / KE0,
and its rotational part alone; height of the centre against the exact parabola, over the
drop g t²/2. With the analytic contact-free jumps (the default) and stepped one by one
(`free_flight=False`).

{flights}"""  # noqa: E501

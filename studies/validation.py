"""The validation page: the simulator against experiments on real dice, one section each.

``run(out, quick)`` writes ``out/validation.json`` (its own throws' numbers) and the page's files,
rendered from it and the weldon and cuboids studies' JSONs under ``out`` (``weldon.json``,
``cuboids.json``; each study run first if absent).
"""

from __future__ import annotations

import json
import math
from operator import itemgetter
from pathlib import Path
from typing import Any

import numpy as np

from dice_env.intervals import wilson
from dice_env.markdown import estimate, markdown_table
from dice_env.model import defaults
from dice_env.model.rotations import up_rotation
from dice_env.model.scene import Scene
from dice_env.simulation.calibration import measured_restitution
from dice_env.simulation.simulate import UP, State, simulate
from dice_env.throws import energy_throws
from studies import cuboids, weldon
from studies.common import DOCS, SEED, write_text
from studies.docs_numbers import generated
from studies.fairness import face_down, throw_energy
from studies.templates import write_study

COMMAND = "python -m studies validation"
JSON = "docs/validation.json"  # the page's own numbers, written by the full study
FILES = ("validation-intro", "validation-intro-2", "validation-weldon-s-dice",
         "validation-weldon-s-dice-2", "validation-weldon-s-dice-3", "validation-weldon-s-dice-4")
MEMORY_THROWS = {False: 4000, True: 300}  # throws of the initially-down face, by ``quick``
ENERGY_RANGE = (0.01, 100.0)  # throw energy above a gentle release (m g a), log-uniform
Z_ONE_SIDED = 1.644854  # 5% one-sided
# The default table's sources (dice_env/model/defaults.py, docs/error-vs-runtime.md).
RESTITUTION_RANGE = (0.4, 0.5)
RESTITUTION_SOURCE = ("dice on wooden tables, 0.4–0.5: Kapitaniak, Strzalko, Grabski & "
                      "Kapitaniak, Chaos 22, 047504 (2012); Strzalko et al., Physics Reports "
                      "469, 59 (2008)")
FRICTION_RANGE = (0.3, 0.5)
FRICTION_SOURCE = ("plastics on dry wood, 0.3–0.5: Murase, J. Fac. Agr. Kyushu Univ. 28, 147 "
                   "(1984); Blau, Tribology International 34, 585 (2001)")
SPEEDS = (0.5, 1.0, 2.0)  # m/s: landing speeds of the restitution check
SLIDE_SPEED = 0.5  # m/s: the sliding die's start


def within(value: float, low: float, high: float) -> str:
    """"agrees" when ``low <= value <= high``, else "differs"."""
    return "agrees" if low <= value <= high else "differs"


def sliding_friction(scene: Scene, speed: float = SLIDE_SPEED) -> float:
    """Friction coefficient the simulator produces: a die sliding flat, deceleration / g.

    It starts at ``speed`` (m/s) along x; the fit takes its speeds between 20% and 80% of that.
    """
    die = scene.die
    face = int(np.argmin(die.resting_heights))
    state = State.release(scene, [0.0, 0.0, float(die.resting_heights[face])],
                          [speed, 0.0, 0.0], orientation=up_rotation(die.reading[face]))
    every = 10
    result = simulate(scene, state, t_max=1.0, record_every=every, record=())
    x = result.x_cm[0, :, 0]
    t = np.arange(1, x.size + 1) * every * scene.step
    v = np.gradient(x, t)
    sliding = (v > 0.2 * speed) & (v < 0.8 * speed)
    if sliding.sum() < 3:
        raise ValueError(f"the die did not slide from {speed} m/s to 20% of it within 1 s")
    return -np.polyfit(t[sliding], v[sliding], 1)[0] / scene.gravity


def initial_face_memory(n: int, rng: np.random.Generator, scene: Scene) -> dict:
    """P(rests on the face down at release) in energy terciles: the fairness study's throws.

    ``n`` throws of :func:`dice_env.throws.energy_throws` over :data:`ENERGY_RANGE`
    on ``scene`` (a d6); per tercile its energy range, throws, and hits on either face.
    """
    excess = 10 ** rng.uniform(*np.log10(ENERGY_RANGE), n)
    state = energy_throws(scene, excess, rng)
    result = simulate(scene, state, until="decided")
    ok = (result.decided | result.settled) & ~result.unstable & ~result.sunk
    down0 = face_down(scene.die, state.orientation, UP)
    final_down = 7 - result.face  # the d6's opposite face: the face it rests on
    energy = throw_energy(scene, state)
    edges = np.quantile(energy[ok], [0, 1 / 3, 2 / 3, 1])
    which = np.clip(np.searchsorted(edges, energy, side="right") - 1, 0, 2)
    bins = []
    for b in range(3):
        sel = ok & (which == b)
        bins.append({"low": float(edges[b]), "high": float(edges[b + 1]), "n": int(sel.sum()),
                     "down": int(np.sum(final_down[sel] == down0[sel])),
                     "up": int(np.sum(final_down[sel] == 7 - down0[sel]))})
    return {"thrown": n, "counted": int(ok.sum()), "bins": bins}


def memory_verdict(low: dict, high: dict) -> str:
    """Kapitaniak's direction: the release-down face favoured at low energy, less at high.

    "agrees": the low tercile's 95% interval of P(release-down) above 1/6 and it significantly
    above the high's (one-sided, 5%); "differs": below 1/6 or significantly below; else
    "not resolvable at this sample".
    """
    p_low, p_high = low["down"] / low["n"], high["down"] / high["n"]
    pooled = (low["down"] + high["down"]) / (low["n"] + high["n"])
    se = math.sqrt(max(pooled * (1 - pooled), 1e-300) * (1 / low["n"] + 1 / high["n"]))
    z = (p_low - p_high) / se
    lo, hi = wilson(low["down"], low["n"])
    if lo > 1 / 6 and z > Z_ONE_SIDED:
        return "agrees"
    if hi < 1 / 6 or z < -Z_ONE_SIDED:
        return "differs"
    return "not resolvable at this sample"


def run(out: Path = DOCS, quick: bool = False, seed: int = SEED) -> dict[str, float]:
    """Write ``validation.md`` under ``out``; return the headline numbers."""
    out.mkdir(parents=True, exist_ok=True)
    if not (out / "weldon.json").exists():
        weldon.run(out, quick)
    if not (out / "cuboids.json").exists():
        cuboids.run(out, quick)
    w, page = json.loads((out / "weldon.json").read_text()), cuboids.read_page(out / "cuboids.md")
    scene = Scene()
    memory = initial_face_memory(MEMORY_THROWS[quick], np.random.default_rng(seed), scene)
    restitution = {v: measured_restitution(scene, v) for v in SPEEDS}
    friction = sliding_friction(scene)
    data = page_data(COMMAND + (" --quick" if quick else ""), seed, memory, restitution,
                     friction)
    write_text(out / "validation.json", json.dumps(data, indent=1) + "\n")
    c = json.loads((out / "cuboids.json").read_text())
    write_study(out, "validation", list(FILES), {"d": data, "w": w, "c": c})
    low, high = memory["bins"][0], memory["bins"][-1]
    return {"weldon_p": w["alone"]["drilled16"]["p"], "memory_low": low["down"] / low["n"],
            "memory_high": high["down"] / high["n"], "restitution": restitution[1.0],
            "friction": friction, "cube_p": page.table[cuboids.CONDITIONS[0][0]][1.0][0]}


# ---- the page: the names its template reads ----------------------------------------------

def _bold(verdict: str) -> str:
    return f"**{verdict}**"


def _weldon_names(w: dict) -> dict[str, object]:
    t, a = w["together"], w["alone"]
    sens = markdown_table(
        "die | com x, y, z (µm) | die-throws | p(5 or 6) [95%] | − 1/3 | vs 1/3 | vs Weldon",
        ((v["label"], ", ".join(f"{c:.1f}" for c in v["com_um"]), f"{v['n']:,}",
          weldon.p_text(v), f"{v['p'] - 1 / 3:+.4f}",
          _bold(v["vs_fair_p"]["verdict"]), _bold(v["vs_weldon_p"]["verdict"]))
         for v in a.values()))
    dist_line = (f"chi-square against Weldon's (tails pooled, cells "
                 f"{weldon.cells_text(t['vs_weldon'])}): chi2 = {t['vs_weldon']['statistic']:.2f}, "
                 f"{t['vs_weldon']['dof']} d.f., p = {t['vs_weldon']['p_value']:.3g}; this "
                 f"sample tells Weldon's distribution from a fair die's with probability "
                 f"{t['power_against_fair']:.2f}"
                 + (f" (0.8 needs about {t['throws_to_resolve']:,} throws)"
                    if t.get("throws_to_resolve") else "")
                 + f"; variance of successes per throw {t['dispersion']:.2f} × the "
                 f"binomial's (1 for independent dice)" if "p" in t else "too few throws")
    return {"meta": w["meta"], "wd": w["weldon"], "t": t, "ref": a["drilled16"], "sens": sens,
            "s": weldon.sensitivity(w), "dist_line": dist_line,
            "together": weldon.p_text(t) if "p" in t else "too few throws",
            "t_verdict": t["vs_weldon_p"]["verdict"] if "p" in t
            else "not resolvable at this sample",
            "dist": t.get("distribution_verdict", "not resolvable at this sample")}


def _memory_names(m: dict) -> dict[str, object]:
    rows = [(name, f"{b['low']:.3g}–{b['high']:.3g}", b["n"],
             *(estimate(b[face] / b["n"], wilson(b[face], b["n"])) for face in ("down", "up")))
            for name, b in zip(("low", "middle", "high"), m["bins"], strict=True)]
    low, high = m["bins"][0], m["bins"][-1]
    return {"low": low, "high": high, "m_verdict": memory_verdict(low, high),
            "memory_table": markdown_table("energy | m g a | throws | P(rests on release-down "
                                           "face) [95%] | P(release-up face) [95%]", rows)}


def _steepness(page: cuboids.Page) -> str:
    """Whether the prediction of record is steeper than the solid-angle share at both ends."""
    row = page.table[cuboids.CONDITIONS[0][0]]
    flat, tall = min(row), max(row)
    if row[flat][0] > cuboids.solid_angle_share(flat) and \
            row[tall][0] < cuboids.solid_angle_share(tall):
        return ("steeper at both ends: a die that bounces and rolls ends on its large, low "
                "faces more often than their solid angle says")
    return "not steeper than the solid-angle share at both ends"


def _cuboid_names(page: cuboids.Page) -> dict[str, object]:
    record = cuboids.CONDITIONS[0][0]
    labels = list(page.table)
    rows = markdown_table("x/y | " + " | ".join(labels), (
        (f"{r:g}", *(estimate(p, (lo, hi)) for p, lo, hi in
                     (page.table[label][r] for label in labels)))
        for r in page.table[record]))
    cube = {label: page.table[label][1.0] for label in labels if 1.0 in page.table[label]}
    return {"page": page, "record": record, "cuboid_rows": rows, "cube": cube,
            "check": "agrees" if all(lo <= 1 / 3 <= hi for _, lo, hi in cube.values())
            else "differs", "flat": min(page.table[record]), "tall": max(page.table[record])}


def page_data(command: str, seed: int, memory: dict, restitution: dict,
              friction: float) -> dict:
    """The page's own numbers (JSON-ready), kept as ``validation.json``.

    The weldon and cuboids sections read those studies' JSONs.
    """
    return {"command": command, "seed": seed, "memory": memory,
            "restitution": [[float(v), float(e)] for v, e in restitution.items()],
            "friction": float(friction)}


def cuboid_page(c: dict) -> cuboids.Page:
    """The cuboids study's numbers (its JSON, ``c``) as :class:`studies.cuboids.Page`."""
    return cuboids.Page(c["command"], c["seed"], c["throws"], {
        label: {float(r): tuple(v) for r, v in zip(c["ratios"], rows, strict=True)}
        for label, rows in c["shares"].items()})


def _page(d: dict, w: dict, c: dict) -> dict[str, str]:
    """The page's generated files (``docs/generated/validation-*.md``), by name.

    From its own numbers ``d``, the weldon study's ``w`` and the cuboids study's ``c``.
    """
    restitution = {v: e for v, e in d["restitution"]}
    friction, m = d["friction"], d["memory"]
    e_verdict = "agrees" if all(within(e, *RESTITUTION_RANGE) == "agrees"
                                for e in restitution.values()) else "differs"
    return _files(dict(command=d["command"], seed=d["seed"], e_verdict=e_verdict, friction=friction,
                  g=Scene().ground, m=m, restitution=restitution, defaults=defaults,
                  **_weldon_names(w), **_memory_names(m), **_cuboid_names(cuboid_page(c))))


def _files(names: dict[str, Any]) -> dict[str, str]:
    """The page's generated files (``docs/generated/validation-*.md``), by name."""
    (command, seed, e_verdict, friction, g, m, restitution, defaults, meta, wd, t, ref, sens, s,
        dist_line, together, t_verdict, dist, low, high, m_verdict, memory_table, page, record,
        cuboid_rows, cube, check, flat, tall) = itemgetter("command", "seed", "e_verdict",
        "friction", "g", "m", "restitution", "defaults", "meta", "wd", "t", "ref", "sens", "s",
        "dist_line", "together", "t_verdict", "dist", "low", "high", "m_verdict",
        "memory_table", "page", "record", "cuboid_rows", "cube", "check", "flat", "tall")(names)
    return {
        "validation-intro": f"""\
Generated by `{command}` (module `studies/validation.py`, seed {seed}). One section
per experiment: what was measured on real dice and where, what the simulator gives for the
same set-up and by which command, and a verdict computed by the script. Nothing is fitted to
the data it is compared with; where a parameter was set from the same source, the section
says so. Expensive studies are not rerun here: their sections quote the numbers their own
command wrote, with its size.""",
        "validation-intro-2": f"""\
| experiment | real dice | simulator | verdict |
|---|---|---|---|
| Weldon's dice: p(5 or 6), one die at a time | {weldon.p_text(wd)} (Weldon 1894) | `drilled16`: {weldon.p_text(ref)} | {_bold(ref['vs_weldon_p']['verdict'])} |
| Weldon's dice: twelve thrown together | {weldon.p_text(wd)}; its distribution of 0–12 | {t['counted']:,} throws: {together} | {_bold(t_verdict)} |
| Weldon's dice: distribution of successes per throw | 26,306 throws | {t['counted']:,} throws, chi-square vs Weldon's | {_bold(dist)} |
| Initially-down face against throw energy | favoured at low energy, fading with energy (Kapitaniak et al. 2012) | P(release-down) {low['down'] / low['n']:.3f} (low) → {high['down'] / high['n']:.3f} (high) | {_bold(m_verdict)} |
| Restitution of the default table | {RESTITUTION_RANGE[0]:g}–{RESTITUTION_RANGE[1]:g} | {restitution[1.0]:.3f} at 1 m/s (set from it) | {_bold(e_verdict)} |
| Sliding friction of the default table | {FRICTION_RANGE[0]:g}–{FRICTION_RANGE[1]:g} | {friction:.3f} (an input) | {_bold(within(friction, *FRICTION_RANGE))} |
| Square-cuboid dice: P(square face) against x/y | no measurement known to us | {page.table[record][flat][0]:.3f} at x/y = {flat:g}, {page.table[record][tall][0]:.3f} at {tall:g} | **prediction** |
| Square cuboid at x/y = 1 (the cube) against 1/3 | 1/3 by symmetry | {page.table[record][1.0][0]:.3f} | {_bold(check)} |""",  # noqa: E501
        "validation-weldon-s-dice": f"""\
**Real dice.** W. F. R. Weldon threw 12 dice 26,306 times and counted the dice showing a 5 or
a 6: {wd['n']:,} die-throws, p = {weldon.p_text(wd)} (standard error
{wd['se']:.4f}), {wd['effect']:+.4f} above 1/3; his 0–12 counts
{', '.join(map(str, wd['counts']))} (K. Pearson, Phil. Mag. 50, 157 (1900); A. W. Kemp &
C. D. Kemp, The American Statistician 45, 216 (1991)). Against the binomial at 1/3:
chi2 = {wd['vs_fair']['statistic']:.1f}, {wd['vs_fair']['dof']} d.f., p =
{wd['vs_fair']['p_value']:.2g}; against the binomial at his own p: p =
{wd['vs_own_p']['p_value']:.2f}. The usual explanation is the drilled pips.

**Simulator.** `{meta['command']}` ({meta['threads']} thread(s), seed
{meta['seed']}; details in [weldon.md](weldon.md)): pip-drilled 16 mm dice (`drilled16`:
3 mm pips, 1 mm deep, centre of mass {math.hypot(*ref['com_um']):.1f} µm toward the 1-2-3
corner) tipped twelve at a time from a cup onto the default wooden table.

- **Alone** (each die of the cups thrown by itself; the per-die probability only):
  {ref['n']:,} die-throws, p = {weldon.p_text(ref)}, {ref['p'] - 1 / 3:+.4f}
  above 1/3: against Weldon {_bold(ref['vs_weldon_p']['verdict'])} (difference
  {ref['vs_weldon_p']['difference']:+.4f} ± {ref['vs_weldon_p']['half_width']:.4f}); against
  1/3 {_bold(ref['vs_fair_p']['verdict'])}. Resolving Weldon's excess needs about
  {ref['trials_to_resolve'] or 0:,} die-throws.
- **Together** (`simulate_group`, the dice collide; {t['thrown']:,} throws, {t['counted']:,}
  counted, {t['leaning']} left out for a die leaning on another, {t['undecided']} not decided
  in time, {meta['seconds_together']:.0f} s): p = {together}, against Weldon
  {_bold(t_verdict)}; {dist_line}: {_bold(dist)}.

Sensitivity to the pips (single throws; centre of mass in µm along the axes of faces 2, 3, 1).
On this throw the excess over 1/3 grows by {1e3 * s['slope']:.3f} ± {1e3 * s['se']:.3f} × 10⁻³ per µm of the centre's offset (a line through the origin, `weldon.excess_per_offset`); Weldon's excess would need about {s['offset']:.0f} µm (95%: {s['low']:.0f} µm to {"no upper bound" if math.isinf(s['high']) else f"{s['high']:.0f} µm"}). A reading of the model, used in no verdict: the size and pips of Weldon's dice are not recorded.

{sens}""",  # noqa: E501
        "validation-weldon-s-dice-2": f"""\
**Simulator.** `{command}` ({m['thrown']} throws, {m['counted']} decided and counted): the
default die on the default table with the fairness study's energy throws
(`fairness.energy_throws`: energy {ENERGY_RANGE[0]:g}–{ENERGY_RANGE[1]:g} m g a above a
gentle release, log-uniform, split at random between drop, speed and spin; orientation
uniform), each until its face is decided; terciles of energy. The full study over 40,000
throws is [fairness.md](fairness.md).

{memory_table}

**Verdict: {m_verdict}** (the low tercile's interval above 1/6 and a one-sided test of low
above high at 5%).""",
        "validation-weldon-s-dice-3": f"""\
**Real dice.** Restitution of a die on a wooden table: {RESTITUTION_SOURCE}. Sliding
friction: {FRICTION_SOURCE}. (`dice_env/model/defaults.py`; `docs/error-vs-runtime.md`.)

**Simulator.** `{command}`: the default scene (16 mm, 4.5 g die; S = {g.stiffness:g} N/m,
D = {g.damping:.4g} N s/m, mu = {g.friction:g} per corner).

- Restitution (`calibration.measured_restitution`: dropped flat, no spin, rebound speed over
  impact speed): {', '.join(f'{e:.3f} at {v:g} m/s' for v, e in restitution.items())}. **Verdict: {e_verdict}** (inside {RESTITUTION_RANGE[0]:g}–
  {RESTITUTION_RANGE[1]:g} at every speed). Not an independent test: the damping D is
  computed from the target {defaults.RESTITUTION:g}, the middle of this range
  (`defaults.damping_for_restitution`); this checks that the contact model delivers it.
- Sliding friction (`validation.sliding_friction`: the die slides flat from
  {SLIDE_SPEED:g} m/s, deceleration over g): {friction:.3f}. **Verdict: {within(friction, *FRICTION_RANGE)}**
  (inside {FRICTION_RANGE[0]:g}–{FRICTION_RANGE[1]:g}). Not independent either: mu =
  {defaults.FRICTION:g} is the model's input; this checks that the regularised, stick-slip
  friction law delivers it.""",  # noqa: E501
        "validation-weldon-s-dice-4": f"""\
**Simulator.** `{page.command}` (seed {page.seed}, {page.throws} throws per shape and
condition; the conditions, the sizes and the figure are in [cuboids.md](cuboids.md)).
P(lands on a square face) [95%]; the prediction of record is "{record}":

{cuboid_rows}

Against the naive share of directions the two square faces cover from the centre
(`cuboids.solid_angle_share`, not a fit): {cuboids.solid_angle_share(flat):.3f} at x/y =
{flat:g} and {cuboids.solid_angle_share(tall):.3f} at {tall:g}, where the model predicts
{page.table[record][flat][0]:.3f} and {page.table[record][tall][0]:.3f}: {_steepness(page)}.

**Verdict: prediction.** The one check it carries: at x/y = 1 the cuboid is the cube, whose
square faces must come up 1/3 of the time by symmetry; 1/3 is inside the interval in
{sum(lo <= 1 / 3 <= hi for _, lo, hi in cube.values())} of {len(cube)} conditions:
**{check}**.""",
    }


def _renderer(name: str) -> None:
    generated(name, COMMAND, d=JSON, w=weldon.JSON, c=cuboids.JSON)(
        lambda d, w, c: _page(d, w, c)[name])


for _name in FILES:
    _renderer(_name)

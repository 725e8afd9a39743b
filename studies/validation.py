"""The validation page: the simulator against experiments on real dice, one section each.

``run(out, quick)`` writes ``out/validation.md`` from its own throws and the weldon and cuboids
studies' output under ``out`` (``weldon.json``, ``cuboids.md``; each study run first if absent).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

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
from studies.fairness import face_down, throw_energy
from studies.templates import study_page

COMMAND = "python -m studies validation"
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
    if not (out / "cuboids.md").exists():
        cuboids.run(out, quick)
    w, page = json.loads((out / "weldon.json").read_text()), cuboids.read_page(out / "cuboids.md")
    scene = Scene()
    memory = initial_face_memory(MEMORY_THROWS[quick], np.random.default_rng(seed), scene)
    restitution = {v: measured_restitution(scene, v) for v in SPEEDS}
    friction = sliding_friction(scene)
    command = COMMAND + (" --quick" if quick else "")
    e_verdict = "agrees" if all(within(e, *RESTITUTION_RANGE) == "agrees"
                                for e in restitution.values()) else "differs"
    write_text(out / "validation.md", study_page(
        "validation", globals(), command=command, e_verdict=e_verdict, friction=friction,
        g=scene.ground, m=memory, map=map, restitution=restitution, defaults=defaults,
        **_weldon_names(w),
        **_memory_names(memory), **_cuboid_names(page)))
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

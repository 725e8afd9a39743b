"""Stiff and extreme cases: a stability map over stiffness and step, and a table of extremes.

``run(out, quick)`` writes ``out/stability.md`` and ``out/figures/stability_*.png``; that page
defines a map cell's classes (:data:`STABLE`, :data:`DRIFTING`, :data:`BLOWUP`).
"""

from __future__ import annotations

import json
import time
import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap

from dice_env.markdown import markdown_table
from dice_env.model.die import Die
from dice_env.model.scene import MAX_STEPS, ContactLaw, Ground, Scene
from dice_env.simulation.paper import paper_scene
from dice_env.simulation.simulate import Result, State, simulate
from dice_env.throws import Vigour, vigorous_throws
from studies.common import DOCS, draw_figures, progress, save_figure, write_text
from studies.docs_numbers import generated
from studies.templates import write_study

STABLE, DRIFTING, BLOWUP = 0, 1, 2
COMMAND = "python -m studies stability"  # writes docs/generated/stability-*.md
JSON = "docs/stability.json"  # every number of the page, written by the full study
FILES = ("stability-stability-map", "stability-extreme-cases-default-scene")
LAWS = (ContactLaw.PAPER, ContactLaw.GATED)  # the map's contact laws
DRIFT_LIMIT = 10.0  # worst energy rise (fraction of KE0 + m g (h0 + edge)) still drifting
MAP_T_MAX = 5.0  # simulated time of each map cell (s): the paper throw lands at about 1.5 s


def classify(result: Result, energy_tol: float) -> int:
    """Worst class over a batch: STABLE, DRIFTING or BLOWUP (docs/stability.md)."""
    finite = all(np.isfinite(a).all() for a in (result.final.position, result.final.velocity,
                                                  result.final.angular_momentum))
    rise = float(result.energy_rise.max()) * energy_tol
    if not finite or rise > DRIFT_LIMIT:
        return BLOWUP
    return DRIFTING if result.unstable.any() else STABLE


def map_cell(stiffness: float, ratio: float, law: ContactLaw, spins: int = 3) -> int:
    """Class of the paper's real throw at ``dt = ratio * critical_dt`` (``spins`` seeded L0)."""
    listing = paper_scene(S=stiffness, dt=None)
    scene = listing.with_(dt=ratio * listing.critical_dt, allow_unstable=True, t_max=MAP_T_MAX,
                          ground=listing.ground.with_(contact_law=law))
    rng = np.random.default_rng(0)
    spin = (rng.random((spins, 3)) * 0.75 + 1e-6) / scene.die.inertia_body[0, 0]
    state = State.release(scene, [0.0, 0.0, 3.0], [5.0, 0.0, 5.0], spin)
    return classify(simulate(scene, state), scene.energy_tol)


def stability_map(stiffnesses: np.ndarray, ratios: np.ndarray, law: ContactLaw,
                  bar) -> np.ndarray:
    """Classes over (ratio, stiffness), shape (len(ratios), len(stiffnesses))."""
    out = np.empty((len(ratios), len(stiffnesses)), dtype=int)
    for j, s in enumerate(stiffnesses):
        for i, r in enumerate(ratios):
            out[i, j] = map_cell(s, r, law)
            bar.update()
    return out


# Throws of the extreme cases unless a case changes them.
MODERATE = Vigour(clearance=(3.0, 10.0), speed=(10.0, 30.0), spin=(10.0, 30.0))


@dataclass(frozen=True)
class Case:
    """One extreme case: a label, the scene, and the throws' ranges."""

    group: str
    label: str
    scene: Scene
    vigour: Vigour = MODERATE


def extreme_cases(quick: bool) -> list[Case]:
    """The table's cases, one parameter pushed at a time from the default scene."""
    base = Scene()
    g, die = base.ground, base.die
    d_crit = 2 * np.sqrt(g.stiffness * base.effective_mass)
    cases = [Case("baseline", "default scene", base)]
    for v in (10.0, 100.0):
        cases.append(Case("speed", f"{v:g} edges/s ({v * die.size:.2g} m/s)", base,
                          replace(MODERATE, speed=(v, v))))
    for w in (100.0, 1000.0):
        cases.append(Case("spin", f"{w:g} rad/s", base, replace(MODERATE, spin=(w, w))))
    for mu in (0.0, 1.0, 2.0):
        cases.append(Case("friction", f"mu = {mu:g}", base.with_(ground=g.with_(friction=mu))))
    for frac in (0.0, 0.5, 1.0):
        cases.append(Case("damping", f"D = {frac:g} x critical ({frac * d_crit:.3g})",
                          base.with_(ground=g.with_(damping=frac * d_crit))))
    for angle in (15.0, 30.0, 45.0):
        tilted = Ground.tilted(angle, stiffness=g.stiffness, damping=g.damping,
                               friction=g.friction)
        cases.append(Case("tilt", f"{angle:g} deg", base.with_(ground=tilted)))
    for mass in (1e-3, 1.0, 1e3):
        cases.append(Case("mass", f"{mass:g} kg", base.with_(die=Die(edge=die.size, mass=mass))))
    for s in (1e6, 1e7) if quick else (1e6, 1e7, 1e8, 1e9, 1e10):
        cases.append(Case("stiffness", f"S = {s:g}", base.with_(ground=g.with_(stiffness=s))))
    return cases


def run_case(case: Case, throws: int, rng: np.random.Generator) -> dict[str, float]:
    """Throw ``throws`` dice in ``case`` and summarise the outcome."""
    scene = case.scene
    state = vigorous_throws(scene, throws, rng, case.vigour)
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = simulate(scene, state)
    wall = time.perf_counter() - start
    arrays = (result.final.position, result.final.velocity, result.final.angular_momentum)
    settled = result.settled
    return {
        "settled": float(settled.mean()),
        "max_penetration": float(result.max_penetration.max() / scene.die.size),
        "energy_drift": float(result.energy_rise.max() * scene.energy_tol),
        "unstable": float(result.unstable.mean()),
        "sunk": float(result.sunk.mean()),
        "rest_time": float(np.median(result.rest_time[settled])) if settled.any() else np.nan,
        "nan": float(not all(np.isfinite(a).all() for a in arrays)),
        "dt": scene.step,
        "steps_per_s": 1.0 / scene.step,
        "die_steps": float(result.steps.sum()),
        "wall": wall,
        "warnings": "; ".join(sorted({str(w.message) for w in caught})),
    }


def safety_sweep(cases: list[Case], safeties: tuple[float, ...], throws: int,
                 seed: int) -> np.ndarray:
    """Largest energy drift and share flagged unstable, per case and safety factor.

    Returns shape (len(cases), len(safeties), 2); the same throws for every safety.
    """
    out = np.empty((len(cases), len(safeties), 2))
    for i, case in enumerate(cases):
        for j, safety in enumerate(safeties):
            step = case.scene.dt or safety * case.scene.critical_dt
            # the stiffest table at the smallest safety would need more than MAX_STEPS steps
            scene = case.scene.with_(safety=safety, t_max=min(case.scene.t_max,
                                                              0.999 * MAX_STEPS * step))
            state = vigorous_throws(scene, throws, np.random.default_rng(seed), case.vigour)
            result = simulate(scene, state)
            out[i, j] = result.energy_rise.max() * scene.energy_tol, result.unstable.mean()
    return out


SAFETIES = (0.15, 0.05, 0.015)  # the default first


def run(out: Path = DOCS, quick: bool = False, seed: int = 7) -> dict[str, float]:
    """Regenerate ``stability.md`` and its figures under ``out``; return the headline numbers."""
    stiffnesses = np.logspace(1, 8, 4 if quick else 15)
    ratios = np.logspace(np.log10(0.05), np.log10(5.0), 5 if quick else 21)
    cases = extreme_cases(quick)
    stiffest = [c for c in cases if c.group == "stiffness"][-1]
    sweep_cases = [c for c in cases if c.group == "baseline" or c.label == "mu = 2"
                   or c.label.startswith("D = 0 ")] + [stiffest]
    throws = 4 if quick else 32
    laws = LAWS
    bar = progress(len(laws) * len(stiffnesses) * len(ratios) + len(cases) + 1, "stability")
    maps = {law: stability_map(stiffnesses, ratios, law, bar) for law in laws}
    rng = np.random.default_rng(seed)
    rows = []
    for case in cases:
        rows.append((case, run_case(case, throws, rng)))
        bar.update()
    sweep = safety_sweep(sweep_cases, SAFETIES, throws, seed)
    bar.update()
    bar.close()
    numbers = {}
    for law in laws:
        name = law.name.lower()
        for c, cname in enumerate(("stable", "drifting", "blowing_up")):
            for side, rows_ in (("above", ratios > 1), ("below", ratios < 1)):
                numbers[f"{name}_{cname}_{side}_bound"] = float(np.mean(maps[law][rows_] == c))
        numbers[f"{name}_first_not_stable"] = _first_ratio(maps[law] != STABLE, ratios)
        numbers[f"{name}_first_blowup"] = _first_ratio(maps[law] == BLOWUP, ratios)
    numbers["extreme_any_nan"] = float(any(r["nan"] for _, r in rows))
    numbers["automatic_step_flagged_cases"] = float(sum(r["unstable"] > 0 for _, r in rows))
    data = page_data(stiffnesses, ratios, maps, rows, throws, numbers, sweep_cases, sweep, seed)
    draw_figures(FIGURES, data, out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "stability.json", json.dumps(data, indent=1) + "\n")
    write_study(out, "stability", list(FILES), {"d": json.loads(json.dumps(data))})
    return numbers


def _first_ratio(mask: np.ndarray, ratios: np.ndarray) -> float:
    """Smallest dt/bound at which any stiffness shows ``mask`` (inf if none)."""
    rows = np.flatnonzero(mask.any(axis=1))
    return float(ratios[rows[0]]) if len(rows) else float("inf")


def figure(data: dict, path: Path) -> None:
    """Draw ``figures/stability_map.png`` from the page's numbers ``data`` (``stability.json``).

    ``data["maps"][law]``: a string per ratio, a digit per stiffness, the class of
    :func:`stability_map` (0 stable, 1 drifting, 2 blowing up).
    """
    stiffnesses, ratios = np.array(data["stiffnesses"]), np.array(data["ratios"])
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), sharey=True, layout="constrained")
    cmap = ListedColormap(["#4caf50", "#ffc107", "#e53935"])
    scenes = [paper_scene(S=s, dt=None) for s in stiffnesses]
    bounds = np.array([scene.critical_dt for scene in scenes])
    d = np.array([scene.ground.damping for scene in scenes])
    m = np.array([scene.die.mass / 8 for scene in scenes])  # one node's mass
    node = (np.sqrt(d * d + 4 * stiffnesses * m) - d) / stiffnesses
    for ax, (law, rows) in zip(axes, data["maps"].items(), strict=True):
        classes = np.array([[int(c) for c in row] for row in rows])
        dts = ratios[:, None] * bounds[None, :]
        ax.scatter(np.broadcast_to(stiffnesses, dts.shape), dts, c=classes, cmap=cmap, vmin=0,
                   vmax=2, marker="s", s=18)
        ax.loglog(stiffnesses, bounds, "k-", label="Scene.critical_dt (effective mass m/6)")
        ax.loglog(stiffnesses, node, "k--", label="node mass m/8")
        ax.set_xlabel("stiffness S")
        ax.set_title(f"{law} law: green stable, amber drifting, red blowing up",
                     fontsize=10)
        ax.legend(loc="lower left", fontsize=8)
    axes[0].set_ylabel("step dt")
    save_figure(fig, path)


FIGURES = {"stability_map": figure}  # the page's figure, drawn by run from its numbers


def page_data(stiffnesses: np.ndarray, ratios: np.ndarray, maps: dict, rows: list,
              throws: int, n: dict[str, float], sweep_cases: list[Case], sweep: np.ndarray,
              seed: int) -> dict:
    """Every number of the page (JSON-ready), kept as ``stability.json``.

    A case's rest time is null where no throw settled (NaN).
    """
    def row(c: Case, r: dict) -> dict:
        rest = None if np.isnan(r["rest_time"]) else r["rest_time"]
        return {"group": c.group, "label": c.label, **r, "rest_time": rest,
                "stiffness": c.scene.ground.stiffness, "static_sink": _static_sink(c.scene)}

    return {"seed": seed, "stiffnesses": [float(x) for x in stiffnesses],
            "ratios": [float(x) for x in ratios], "numbers": n, "throws": throws,
            "maps": {law.name.lower(): ["".join(map(str, row)) for row in classes]
                     for law, classes in maps.items()},
            "cases": [row(c, r) for c, r in rows], "safeties": list(SAFETIES),
            "sweep": [{"group": c.group, "label": c.label,
                       "drift": [float(x) for x in sweep[i, :, 0]],
                       "flagged": [float(x) for x in sweep[i, :, 1]]}
                      for i, c in enumerate(sweep_cases)]}


def _rest(r: dict) -> float:
    """A case's median rest time (NaN where none settled: null in the JSON)."""
    return float("nan") if r["rest_time"] is None else r["rest_time"]


@generated("stability-stability-map", COMMAND, d=JSON)
def map_text(d: dict) -> str:
    """The stability map: the share of each class on either side of the bound, and where."""
    n, stiffnesses, ratios = d["numbers"], d["stiffnesses"], d["ratios"]
    law_lines = markdown_table(
        "law | below: stable | drift | blow-up | above: stable | drift | blow-up | 1st drift | "
        "1st blowup",
        ((name, *(f"{100 * n[f'{name}_{c}_{side}_bound']:.0f}%" for side in ("below", "above")
                  for c in ("stable", "drifting", "blowing_up")),
          f"{n[f'{name}_first_not_stable']:.3g}", f"{n[f'{name}_first_blowup']:.3g}")
         for name in (law.name.lower() for law in LAWS)))
    return f"""\
The paper's real throw (its die, x0 = (0, 0, 3), u0 = (5, 0, 5), D = 0.1, mu = 0.1,
{MAP_T_MAX:g} s simulated, 3 seeded spins L0 = rand·0.75 + 1e-6 per cell) for S =
{stiffnesses[0]:g}–{stiffnesses[-1]:g} ({len(stiffnesses)} values) and dt from
{ratios[0]:g} to {ratios[-1]:g} times the predicted bound `Scene.critical_dt` =
(sqrt(D^2 + 4 S m_eff) - D) / S with m_eff = m/6 (the fastest contact mode of a face on the
table: rocking about an edge), {len(ratios)} values. Classes, from the worst of the spins:
*stable* = the total energy (kinetic + potential + ground springs) never rose above its start
by more than 10% of KE0 + m g (h0 + edge) (`Result.unstable` False); *drifting* = rose more
than that but less than {DRIFT_LIMIT:g} times that scale and stayed finite; *blowing up* =
beyond, or non-finite.

{law_lines}

Blow-up starts at {n['paper_first_blowup']:.3g} (paper law) and
{n['gated_first_blowup']:.3g} (gated law) times the bound (grid spacing
{100 * (ratios[1] / ratios[0] - 1):.0f}%), and no cell above the bound stays stable
{_above_stable_phrase(n)}: the predicted bound is the
stability limit of the scheme. *Drifting* (energy up by more than 10% but bounded) starts
below it: at {n['paper_first_not_stable']:.2g} of the bound for the paper law and
{n['gated_first_not_stable']:.2g} for the gated law. The 10% tolerance is an accuracy test: a
coarse step gives each impact an energy error, and in this scene almost nothing removes it
under the gated law (the ground's damping ratio is about 0.1%), while the paper law's air drag
(8·D·v on a falling die) takes energy out on every flight and hides it. The node-mass bound
(m/8, dashed) lies slightly below the effective-mass bound: a conservative estimate, not the
limit."""


@generated("stability-extreme-cases-default-scene", COMMAND, d=JSON)
def cases_text(d: dict) -> str:
    """The extreme cases at the automatic step, the safety sweep, and what they show."""
    rows, throws, sweep = d["cases"], d["throws"], d["sweep"]
    base = Scene()
    g = base.ground
    table = markdown_table(
        "group | case | settled | max pen. | drift | unstable | sunk | rest (s) | NaN | dt (s) | "
        "wall (s) | warn",
        ((r["group"], r["label"], f"{100 * r['settled']:.0f}%",
          f"{100 * r['max_penetration']:.2f}%", f"{100 * r['energy_drift']:+.2f}%",
          f"{100 * r['unstable']:.0f}%", f"{100 * r['sunk']:.0f}%", f"{_rest(r):.2f}",
          "NaN!" if r["nan"] else "none", f"{r['dt']:.2g}", f"{r['wall']:.2f}",
          r["warnings"] or "-") for r in rows))
    sweep_rows = markdown_table(
        "case | " + " | ".join(f"safety {s:g}" for s in d["safeties"]),
        ((f"{c['group']}: {c['label']}", *(f"{100 * x:+.1f}% / {100 * f:.0f}%"
                                           for x, f in zip(c["drift"], c["flagged"],
                                                           strict=True)))
         for c in sweep))
    flagged = [f"{r['group']} {r['label']} ({100 * r['unstable']:.0f}%)" for r in rows
               if r["unstable"] > 0]
    sunk = [f"{r['group']} {r['label']} ({100 * r['sunk']:.0f}%)" for r in rows if r["sunk"] > 0]
    nan_cases = [f"{r['group']} {r['label']}" for r in rows if r["nan"]]
    tilt_rows = ", ".join(f"{r['label']} {100 * r['settled']:.0f}%" for r in rows
                          if r["group"] == "tilt")
    sink = [f"{r['label']}: {100 * r['static_sink']:.2g}% static, "
            f"{100 * r['max_penetration']:.3g}% in the throws" for r in rows
            if r["group"] == "mass"]
    by_label = {r["label"]: r for r in rows}
    d_rows = [(r["label"], r) for r in rows if r["group"] == "damping"]
    stiff = [r for r in rows if r["group"] == "stiffness"]
    slip = float(np.degrees(np.arctan(base.ground.friction)))
    return f"""\
Default scene: die {base.die.size * 1e3:g} mm, {base.die.mass * 1e3:g} g; table
S = {g.stiffness:g} N/m, D = {g.damping:.4g} N s/m, mu = {g.friction:g},
{g.contact_law.name.lower()} law; automatic step = {base.safety:g} x critical =
{base.step:.3g} s; up to {base.t_max:g} s per throw. Each row: {throws} random throws
(uniform orientation, centre 3–10 edges above touching, 10–30 edges/s toward the table, 10–30
rad/s) with one thing changed. Max pen. = deepest corner in % of the edge; drift = largest rise
of total energy above its start as a fraction of KE0 + m g (h0 + edge); unstable = share of
throws flagged; sunk = share whose deepest corner passed `Scene.sink_limit`
({base.sink_limit:g} of the die's size: `Result.sunk`, voided by the env); rest = median rest
time of the settled throws; wall = seconds for the batch on this machine (2 cores, shared);
warn = warnings raised. The last two columns of the map table are the smallest dt/bound where
any stiffness is not stable / blows up.

{table}

- NaN or infinite values: {', '.join(nan_cases) if nan_cases else 'none in any case'}.
- Flagged unstable at the automatic step: {', '.join(flagged) if flagged else 'none'}.
- Flagged sunk (deepest corner beyond {base.sink_limit:g} of the die's size, `Result.sunk`):
  {', '.join(sunk) if sunk else 'none'}.
  The drift shrinks fast with the step (same throws, drift / share flagged):

{_indent(sweep_rows)}

  At the automatic safety factor {base.safety:g}, {_sweep_sentence(sweep, d['safeties'])}
  The tolerance's scale KE0 + m g (h0 + edge) includes the drop height h0 of the centre above
  the table, so a drop is judged against the energy it brings to its first impact.
- Very stiff ground at the automatic step costs time, not accuracy: the step shrinks like
  1/sqrt(S) (S = {stiff[-1]['stiffness']:g}: dt = {stiff[-1]['dt']:.2g} s,
  {stiff[-1]['steps_per_s']:.3g} steps per simulated second). The simulator neither warns
  nor refuses (warn column); it just takes longer: {stiff[-1]['wall']:.1f} s wall for
  the {throws} throws at S = {stiff[-1]['stiffness']:g}
  ({stiff[-1]['die_steps'] / throws:.3g} steps per throw, counting the flight steps taken
  in analytic jumps). A user-given step above the bound raises `ValueError` unless
  `allow_unstable=True`.
- Tilted table (settled within {base.t_max:g} s: {tilt_rows}): a die can only stay where
  tan(angle) < mu, i.e. below {slip:.1f}°. Steeper tables let it slide and tumble down the
  infinite plane until the time limit, so "not settled" there is physics, not a failure; it
  gathers speed and hits hard (the penetration column).
- Damping (critical = 2 sqrt(S m_eff), m_eff = m/{base.die.mass / base.effective_mass:.0f}): settled
  {', '.join(f"{lab.split(' (')[0]}: {100 * r['settled']:.0f}%" for lab, r in d_rows)};
  median rest {', '.join(f"{_rest(r):.2f} s" for _, r in d_rows)} (baseline
  {_rest(by_label['default scene']):.2f} s). Without damping only sliding friction dissipates
  (a sticking corner's tangential spring is undamped too);
  near-critical damping settles fastest and needs a smaller automatic step (the bound's D term).
- Mass, same die size and table (sink m g / (4 S) of a flat die vs deepest corner seen):
  {'; '.join(sink)}. At 1000 kg the penalty ground is far outside its valid range (the die
  sinks through it), though the automatic step grows with the mass and nothing becomes
  non-finite. The same D is a smaller damping ratio for a heavier die (D / (2 sqrt(S m_eff))),
  so heavy dice bounce longer and drift like the undamped case."""


def _above_stable_phrase(n: dict[str, float]) -> str:
    bad = [law for law in ("paper", "gated") if n[f"{law}_stable_above_bound"] > 0]
    return f"(except some cells of the {' and '.join(bad)} law)" if bad else "(either law)"


def _sweep_sentence(sweep: list[dict], safeties: list[float]) -> str:
    """Which swept cases miss the 10% tolerance at the first safety, and what fixes them."""
    bad = [c for c in sweep if c["flagged"][0] > 0]
    if not bad:
        return "every swept case stays within the 10% energy tolerance."
    names = ", ".join(f"{c['group']} {c['label']}" for c in bad)
    fixed = [s for j, s in enumerate(safeties) if all(c["flagged"][j] == 0 for c in bad)]
    fix = f"a safety of {fixed[0]:g} brings them within it" if fixed else "no swept safety does"
    return f"{names} miss the 10% energy tolerance; {fix}."


def _static_sink(scene: Scene) -> float:
    """Sink of a die resting flat, ``m g / (4 S)``, in edges."""
    return scene.die.mass * scene.gravity / (4 * scene.ground.stiffness) / scene.die.size


def _indent(text: str) -> str:
    return "\n".join("  " + line for line in text.splitlines())

"""The paper's Figures 4–13 from its own scenes and contact law, with its claims checked.

``run(out, quick)`` writes ``out/paper.md`` and ``out/figures/paper_*.png``. Every claim is
also a function returning the number it rests on, so the tests assert the same numbers.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from dice_env.markdown import markdown_table
from dice_env.model.scene import ContactLaw
from dice_env.simulation.paper import PaperRun, ground_cube, paper_scene, real_throw_cube
from studies.common import DOCS, progress, save_figure, write_text
from studies.docs_numbers import generated
from studies.templates import write_study

COMMAND = "python -m studies paper"  # writes docs/generated/paper-*.md, included by paper.md
JSON = "docs/paper.json"  # every number of the page, written by the full study
FILES = ("paper-the-paper-reproduced", "paper-claims", "paper-figures-4-and-5",
         "paper-figure-13-steps-needed")
THROW_SEED = 0  # seed of the real throw's initial angular momentum (the listing's rand(3,1))
# Ground-cube variants of Figures 6–12: (figure label, keyword overrides of ground_cube).
VARIANTS = {
    "fig6_mu0": ("Figure 6: mu = 0", {"mu": 0.0}),
    "fig7_D0": ("Figure 7: D = 0", {"D": 0.0}),
    "fig8_S10": ("Figure 8: S = 10", {"S": 10.0}),
    "fig9_S1e6_10000": ("Figures 9–10: S = 1e6, clockmax 10000",
                        {"S": 1e6, "allow_unstable": True}),
    "fig11_S1e6_20000": ("Figures 11–12: S = 1e6, clockmax 20000",
                         {"S": 1e6, "clockmax": 20000}),
}


def sliding_speed_at_end(run: PaperRun) -> float:
    """Mean x velocity over the last second (Figure 6: mu = 0 keeps sliding)."""
    last = run.t >= run.t[-1] - 1.0
    return float((run.x_cm[-1, 0] - run.x_cm[last][0, 0]) / (run.t[-1] - run.t[last][0]))


def bounce_range_at_end(run: PaperRun) -> float:
    """Peak-to-peak z of the centre over the last two seconds (Figure 7: D = 0 keeps bouncing)."""
    return float(np.ptp(run.x_cm[run.t >= run.t[-1] - 2.0, 2]))


def lowest_centre(run: PaperRun) -> float:
    """Lowest z of the centre of mass (Figure 8: S = 10 sinks below z = 0)."""
    return float(run.x_cm[:, 2].min())


def energy_gain_after_landing(run: PaperRun) -> float:
    """Largest listing energy after the first landing minus its start (Figures 10 and 12)."""
    return float(run.energy[first_landing(run):].max() - run.energy[0])


def first_landing(run: PaperRun) -> int:
    """Index of the step where the centre first reaches its lowest point of the first fall."""
    z = run.x_cm[:, 2]
    falling = np.flatnonzero(np.diff(z) < 0)
    rising_after = np.flatnonzero((np.diff(z) > 0) & (np.arange(len(z) - 1) > falling[0]))
    return int(rising_after[0]) if len(rising_after) else len(z) - 1


def rebound_peaks(run: PaperRun) -> np.ndarray:
    """Heights of the centre at the tops of free flights (no corner touching; launch excluded).

    Needs ``run.nodes``. Maxima of z while a corner is down are rocking, not rebounds.
    """
    z = run.x_cm[:, 2]
    airborne = run.nodes[1:-1, :, 2].min(axis=1) > 0
    top = (z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:]) & airborne
    return z[1:-1][top][1:]


# Figure 13's criteria: the largest energy rise allowed, as a fraction of KE0 + m g (h0 + edge).
CRITERIA = {"rise <= 10%": 0.1, "rise <= 100%": 1.0}


def energy_rises(stiffness: float, clockmaxes: np.ndarray,
                 contact_law: ContactLaw = ContactLaw.PAPER) -> np.ndarray:
    """Largest rise of total energy of ``ground_cube`` runs, one per ``clockmax`` (tmax = 10).

    In units of ``KE0 + m g (h0 + edge)``; ``inf`` when the state stopped being finite or the
    cube ended below the plane (huge steps can carry it through between energy checks).
    """
    tol = paper_scene(S=stiffness, rotation=False, dt=None).energy_tol
    runs = (ground_cube(S=stiffness, clockmax=int(c), contact_law=contact_law,
                        allow_unstable=True) for c in clockmaxes)
    return np.array([np.inf if not np.isfinite(r.x_cm).all() or r.x_cm[-1, 2] <= 0
                     else r.result.energy_rise[0] * tol for r in runs], dtype=float)


def steps_needed(clockmaxes: np.ndarray, rises: np.ndarray, limit: float) -> int:
    """Smallest ``clockmax`` of the ascending grid above which every run keeps ``rise <= limit``.

    Raises ``ValueError`` if the grid does not bracket the threshold.
    """
    bad = np.flatnonzero(rises > limit)
    if len(bad) == 0 or bad[-1] == len(clockmaxes) - 1:
        raise ValueError(f"clockmaxes must bracket the stability threshold for limit {limit}")
    return int(clockmaxes[bad[-1] + 1])


def search_grid(stiffness: float, points: int) -> np.ndarray:
    """Ascending clockmax grid from 1/4 to 4 times the theory's steps (a window, not a guess)."""
    centre = theory_steps(stiffness, node_mass=False)[0]
    return np.unique(np.geomspace(centre / 4, centre * 4, points).astype(int))


def theory_steps(stiffness: np.ndarray, node_mass: bool, tmax: float = 10.0,
                 D: float = 0.2) -> np.ndarray:
    """``tmax / critical_dt`` of the scheme for the paper's ground_cube die.

    Mass m/4 (``Scene.critical_dt``: the bottom corners together), or with ``node_mass`` m/8.
    """
    out = []
    for s in np.atleast_1d(stiffness):
        scene = paper_scene(S=float(s), D=D, rotation=False, dt=None)
        m = scene.die.mass / 8 if node_mass else scene.effective_mass
        out.append(tmax * s / (math.sqrt(D * D + 4 * s * m) - D))
    return np.array(out)


def fit_exponent(stiffness: np.ndarray, steps: np.ndarray) -> float:
    """Slope of log(steps) against log(S) (0.5 for steps growing like sqrt(S))."""
    return float(np.polyfit(np.log(stiffness), np.log(steps), 1)[0])


def real_throws() -> dict[ContactLaw, PaperRun]:
    """Figures 4–5's real throw (seed :data:`THROW_SEED`) under the paper's and the gated law."""
    return {law: real_throw_cube(seed=THROW_SEED, contact_law=law, record_nodes=True)
            for law in (ContactLaw.PAPER, ContactLaw.GATED)}


def variant_runs() -> dict[str, PaperRun]:
    """Figures 6–12's ground-cube runs, one per :data:`VARIANTS` key."""
    return {key: ground_cube(**kw) for key, (_, kw) in VARIANTS.items()}


def run(out: Path = DOCS, quick: bool = False) -> dict[str, float]:
    """Regenerate ``paper.json``, the page's files and the figures under ``out``.

    Return the headline numbers. The files ``generated/paper-*.md`` are rendered from the JSON as
    written; outside docs/ the page ``paper.md`` with them included is written too.
    """
    stiffnesses = np.logspace(3, 6, 4) if quick else np.logspace(1, 8, 15)
    points = 60 if quick else 200
    bar = progress(2 + len(VARIANTS) + len(stiffnesses), "paper figures")
    throws, runs = real_throws(), variant_runs()
    bar.update(2 + len(VARIANTS))
    search = {name: [] for name in CRITERIA}
    for s in stiffnesses:
        grid = search_grid(s, points)
        rises = energy_rises(s, grid)
        for name, limit in CRITERIA.items():
            search[name].append(steps_needed(grid, rises, limit))
        bar.update()
    bar.close()
    search = {name: np.array(v) for name, v in search.items()}
    figs = out / "figures"
    _plot_throw(throws, figs / "paper_fig4_5_real_throw.png")
    _plot_variants(runs, figs / "paper_fig6_12_ground_cube.png")
    numbers = _numbers(throws, runs, stiffnesses, search)
    data = page_data(numbers, throws, stiffnesses, search)
    figure_search(data, figs / "paper_fig13_steps_vs_stiffness.png")
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "paper.json", json.dumps(data, indent=1) + "\n")
    write_study(out, "paper", list(FILES), {"d": json.loads(json.dumps(data))})
    return numbers


def _numbers(throws: dict, runs: dict, stiffnesses: np.ndarray,
             search: dict[str, np.ndarray]) -> dict[str, float]:
    paper_throw = throws[ContactLaw.PAPER]
    m4 = theory_steps(stiffnesses, node_mass=False)
    m8 = theory_steps(stiffnesses, node_mass=True)
    numbers = {
        "mu0_sliding_speed": sliding_speed_at_end(runs["fig6_mu0"]),
        "D0_bounce_range": bounce_range_at_end(runs["fig7_D0"]),
        "S10_lowest_centre": lowest_centre(runs["fig8_S10"]),
        "S1e6_10000_gain": energy_gain_after_landing(runs["fig9_S1e6_10000"]),
        "S1e6_20000_gain": energy_gain_after_landing(runs["fig11_S1e6_20000"]),
        "S1e6_10000_unstable": float(runs["fig9_S1e6_10000"].result.unstable[0]),
        "S1e6_20000_unstable": float(runs["fig11_S1e6_20000"].result.unstable[0]),
        "throw_final_energy": float(paper_throw.energy[-1]),
        "throw_final_potential": float(9.8 * paper_throw.x_cm[-1, 2]),
    }
    big = stiffnesses >= 1e3
    for name, steps in search.items():
        key = "10" if name == "rise <= 10%" else "100"
        numbers[f"fig13_exponent_{key}"] = fit_exponent(stiffnesses[big], steps[big])
        numbers[f"fig13_ratio_meff_{key}"] = float(np.median(steps / m4))
        numbers[f"fig13_ratio_node_{key}"] = float(np.median(steps / m8))
        numbers[f"fig13_ratio_meff_{key}_min"] = float(np.min(steps / m4))
        numbers[f"fig13_ratio_meff_{key}_max"] = float(np.max(steps / m4))
    for law, name in ((ContactLaw.PAPER, "paper"), (ContactLaw.GATED, "gated")):
        numbers[f"throw_{name}_x_end"] = float(throws[law].x_cm[-1, 0])
        numbers[f"throw_{name}_energy_end"] = float(throws[law].energy[-1])
    return numbers


def _plot_throw(throws: dict, path: Path) -> None:
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True, layout="constrained")
    for col, (law, run_) in enumerate(throws.items()):
        axes[0, col].plot(run_.t, run_.x_cm, label=list("xyz"))
        axes[0, col].set_title(f"Figure 4: centre of mass, {law.name.lower()} law")
        axes[0, col].legend()
        axes[1, col].plot(run_.t, run_.energy)
        axes[1, col].set_title(f"Figure 5: total energy (listing), {law.name.lower()} law")
        axes[1, col].set_xlabel("t")
    axes[0, 0].set_ylabel("position")
    axes[1, 0].set_ylabel("energy")
    save_figure(fig, path)


def _plot_variants(runs: dict, path: Path) -> None:
    fig, axes = plt.subplots(2, 4, figsize=(17, 7), layout="constrained")
    for ax, (key, run_) in zip(axes.flat[:5], runs.items(), strict=True):
        ax.plot(run_.t, run_.x_cm, label=list("xyz"))
        ax.set_title(VARIANTS[key][0], fontsize=9)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_xlabel("t")
    axes.flat[0].legend()
    for ax, key in zip(axes.flat[5:7], ("fig9_S1e6_10000", "fig11_S1e6_20000"), strict=True):
        ax.plot(runs[key].t, runs[key].energy, color="C3")
        ax.axhline(runs[key].energy[0], color="k", ls=":", lw=0.8, label="start")
        ax.set_title(VARIANTS[key][0].replace("Figures 9–10", "Figure 10").replace(
            "Figures 11–12", "Figure 12") + ": energy", fontsize=9)
        ax.set_xlabel("t")
        ax.legend()
    axes.flat[7].axis("off")
    save_figure(fig, path)


def figure_search(d: dict, path: Path) -> None:
    """Draw Figure 13 (steps needed against stiffness) from the page's numbers ``d``."""
    stiffnesses = np.array(d["stiffnesses"])
    search = {name: np.array(steps) for name, steps in d["search"].items()}
    fig, ax = plt.subplots(figsize=(7, 5))
    fine = np.logspace(np.log10(stiffnesses[0]), np.log10(stiffnesses[-1]), 200)
    ax.loglog(fine, theory_steps(fine, node_mass=False), "k-",
              label="theory, effective mass m/4 (Scene.critical_dt)")
    ax.loglog(fine, theory_steps(fine, node_mass=True), "k--", label="theory, node mass m/8")
    for (name, steps), marker in zip(search.items(), "ox", strict=True):
        ax.loglog(stiffnesses, steps, marker, label=f"search, energy {name}")
    ax.set(xlabel="stiffness S", ylabel="steps needed (tmax = 10)",
           title="Figure 13: steps needed against stiffness (paper law)")
    ax.legend()
    save_figure(fig, path)


# The page's figures (name: draw), drawn by run; Figures 4–12 simulate their runs again (a
# trajectory each, deterministic), Figure 13 is drawn from the page's numbers.
FIGURES = {"paper_fig4_5_real_throw": lambda d, path: _plot_throw(real_throws(), path),
           "paper_fig6_12_ground_cube": lambda d, path: _plot_variants(variant_runs(), path),
           "paper_fig13_steps_vs_stiffness": figure_search}


def _verdict(ok: bool | str) -> str:
    if isinstance(ok, str):
        return f"**{ok}**"
    return "**confirmed**" if ok else "**not confirmed**"


def page_data(n: dict[str, float], throws: dict, stiffnesses: np.ndarray,
              search: dict[str, np.ndarray]) -> dict:
    """Every number of the page (JSON-ready), kept as ``paper.json``."""
    peaks = rebound_peaks(throws[ContactLaw.PAPER])
    return {"command": COMMAND, "numbers": {k: float(v) for k, v in n.items()},
            "L0": [float(x) for x in throws[ContactLaw.PAPER].L0],
            "first_peaks": [float(p) for p in peaks[:8]],
            "rebounds_higher": int(np.sum(np.diff(peaks) > 0)), "rebounds": len(peaks) - 1,
            "stiffnesses": [float(x) for x in stiffnesses],
            "search": {name: [int(x) for x in v] for name, v in search.items()}}


@generated("paper-the-paper-reproduced", COMMAND, d=JSON)
def intro_text(d: dict) -> str:
    """Where the page's runs come from, and the real throw's L0."""
    L0 = np.array2string(np.array(d["L0"]), precision=4)
    return f"""\
Generated by `python -m studies paper` (module `studies/paper_figures.py`)
from the paper's own scripts (`dice_env.simulation.paper.real_throw_cube`, `ground_cube`) with
its own contact law and defaults. The real throw uses the listing's random initial angular momentum
drawn with seed {THROW_SEED}: L0 = {L0}."""


@generated("paper-claims", COMMAND, d=JSON)
def claims_table(d: dict) -> str:
    """Each figure's claim, what our run shows, and the verdict."""
    n, peaks, rises = d["numbers"], d["first_peaks"], d["rebounds_higher"]
    rows = [
        ("4", "z bounces with each rebound lower than the last",
         f"tops of the first free flights: {', '.join(f'{p:.2f}' for p in peaks)}; "
         f"{rises} of {d['rebounds']} rebounds higher than the one before (spin turned "
         "into bounce at an impact)", "partly" if rises else True),
        ("4", "x increases then tapers off (friction)",
         f"x at 10 s: {n['throw_paper_x_end']:.2f}", True),
        ("5", "energy decreases and tapers off above zero (centre stays above ground)",
         f"E(10 s) = {n['throw_final_energy']:.2f}, m g z = {n['throw_final_potential']:.2f}",
         abs(n["throw_final_energy"] - n["throw_final_potential"]) < 0.1),
        ("6", "mu = 0: keeps sliding", f"x speed over the last second "
         f"{n['mu0_sliding_speed']:.3f} (launch speed 5)", n["mu0_sliding_speed"] > 4.0),
        ("7", "D = 0: keeps bouncing", f"z range over the last 2 s "
         f"{n['D0_bounce_range']:.2f}", n["D0_bounce_range"] > 1.0),
        ("8", "S = 10: the centre dips below z = 0", f"lowest z = {n['S10_lowest_centre']:.3f}",
         n["S10_lowest_centre"] < 0),
        ("9–10", "S = 1e6, clockmax 10000: bounces higher, energy grows",
         f"largest energy after landing minus start {n['S1e6_10000_gain']:+.1f}; "
         f"flagged unstable: {bool(n['S1e6_10000_unstable'])}", n["S1e6_10000_gain"] > 0),
        ("11–12", "S = 1e6, clockmax 20000: normal again",
         f"largest energy after landing minus start {n['S1e6_20000_gain']:+.1f}; "
         f"flagged unstable: {bool(n['S1e6_20000_unstable'])}", n["S1e6_20000_gain"] < 0),
        ("13", "more stiffness needs more steps (we test: like sqrt(S))",
         f"fitted exponent for S >= 1e3: {n['fig13_exponent_10']:.3f} (10% criterion), "
         f"{n['fig13_exponent_100']:.3f} (100% criterion)",
         max(abs(n["fig13_exponent_10"] - 0.5), abs(n["fig13_exponent_100"] - 0.5)) < 0.05),
    ]
    return markdown_table("figure | the paper says | our run | verdict",
                          ((fig, claim, ours, _verdict(ok)) for fig, claim, ours, ok in rows))


@generated("paper-figures-4-and-5", COMMAND, d=JSON)
def throw_text(d: dict) -> str:
    """The paper's contact law against the gated law on the real throw."""
    n = d["numbers"]
    return f"""\
Left the paper's contact law, right the gated law (same die, same L0). The paper's
`fn = max(0, S*dg - D*un)` acts on every corner, also those above the ground: a corner
moving down feels `-D*un` > 0 pushing it up, an air drag of about 8·D·v = 0.8·v on the falling
cube (D = 0.1), and in contact the corners still in the air damp the rocking. The gated law
applies the ground force only to corners below the plane. With the paper law the throw loses
more energy in flight and slides less far: x at 10 s is {n['throw_paper_x_end']:.2f} (paper) vs
{n['throw_gated_x_end']:.2f} (gated); listing energy at 10 s {n['throw_paper_energy_end']:.2f}
vs {n['throw_gated_energy_end']:.2f}. Past the first impacts the two runs are different
trajectories of a chaotic system, not one curve with a small correction."""


@generated("paper-figure-13-steps-needed", COMMAND, d=JSON)
def steps_text(d: dict) -> str:
    """Figure 13: the steps the search needs against the two theory lines."""
    n, search = d["numbers"], d["search"]
    steps = markdown_table(
        "S | " + " | ".join(f"search, energy {name}" for name in search)
        + " | theory m/4 | theory m/8",
        ((f"{s:.3g}", *(search[name][i] for name in search),
          f"{theory_steps(s, False)[0]:.0f}", f"{theory_steps(s, True)[0]:.0f}")
         for i, s in enumerate(d["stiffnesses"])))
    return f"""\
- "Does not blow up" (100%) follows the **effective-mass line**: median steps/theory
  {n['fig13_ratio_meff_100']:.3f} for m/4, {n['fig13_ratio_node_100']:.3f} for m/8. This is the
  linear stability bound of the scheme for the mass that really sits on the contact.
- The 10% criterion asks for accuracy, not only stability: {n['fig13_ratio_meff_10_min']:.2f}–
  {n['fig13_ratio_meff_10_max']:.2f} times the m/4 line (median {n['fig13_ratio_meff_10']:.3f};
  {n['fig13_ratio_node_10']:.3f} times the m/8 line). Close to the critical step the scheme is
  stable but each impact's energy error is large, so it needs more steps than the bound.
- The node-mass line asks for sqrt(2) times the steps of the effective-mass line: more than
  either search needs, so for this die it is a conservative bound, not the limit.
- Both grow like sqrt(S) for S >= 1e3: fitted exponents {n['fig13_exponent_10']:.3f} (10%) and
  {n['fig13_exponent_100']:.3f} (100%). At small S the damping term (D^2 next to 4 S m) and the
  coarse flight steps (a few dozen steps for 10 s) bend the curve.

{steps}"""

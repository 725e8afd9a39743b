"""Error against run time: ``python -m studies error`` writes docs/error-vs-runtime.md.

:func:`trajectory_errors` against step and CPU time, :func:`outcome_test` (``dt`` against
``dt/4``) and :func:`face_agreement` beside the chaos floor; the page explains each.
"""

from __future__ import annotations

import itertools
import json
import math
import time
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.stats import chi2_contingency, norm

from dice_env.markdown import markdown_table
from dice_env.model.defaults import DAMPING, FRICTION, RESTITUTION, STIFFNESS
from dice_env.model.rotations import random_rotations
from dice_env.model.scene import FrictionLaw, Scene, Scheme
from dice_env.simulation.calibration import measured_restitution
from dice_env.simulation.simulate import Result, State, simulate
from dice_env.throws import (
    RELEASES,
    T_THROW,
    Release,
    face_agreement,
)
from studies.common import SEED, draw_figures, progress, save_figure, write_text
from studies.docs_numbers import generated
from studies.templates import write_study

COMMAND = "python -m studies error"  # writes docs/generated/error-vs-runtime-*.md
JSON = "docs/error-vs-runtime.json"  # every number of the page, written by the full study
FILES = tuple(f"error-vs-runtime-{part}" for part in (
    "intro", "default-scene-real", "default-scene-real-2", "default-scene-real-3",
    "1-trajectory-error", "1-trajectory-error-2", "1-trajectory-error-3",
    "2-outcome-statistics", "2-outcome-statistics-2", "3-throw-face", "3-throw-face-2",
    "3-throw-face-3", "conclusions"))
ENERGY_BINS = (0.0, 0.06, 0.12, 0.2, 0.3, np.inf)  # drop heights E / (m g) (m) of the bins


def spread_throws(scene: Scene, n: int, rng: np.random.Generator) -> State:
    """Throws from gentle to vigorous: centre 3–30 cm up, hand speeds and spins, any tilt."""
    position = np.column_stack([np.zeros((n, 2)), rng.uniform(0.03, 0.30, n)])
    velocity = rng.normal(0.0, 0.6, (n, 3))
    spin = rng.normal(0.0, 12.0, (n, 3))
    return State.release(scene, position, velocity, spin, random_rotations(rng, n))


def drop_height(scene: Scene, state: State) -> np.ndarray:
    """Throw energy as an equivalent drop height ``E / (m g)`` (m), E relative to resting flat."""
    die = scene.die
    inv = np.linalg.inv(state.orientation @ die.inertia_body @ state.orientation.transpose(0, 2, 1))
    spin = np.einsum("bij,bj->bi", inv, state.angular_momentum)
    kinetic = 0.5 * die.mass * (state.velocity**2).sum(1) + 0.5 * np.einsum(
        "bi,bi->b", state.angular_momentum, spin)
    return kinetic / (die.mass * scene.gravity) + state.position[:, 2] - die.resting_heights.min()


def timed(scene: Scene, state: State, **kwargs: object) -> tuple[Result, float]:
    """:func:`simulate` and the CPU seconds it took per throw."""
    start = time.process_time()
    result = simulate(scene, state, **kwargs)
    return result, (time.process_time() - start) / state.batch_size


def rotation_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (rad) of the rotation between orientations ``a`` and ``b`` (..., 3, 3)."""
    trace = np.einsum("...ij,...ij->...", a, b)
    return np.arccos(np.clip((trace - 1.0) / 2.0, -1.0, 1.0))


def trajectory_errors(scene: Scene, start: State, horizon: float, safeties: tuple[float, ...],
                      reference: Result, *, free_flight: bool = True) -> dict[str, np.ndarray]:
    """Median centre and orientation error at ``horizon`` for steps ``safety * critical_dt``.

    ``reference``: the same model at a much finer step. Returns ``dt`` (rounded to divide
    ``horizon``), ``position`` (m), ``angle`` (rad) and ``cpu`` (s per throw).
    """
    out: dict[str, list[float]] = {"dt": [], "position": [], "angle": [], "cpu": []}
    for safety in safeties:
        dt = safety * scene.critical_dt
        result, cpu = run_at(scene, start, horizon, dt, free_flight=free_flight)
        out["dt"].append(horizon / round(horizon / dt))
        out["position"].append(float(np.median(np.linalg.norm(
            result.final.position - reference.final.position, axis=1))))
        out["angle"].append(float(np.median(rotation_angle(
            result.final.orientation, reference.final.orientation))))
        out["cpu"].append(cpu)
    return {k: np.array(v) for k, v in out.items()}


def run_at(scene: Scene, start: State, horizon: float, dt: float,
           free_flight: bool = True) -> tuple[Result, float]:
    """Run ``start`` to exactly ``horizon`` with the step nearest ``dt`` that divides it."""
    steps = max(1, round(horizon / dt))
    fixed = scene.with_(dt=horizon / steps, t_max=horizon, allow_unstable=True)
    return timed(fixed, start, until="t_max", free_flight=free_flight, num_threads=1)


def observed_order(dt: np.ndarray, error: np.ndarray) -> float:
    """Least-squares slope of log error against log dt."""
    return float(np.polyfit(np.log(dt), np.log(error), 1)[0])


def outcome_test(scene: Scene, release: Release, n: int, rng: np.random.Generator,
                 factor: int = 4) -> dict[str, object]:
    """Face counts at ``dt`` and ``dt/factor`` on independent draws of ``n`` throws each.

    Two-sample tests: chi-square homogeneity of the 2 x 6 count table (``p_faces``) and the
    two-proportion z-test of the success probability (``p_success``).
    """
    fine = scene.with_(dt=scene.step / factor, t_max=T_THROW)
    coarse, cpu = timed(scene.with_(t_max=T_THROW), release.sample(scene, n, rng))
    finer, cpu_fine = timed(fine, release.sample(scene, n, rng))
    counts = np.array([np.bincount(r.face, minlength=7)[1:] for r in (coarse, finer)])
    seen = counts.sum(0) > 0
    p_faces = float(chi2_contingency(counts[:, seen])[1]) if seen.sum() > 1 else 1.0
    success = counts[:, release.target - 1] / n
    pooled = success.mean()
    se = math.sqrt(max(2 * pooled * (1 - pooled) / n, 1e-300))
    p_success = float(2 * norm.sf(abs(success[0] - success[1]) / se))
    return {"counts": counts, "success": success, "se": se, "p_faces": p_faces,
            "p_success": p_success, "cpu": cpu, "cpu_fine": cpu_fine,
            "settled": float(min(coarse.settled.mean(), finer.settled.mean()))}


def binned(height: np.ndarray, agree: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Agreement fraction, its standard error and the count per :data:`ENERGY_BINS` bin."""
    which = np.digitize(height, ENERGY_BINS) - 1
    count = np.array([np.sum(which == b) for b in range(len(ENERGY_BINS) - 1)])
    hits = np.array([np.sum(agree[which == b]) for b in range(len(ENERGY_BINS) - 1)])
    with np.errstate(invalid="ignore"):  # an empty bin: nan
        fraction = hits / count
        return fraction, np.sqrt(fraction * (1 - fraction) / count), count


# Throws of each part of the full and quick runs.
FULL = {"trajectory": 200, "outcomes": 10_000, "agreement": 3000, "gentle": 2000}
QUICK = {"trajectory": 12, "outcomes": 300, "agreement": 120, "gentle": 100}
SAFETIES = (0.6, 0.3, 0.15, 0.075, 0.0375, 0.01875, 0.009375)  # fractions of the critical step
# Horizon (s) of the trajectory error: releases 6–10 cm up land at about 0.1 s and hit the
# table two or three times by then.
HORIZON = 0.25
# The listing's friction with the default's integration is compared with the default throughout.
LISTING_FRICTION = "paper scheme, listing friction, analytic flight"
DEFAULT = "default (midpoint, stick-slip, analytic flight)"
LISTING = "listing (paper scheme, listing friction, every step)"
GENTLE_DIVISORS = (1, 2, 4)  # the gentle release's steps compared: dt/a against dt/(4a)
REFERENCE_DT = Scene().step / 128  # s: the reference runs' step (midpoint scheme)


def variants() -> dict[str, tuple[Scene, bool]]:
    """Scenes compared in the work-precision plot: (scene, free flight)."""
    default = Scene()
    listing = default.with_(friction_law=FrictionLaw.REGULARIZED, scheme=Scheme.PAPER)
    return {
        LISTING: (listing, False),
        LISTING_FRICTION: (listing, True),
        "paper scheme, stick-slip, analytic flight": (default.with_(scheme=Scheme.PAPER), True),
        DEFAULT: (default, True),
        "midpoint, vmin 0.05 m/s, analytic flight": (
            listing.with_(friction_vmin=0.05, scheme=Scheme.MIDPOINT), True),
    }


def run(out: Path, quick: bool = False) -> dict[str, float]:
    """Run the study and write ``out/error-vs-runtime.md`` and its figures; headline numbers."""
    sizes = QUICK if quick else FULL
    rng = np.random.default_rng(SEED)
    scene = Scene()
    compared = {"default": scene, LISTING_FRICTION: variants()[LISTING_FRICTION][0]}
    parts = len(variants()) + len(compared) * (len(RELEASES) + 1) + 3  # gentle, steps, restitution
    bar = progress(parts, "error study", "part")
    numbers: dict[str, object] = {"scene": scene, "sizes": sizes}

    # 1. trajectory error against step and CPU time
    start = trajectory_start(scene, sizes["trajectory"], rng)
    curves = numbers["curves"] = {}
    references: dict[tuple[FrictionLaw, float], Result] = {}
    for name, (variant, flight) in variants().items():
        bar.set_postfix_str(name)
        model = (variant.friction_law, variant.friction_vmin)
        if model not in references:
            references[model] = run_at(
                variant.with_(scheme=Scheme.MIDPOINT), start, HORIZON, REFERENCE_DT)[0]
        curves[name] = trajectory_errors(variant, start, HORIZON, SAFETIES, references[model],
                                         free_flight=flight)
        bar.update()

    # 2. outcome statistics of fixed releases
    outcomes = numbers["outcomes"] = {label: {} for label in compared}
    for label, variant in compared.items():
        for release in RELEASES:
            bar.set_postfix_str(f"{release.name}, {label}")
            outcomes[label][release.name] = outcome_test(variant, release, sizes["outcomes"], rng)
            bar.update()

    # 3. per-throw agreement, binned by energy, and the gentle release
    spread = spread_throws(scene, sizes["agreement"], rng)
    numbers["height"] = drop_height(scene, spread)
    numbers["agreement"] = {}
    for label, variant in compared.items():
        bar.set_postfix_str(f"agreement, {label}")
        numbers["agreement"][label] = face_agreement(variant, spread)
        bar.update()
    bar.set_postfix_str("gentle")
    gentle = RELEASES[0].sample(scene, sizes["gentle"], rng)
    numbers["gentle"] = {name: face_agreement(variant, gentle)
                         for name, (variant, _) in list(variants().items())[1:]}
    bar.update()
    bar.set_postfix_str("gentle steps")
    numbers["gentle_steps"] = {
        a: float(face_agreement(scene.with_(dt=scene.step / a), gentle)["step"].mean())
        for a in GENTLE_DIVISORS}
    bar.update()
    bar.set_postfix_str("restitution")
    numbers["restitution"] = {
        (speed, factor): measured_restitution(scene.with_(dt=scene.step / factor), speed)
        for speed in (0.3, 1.0, 3.0) for factor in (1, 4)}
    bar.update()
    bar.close()
    return write_report(out, numbers, quick)


def trajectory_start(scene: Scene, n: int, rng: np.random.Generator) -> State:
    """Releases 6–10 cm up with a little speed and spin, any orientation."""
    position = np.column_stack([np.zeros((n, 2)), rng.uniform(0.06, 0.10, n)])
    return State.release(scene, position, rng.normal(0.0, 0.3, (n, 3)),
                         rng.normal(0.0, 10.0, (n, 3)), random_rotations(rng, n))


def _save(fig: plt.Figure, path: Path) -> None:
    """Lay ``fig`` out tightly and write it (:func:`studies.common.save_figure`)."""
    fig.tight_layout()
    save_figure(fig, path)


def figure_work_precision(d: dict, path: Path) -> None:
    """Draw ``figures/error-vs-runtime.png``: error against step and against CPU time."""
    curves = {name: {k: np.array(v) for k, v in c.items()} for name, c in d["curves"].items()}
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for name, c in curves.items():
        left.loglog(c["dt"], 1e3 * c["position"], "o-", label=name)
        right.loglog(1e3 * c["cpu"], 1e3 * c["position"], "o-", label=name)
    dt = curves[DEFAULT]["dt"]
    anchor = 1e3 * curves[DEFAULT]["position"][-1]
    for order, style in ((1, ":"), (2, "--")):
        left.loglog(dt, anchor * (dt / dt[-1]) ** order, "k" + style, lw=0.8,
                    label=f"order {order}")
    left.set(xlabel="step dt (s)", ylabel="median centre error at 0.25 s (mm)",
             title="error against step")
    right.set(xlabel="CPU time per throw, 0.25 s of throw (ms)",
              ylabel="median centre error at 0.25 s (mm)", title="error against run time")
    left.legend(fontsize=7)
    _save(fig, path)


def figure_agreement(d: dict, path: Path) -> None:
    """Draw ``figures/face-agreement.png``: the per-throw face agreement by throw energy."""
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    labels = _bin_labels(">")
    x = np.arange(len(labels))
    shift = -0.15
    for scene_label, result in d["agreement"]["scenes"].items():
        for key, label, marker in (("step", "dt vs dt/4", "o"),
                                   ("floor", "chaos floor (spin + 1e-9 rad/s)", "s")):
            frac, err = np.array(result[key]).T
            ax.errorbar(x + shift, 100 * frac, 200 * err, fmt=marker, capsize=3,
                        label=f"{scene_label}: {label}")
            shift += 0.1
    ax.axhline(100 / 6, color="grey", lw=0.8, ls=":", label="chance (1/6)")
    ax.set(xticks=x, xticklabels=labels, ylim=(0, 102), ylabel="same face (%)",
           xlabel="throw energy as drop height E/(m g) (cm)",
           title="per-throw face agreement (±2 s.e.)")
    ax.legend(fontsize=7)
    _save(fig, path)


def figure_outcomes(d: dict, path: Path) -> None:
    """Draw ``figures/outcome-statistics.png``: the default scene's faces at dt and dt/4."""
    outcomes = d["outcomes"]["default"]
    fig, axes = plt.subplots(1, len(outcomes), figsize=(11, 3.4), sharey=True)
    for ax, (name, o) in zip(axes, outcomes.items(), strict=True):
        freq, n = np.array(o["shares"]), np.array(o["counted"])[:, None]
        err = 2 * np.sqrt(freq * (1 - freq) / n)
        faces = np.arange(1, 7)
        ax.bar(faces - 0.2, 100 * freq[0], 0.4, yerr=100 * err[0], capsize=2, label="dt")
        ax.bar(faces + 0.2, 100 * freq[1], 0.4, yerr=100 * err[1], capsize=2, label="dt/4")
        ax.set(title=f"{name}: chi² p = {o['p_faces']:.2f}", xlabel="face up", xticks=faces)
    axes[0].set_ylabel("frequency (%), ±2 s.e.")
    axes[0].legend()
    _save(fig, path)


# The page's figures (name: draw from the page's numbers), drawn by write_report.
FIGURES = {"error-vs-runtime": figure_work_precision, "face-agreement": figure_agreement,
           "outcome-statistics": figure_outcomes}


def _ratio_at_equal_error(slow: dict[str, np.ndarray], fast: dict[str, np.ndarray],
                          index: int) -> float:
    """CPU of ``slow`` at the error of ``fast`` at ``index`` (log-log), over that of ``fast``."""
    target = fast["position"][index]
    order = np.argsort(slow["position"])
    cpu = np.exp(np.interp(np.log(target), np.log(slow["position"][order]),
                           np.log(slow["cpu"][order])))
    return float(cpu / fast["cpu"][index])


def write_report(out: Path, numbers: dict[str, object], quick: bool) -> dict[str, float]:
    """Write the markdown and PNGs under ``out``; return the headline numbers."""
    scene, curves, outcomes, agreement, gentle, gentle_steps = (numbers[k] for k in (
        "scene", "curves", "outcomes", "agreement", "gentle", "gentle_steps"))
    ratio = _ratio_at_equal_error(curves[LISTING], curves[DEFAULT], SAFETIES.index(scene.safety))
    orders = {name: observed_order(c["dt"][-4:], c["position"][-4:]) for name, c in curves.items()}
    pen = agreement["default"]["penetration"] / scene.die.size
    verdicts = {}
    for label, per in outcomes.items():
        name = DEFAULT if label == "default" else label
        verdicts[label] = {"gentle": float(gentle[name]["step"].mean()), "order": orders[name],
                           "p_min": min(min(o["p_faces"], o["p_success"]) for o in per.values())}
    data = page_data(numbers, quick, ratio, orders, pen, verdicts)
    draw_figures(FIGURES, data, out)
    write_text(out / "error-vs-runtime.json", json.dumps(data, indent=1) + "\n")
    write_study(out, "error-vs-runtime", list(FILES), {"d": json.loads(json.dumps(data))})
    return {"cpu_ratio_at_equal_error": ratio, "order_default": orders[DEFAULT],
            "gentle_agreement": verdicts["default"]["gentle"],
            "min_p_value": verdicts["default"]["p_min"],
            "gentle_agreement_listing_friction": verdicts[LISTING_FRICTION]["gentle"],
            "min_p_value_listing_friction": verdicts[LISTING_FRICTION]["p_min"],
            **{f"gentle_agreement_dt/{a}_vs_dt/{4 * a}": p for a, p in gentle_steps.items()},
            "corner_sink_max": float(pen.max())}


def _verdict(ok: bool) -> str:
    return "met" if ok else "**not met**"


def page_data(numbers: dict, quick: bool, ratio: float, orders: dict, pen: np.ndarray,
              verdicts: dict) -> dict:
    """Every number of the page (JSON-ready), kept as ``error-vs-runtime.json``."""
    height, e = numbers["height"], numbers["restitution"]

    def outcome(o: dict) -> dict:
        counts = np.asarray(o["counts"])
        return {"shares": (counts / counts.sum(1, keepdims=True))[:2].tolist(),
                "counted": counts.sum(1)[:2].tolist(),
                "success": [float(x) for x in o["success"][:2]],
                **{k: float(o[k]) for k in ("se", "p_faces", "p_success", "settled", "cpu",
                                            "cpu_fine")}}

    def gentle(g: dict) -> dict:
        p = float(g["step"].mean())
        return {"step": p, "se": math.sqrt(p * (1 - p) / g["step"].size),
                "floor": float(g["floor"].mean())}

    def agreement(result: dict, key: str) -> list[list[float]]:
        share, se, _ = binned(height, result[key])
        return [[float(f), float(s)] for f, s in zip(share, se, strict=True)]

    first = next(iter(numbers["agreement"].values()))
    return {
        "command": COMMAND + (" --quick" if quick else ""), "quick": quick,
        "sizes": dict(numbers["sizes"]),
        "restitution": [[speed, e[(speed, 1)], e[(speed, 4)]] for speed in (0.3, 1.0, 3.0)],
        "sink": {"throws": int(pen.size), "median": float(np.median(pen)),
                 "p99": float(np.percentile(pen, 99)), "max": float(pen.max())},
        "curves": {name: {k: [float(x) for x in c[k]] for k in ("dt", "position", "angle",
                                                                   "cpu")}
                   for name, c in numbers["curves"].items()},
        "orders": orders, "ratio": ratio,
        "outcomes": {label: {name: outcome(o) for name, o in per.items()}
                     for label, per in numbers["outcomes"].items()},
        "agreement": {"throws": [int(x) for x in binned(height, first["step"])[2]],
                      "scenes": {label: {key: agreement(result, key) for key in ("step", "floor")}
                                 for label, result in numbers["agreement"].items()}},
        "gentle": {name: gentle(g) for name, g in numbers["gentle"].items()},
        "gentle_steps": [[a, p] for a, p in numbers["gentle_steps"].items()],
        "verdicts": verdicts}


def _outcome_table(outcomes: dict) -> str:
    return markdown_table(
        "scene | release | faces 1–6 at dt (%) | faces 1–6 at dt/4 (%) | P(success) dt | "
        "P(success) dt/4 | ± s.e. | p faces | p success | settled | CPU ms/throw dt, dt/4",
        (_outcome_row(scene_label, name, o) for scene_label, per in outcomes.items()
         for name, o in per.items()))


def _outcome_row(scene_label: str, name: str, o: dict) -> tuple:
    return (scene_label, name, *(" ".join(f"{100 * v:.1f}" for v in f) for f in o["shares"]),
            f"{o['success'][0]:.4f}", f"{o['success'][1]:.4f}", f"{o['se']:.4f}",
            f"{o['p_faces']:.3f}", f"{o['p_success']:.3f}", f"{100 * o['settled']:.1f} %",
            f"{1e3 * o['cpu']:.2f}, {1e3 * o['cpu_fine']:.2f}")


def _agreement_table(agreement: dict) -> str:
    scenes = agreement["scenes"]
    header = "E/(m g) (cm) | throws | " + " | ".join(
        f"{label}: dt vs dt/4 (%) | {label}: chaos floor (%)" for label in scenes)
    columns = [result[key] for result in scenes.values() for key in ("step", "floor")]
    return markdown_table(header, ((label, agreement["throws"][b], *(
        f"{100 * column[b][0]:.1f} ± {100 * column[b][1]:.1f}" for column in columns))
        for b, label in enumerate(_bin_labels("> "))))


def _bin_labels(above: str) -> list[str]:
    """The :data:`ENERGY_BINS` in cm: ``low–high``, the last ``{above}low``."""
    return [f"{100 * a:.0f}–{100 * b:.0f}" if np.isfinite(b) else f"{above}{100 * a:.0f}"
            for a, b in itertools.pairwise(ENERGY_BINS)]


def _gentle_table(gentle: dict) -> str:
    return markdown_table("variant | dt (µs) | dt vs dt/4 (%) | chaos floor (%)", (
        (name, f"{1e6 * variants()[name][0].step:.2f}",
         f"{100 * g['step']:.1f} ± {100 * g['se']:.1f}", f"{100 * g['floor']:.1f}")
        for name, g in gentle.items()))


def lines(items: object) -> str:
    """``items`` one per line."""
    return "\n".join(items)


def _page(d: dict) -> dict[str, str]:
    """The page's generated files (``docs/generated/error-vs-runtime-*.md``) from its numbers."""
    scene = Scene()
    paper = scene.with_(scheme=Scheme.PAPER)
    m_ratio = scene.die.mass / scene.effective_mass
    quick, sizes, ratio, orders, verdicts = (d[k] for k in ("quick", "sizes", "ratio", "orders",
                                                             "verdicts"))
    sink = d["sink"]
    gentle_steps = {a: p for a, p in d["gentle_steps"]}
    paper_gentle = d["gentle"]["paper scheme, stick-slip, analytic flight"]["step"]
    restitution = markdown_table("impact speed (m/s) | at dt | at dt/4", (
        (speed, f"{e1:.4f}", f"{e4:.4f}") for speed, e1, e4 in d["restitution"]))
    work = markdown_table(
        "variant | dt (µs) | centre error (mm) | angle error (mrad) | CPU (µs/throw)",
        ((name, f"{1e6 * c['dt'][j]:.2f}", f"{1e3 * c['position'][j]:.4f}",
          f"{1e3 * c['angle'][j]:.3f}", f"{1e6 * c['cpu'][j]:.0f}")
         for name, c in d["curves"].items() for j in range(len(c["dt"]))))
    outcome_table = _outcome_table(d["outcomes"])
    agreement_table = _agreement_table(d["agreement"])
    gentle_table = _gentle_table(d["gentle"])
    return {
        "error-vs-runtime-intro": f"""\
Generated by `python -m studies error`{" --quick (reduced sizes: numbers are not the study's)" if quick else ""}; throws per part: trajectory {sizes['trajectory']}, outcomes {sizes['outcomes']} per release and step, agreement {sizes['agreement']}, gentle {sizes['gentle']}.""",  # noqa: E501
        "error-vs-runtime-default-scene-real": f"""\
| quantity | value | source |
|---|---|---|
| die | {1e3 * scene.die.size:.0f} mm, {1e3 * scene.die.mass:.1f} g, uniform | the common game die; a 16 mm PMMA cube (1.18 g/cm³) is 4.8 g before the pips are drilled |
| restitution (normal, flat landing) | {RESTITUTION} (target) | dice on wooden tables, 0.4–0.5 [1, 2] |
| sliding friction | {FRICTION}, stick-slip | plastic on dry wood 0.3–0.5 [3, 4]; sticking springs {scene.ground.tangential:.3g} × S and D per corner [7, 8] |
| stiffness per corner | {STIFFNESS:.0e} N/m | deepest corner sink ≤ about 3 % of the edge (measured below) |
| damping per corner | {DAMPING:.3f} N s/m | from the restitution (relation below) |
| critical step ({scene.scheme.name.lower()} scheme) | {scene.critical_dt:.4g} s | stiffest contact mode, effective mass m/{scene.die.mass / scene.effective_mass:.1f} (sliding coupled to rocking) |
| default step | {scene.step:.4g} s | safety {scene.safety} × critical |""",  # noqa: E501
        "error-vs-runtime-default-scene-real-2": f"""\
{restitution}""",
        "error-vs-runtime-default-scene-real-3": f"""\
**Corner sink.** Over the {sink['throws']} spread throws below (3–30 cm, hand speeds and spins), the deepest corner sink is {100 * sink['median']:.2f} % of the edge (median), {100 * sink['p99']:.2f} % (99th percentile), {100 * sink['max']:.2f} % (max).""",  # noqa: E501
        "error-vs-runtime-1-trajectory-error": f"""\
{sizes['trajectory']} releases 6–10 cm up (speed ≈ 0.3 m/s, spin ≈ 10 rad/s per component, any orientation) are run to t = {HORIZON} s, which holds the first two or three impacts; the error is the median distance of the centre of mass (and the median rotation angle) from a reference run of the same model (same friction law, midpoint scheme) at 1/128 of the default step. CPU time is per throw of 0.25 s, one thread.""",  # noqa: E501
        "error-vs-runtime-1-trajectory-error-2": f"""\
{work}""",
        "error-vs-runtime-1-trajectory-error-3": f"""\
{lines(f"- {name}: {order:.2f}" for name, order in orders.items())}

**At equal trajectory error the default costs {ratio:.0f}× less CPU than the paper scheme stepping every step** (the listing's CPU interpolated at the default's error at safety {scene.safety}). The gain is the free flight between impacts (its jumps are the paper's Euler steps in closed form) and the stick-slip friction's smaller error.""",  # noqa: E501
        "error-vs-runtime-2-outcome-statistics": f"""\
Three fixed releases with hand noise, {sizes['outcomes']} independent throws at each step (different draws, so the samples are independent), in the default scene and with the listing's friction ('{LISTING_FRICTION}'). Tests: chi-square test of homogeneity of the 2 × 6 table of face counts, and the two-proportion z-test of the success probability (face 1 up). A p-value above 0.05 means no difference detectable at this sample size.""",  # noqa: E501
        "error-vs-runtime-2-outcome-statistics-2": f"""\
{outcome_table}

Releases: {"; ".join(f"{r.name}: centre {100 * r.height:.1f} cm up, v = {r.velocity} m/s, ω = {r.spin} rad/s, tilt {r.tilt} rad, noise σ = {1e3 * r.sigma_position:.0f} mm, {r.sigma_velocity} m/s, {r.sigma_spin} rad/s, {r.sigma_angle} rad" for r in RELEASES)}.""",  # noqa: E501
        "error-vs-runtime-3-throw-face": f"""\
{sizes['agreement']} spread throws (centre 3–30 cm up, velocity σ = 0.6 m/s and spin σ = 12 rad/s per component, any orientation), binned by their energy as a drop height, in both scenes. 'dt vs dt/4': the same release lands on the same face at both steps. 'Chaos floor': the same face at dt after adding 1e-9 rad/s to each spin component.""",  # noqa: E501
        "error-vs-runtime-3-throw-face-2": f"""\
{agreement_table}

**Gentle release** ({sizes['gentle']} throws of the 'gentle' release above: a 5 cm drop, spin σ = 0.5 rad/s), dt vs dt/4 and the chaos floor, per scheme and friction law:

{gentle_table}""",  # noqa: E501
        "error-vs-runtime-3-throw-face-3": f"""\
{markdown_table("steps compared | agreement (%)", ((f"{'dt' if a == 1 else f'dt/{a}'} vs dt/{4 * a}", f"{100 * p:.1f}") for a, p in gentle_steps.items()))}""",  # noqa: E501
        "error-vs-runtime-conclusions": f"""\
- Corner sink ≤ about 3 % of the edge: {_verdict(sink['p99'] <= 0.035)} (99th percentile {100 * sink['p99']:.2f} %).
- 10× less CPU than the paper scheme at equal trajectory error: {_verdict(ratio >= 10)} ({ratio:.0f}×).
{lines(f"- **{label}**: observed order {v['order']:.2f}; outcome statistics at dt and dt/4 agree within statistical error (all 6 p-values > 0.01): {_verdict(v['p_min'] > 0.01)} (smallest {v['p_min']:.3g}); gentle throws keep their face between dt and dt/4 in ≥ 98 % of cases: {_verdict(v['gentle'] >= 0.98)} ({100 * v['gentle']:.1f} %)." for label, v in verdicts.items())}
- Why the listing's friction does not converge: with vmin = 1e-6 m/s its force is a sign function of the slip velocity, so a corner that stops slipping dithers about zero slip speed, switching the force's direction every step; a large vmin converges but creeps (on a 15° table a die slides at about 2·vmin instead of sticking). The default stick-slip friction ties a sticking corner with a tangential spring (it holds a die on a 15° table to 0.2 µm and slides it down a 30° table at Coulomb's acceleration, `tests/test_core.py`), and it takes the slip direction from the slip velocity.
- The step: with the stick-slip friction, the paper's first-order step keeps the gentle release's face between dt and dt/4 in {100 * paper_gentle:.1f} % of throws; the default midpoint scheme in {100 * gentle_steps[1]:.1f} %, and {100 * gentle_steps[GENTLE_DIVISORS[-1]]:.1f} % between dt/{GENTLE_DIVISORS[-1]} and dt/{4 * GENTLE_DIVISORS[-1]} (tables above). It extrapolates the corner velocities to the middle of the kick and weights the damping of a corner that just touched by its time in contact; the friction limit μ·fn takes the unweighted normal force. Its stable step is smaller ({scene.critical_dt:.2g} s against {paper.critical_dt:.2g} s for the same m/{m_ratio:.0f} mode), so at the same safety it takes {paper.critical_dt / scene.critical_dt:.1f}× the steps of the paper scheme.""",  # noqa: E501
    }


def _renderer(name: str) -> None:
    generated(name, COMMAND, d=JSON)(lambda d: _page(d)[name])


for _name in FILES:
    _renderer(_name)

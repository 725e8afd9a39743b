"""Evaluate a trained run against baselines and the oracle, explain its strategy, write a report.

    python -m agents.evaluate RUN_DIR [--eval-throws 1000] [--oracle-observations 64]

All throwers (PPO, the task's rule where it has one, random) face the same observations and the
same hand noise (common random numbers): on ``eval_throws`` throws each, and with the oracle on
its observations × ``ORACLE_SCORE_SAMPLES`` fresh throws. The views size themselves to the task:
success per face of one die (d6, d20) or per total of two dice; for one die the turn and
strategy views and the confusion of faces, for a total the confusion of totals, for a total to
avoid (craps) its probability against the hand's noise (:data:`AVOID_NOISES`). Writes into
RUN_DIR: ``report.md``, ``evaluation.json``, ``learning.png``, ``outcomes.png``, those views'
figures (``turn.png``, ``strategy.png``, ``confusion.png``), ``robustness.png`` and a few
``throw_*.gif`` (failures first).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.baselines import RandomThrower, Thrower, decode, task_rule
from agents.config import Config, field_docs
from agents.episodes import Batch, PolicyThrower, make_eval_task, throw_impacts
from agents.kept import write_json
from agents.oracle import CEM, score, score_noise, search, task_budget
from agents.progress import bar
from agents.report import headline_table, verdict, write_report
from dice_env.envs.throw_task import ThrowTask
from dice_env.intervals import Z95, wilson_bounds

ORACLE_SCORE_SAMPLES = 16  # fresh noise draws per oracle observation
ROBUSTNESS = {  # keyword: multiples of the trained value (1: as trained)
    "hand_noise": [0.0, 0.5, 1.0, 2.0, 4.0],
    "friction": [0.5, 1.0, 2.0],
    "damping": [0.5, 1.0, 2.0],
    "stiffness": [0.3, 1.0, 3.0],
}
# How far the target face must turn: its angle from the table normal in the hand (degrees).
TURN_CLASSES = {"already up": (0.0, 45.0), "on a side": (45.0, 135.0), "down": (135.0, 180.0)}
# The hand and orientation noise at which a total to avoid (craps' seven) is counted.
AVOID_NOISES = (0.001, 0.003, 0.01, 0.03, 0.1)


def clustered(success: np.ndarray) -> tuple[float, float]:
    """95% interval of the success rate of (n, k) throws: k throws of each of n observations.

    Wilson's interval on the pooled throws, with their number divided by the design effect
    (the variance of the observations' rates over the binomial variance, at least 1): throws of
    one observation are not independent. It does not collapse when every throw scores the
    same (all 1024 of 64 × 16 successes: [0.996, 1.000]); with one observation the k throws
    count as one.
    """
    success = np.asarray(success, dtype=np.float64)
    n, k = success.shape
    p = float(success.mean())
    binomial = p * (1 - p) / (n * k)
    if n < 2:
        effect = float(k)
    elif binomial > 0:
        effect = max(1.0, float(np.var(success.mean(axis=1), ddof=1)) / n / binomial)
    else:
        effect = 1.0
    size = n * k / effect
    return wilson_bounds(p * size, size)


def rate(success: np.ndarray) -> dict[str, Any]:
    """Success rate, its 95% interval and the throws of ``success`` (n,) or (n, k).

    With (n, k) (k throws per observation) the interval is :func:`clustered`, else Wilson's.
    """
    s = np.asarray(success)
    ci = clustered(s) if s.ndim == 2 else wilson_bounds(int(s.sum()), s.size)
    return {"rate": float(s.mean()), "ci": ci, "n": int(s.size)}


def summary(success: np.ndarray, targets: np.ndarray,
            faces: int | Sequence[int]) -> dict[str, Any]:
    """:func:`rate` overall and per target (with (n, k), also the observations).

    ``faces``: the target values to split by (an int n: 1 … n; :func:`target_values`).
    """
    def one(s: np.ndarray) -> dict[str, Any]:
        return {**rate(s), **({"observations": len(s)} if s.ndim == 2 else {})}

    values = range(1, faces + 1) if isinstance(faces, int) else faces
    return {**one(success), "per_target": {
        f: one(success[targets == f]) for f in values if np.any(targets == f)}}


def target_values(task: ThrowTask) -> list[int]:
    """The targets a summary splits by: one die's faces, the totals of "sum" and "avoid_sum".

    None for the faces of several dice (one per combination would be too many).
    """
    if task.n_dice == 1:
        return list(range(1, task.n_faces + 1))
    return list(task.totals) if task.target != "faces" else []


def paired_difference(a: np.ndarray, b: np.ndarray) -> dict[str, Any]:
    """Mean of ``a - b`` over the same throws (n,) or (n, k), with its 95% normal interval.

    Rows are the independent units (throws, or observations with k throws each).
    """
    d = np.asarray(a, np.float64) - np.asarray(b, np.float64)
    rows = d.reshape(len(d), -1).mean(axis=1)
    mean = float(rows.mean())
    half = Z95 * float(rows.std(ddof=1)) / math.sqrt(len(rows)) if len(rows) > 1 else 1.0
    return {"diff": mean, "ci": (mean - half, mean + half),
            "same": bool(np.all(d == 0))}


def compare(
    task: ThrowTask, throwers: dict[str, Thrower], throws: int, oracle_observations: int,
    seed: int, cem: CEM | None = None, episode: dict[str, Any] | None = None,
    progress: bool = False, log: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Every thrower on the same ``throws`` episodes, and with the oracle on its observations.

    Returns per thrower its summary and raw throws; with ``oracle_observations`` > 0 the oracle's
    actions and ``common``: every thrower and the oracle scored on the same throws (the oracle's
    observations × ``ORACLE_SCORE_SAMPLES`` fresh noise draws), their summaries and successes.
    """
    cem = CEM() if cem is None else cem
    rng = np.random.default_rng(seed)
    batch = Batch.sample(task, throws, rng, **(episode or {}))
    faces = target_values(task)
    out: dict[str, Any] = {"throws": {}, "summary": {}, "batch": batch}
    with bar(throws * len(throwers), "evaluation", "throw", progress) as b:
        for name, thrower in throwers.items():
            out["throws"][name] = batch.throw(task, thrower, b.update)
            out["summary"][name] = summary(out["throws"][name]["is_success"], batch.targets,
                                           faces)
    if oracle_observations > 0:
        m = min(oracle_observations, throws)
        obs, targets = batch.observations[:m], batch.targets[:m]
        starts = {name: out["throws"][name]["action"][:m] for name in throwers}
        log(f"oracle: searching {m} observations, about "
            f"{cem.throws_per_observation(len(starts) + 1)} throws each")
        start = time.perf_counter()
        with bar(m, "oracle search", "obs", progress) as b:
            actions = search(task, obs, rng, cem, starts=starts, progress=b.update)
        out["oracle_seconds"] = time.perf_counter() - start
        noise = score_noise(task, rng, m, ORACLE_SCORE_SAMPLES)
        success = {name: score(task, obs, a, noise)
                   for name, a in {**starts, "oracle": actions}.items()}
        out["common"] = {name: summary(s, targets, faces) for name, s in success.items()}
        out["common_success"] = success
        out["oracle_actions"] = actions
    return out


def robustness(
    config: Config, throwers: dict[str, Thrower], throws: int, seed: int, progress: bool = False,
) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """Success of each thrower when one keyword (noise, table) departs from the trained value."""
    sweeps: dict[str, dict[str, list[dict[str, Any]]]] = {}
    if throws < 1:
        return sweeps
    trained = trained_values(make_eval_task(config)[0])
    settings = sum(len(f) for f in ROBUSTNESS.values())
    with bar(settings * len(throwers) * throws, "robustness", "throw", progress) as b:
        for key, factors in ROBUSTNESS.items():
            sweeps[key] = {name: [] for name in throwers}
            for value in (factor * trained[key] for factor in factors):
                task, episode = make_eval_task(config, **{key: value})
                batch = Batch.sample(task, throws, np.random.default_rng(seed), **episode)
                for name, thrower in throwers.items():
                    s = batch.throw(task, thrower)["is_success"]
                    b.update(throws)
                    sweeps[key][name].append({"value": value, "rate": float(s.mean()),
                                              "ci": wilson_bounds(int(s.sum()), s.size)})
    return sweeps


def trained_values(task: ThrowTask) -> dict[str, float]:
    """The task's value of each keyword swept in :data:`ROBUSTNESS`."""
    ground = task.scene.ground
    return {"hand_noise": task.hand_noise, "friction": ground.friction,
            "damping": ground.damping, "stiffness": ground.stiffness}


def tilt(observations: np.ndarray, task: ThrowTask) -> tuple[np.ndarray, np.ndarray]:
    """The target's angle from the table normal in the hand (rad) and its direction (n, 3).

    The direction is the target's reading direction (:attr:`dice_env.Die.reading`) in the world.
    """
    targets, hands = decode(observations)
    up = np.asarray(task.scene.ground.normal)
    normal = np.einsum("nij,nj->ni", hands, task.scene.die.reading[targets - 1])
    return np.arccos(np.clip(normal @ up, -1, 1)), normal


def turn_class(angle: np.ndarray) -> np.ndarray:
    """Index into :data:`TURN_CLASSES` of each angle (rad)."""
    edges = [high for _, high in list(TURN_CLASSES.values())[:-1]]
    return np.digitize(np.degrees(angle), edges)


def by_turn(success: np.ndarray, angle: np.ndarray) -> dict[str, dict[str, Any]]:
    """Success per class of :data:`TURN_CLASSES`; ``success`` (n,) or (n, k) per observation."""
    classes = turn_class(angle)
    return {name: rate(success[classes == i]) for i, name in enumerate(TURN_CLASSES)
            if np.any(classes == i)}


def strategy(batch: Batch, actions: np.ndarray, task: ThrowTask) -> dict[str, np.ndarray]:
    """What a thrower does against how far the target must turn (its intended release).

    Per throw: ``tilt`` (rad) of the target from up in the hand; ``vz`` the vertical toss
    (m/s); ``push`` the horizontal speed along the roll direction (m/s; the direction the die
    rolls when it turns the target up, ``(n_target × up) × up``); ``spin`` (rad/s);
    ``axis_cosine`` between the spin axis and ``n_target × up`` (1: the spin turns the target
    straight up).
    """
    angle, normal = tilt(batch.observations, task)
    up = np.asarray(task.scene.ground.normal)
    velocity = actions[:, :3] * task.max_speed
    spin = actions[:, 3:] * task.max_spin
    turn_axis = np.cross(normal, up)
    roll = np.cross(turn_axis, up)
    roll_norm = np.linalg.norm(roll, axis=1)
    push = np.where(roll_norm > 1e-6,
                    np.einsum("ni,ni->n", velocity, roll) / np.maximum(roll_norm, 1e-12), np.nan)
    spin_norm = np.linalg.norm(spin, axis=1)
    cos = np.einsum("ni,ni->n", spin, turn_axis) / np.maximum(
        spin_norm * np.linalg.norm(turn_axis, axis=1), 1e-12)
    return {"tilt": angle, "vz": velocity @ up, "push": push, "spin": spin_norm,
            "axis_cosine": cos}


def strategy_table(s: dict[str, np.ndarray]) -> dict[str, dict[str, float]]:
    """Medians of :func:`strategy`'s quantities per class of :data:`TURN_CLASSES`."""
    classes = turn_class(s["tilt"])
    return {name: {key: float(np.nanmedian(s[key][classes == i])) if np.any(classes == i)
                   and not np.all(np.isnan(s[key][classes == i])) else float("nan")
                   for key in ("vz", "push", "spin", "axis_cosine")}
            for i, name in enumerate(TURN_CLASSES)}


def release(actions: np.ndarray, task: ThrowTask) -> dict[str, float]:
    """Medians of the intended release: speed, vertical speed, horizontal speed, spin."""
    velocity = actions[:, :3] * task.max_speed
    spin = actions[:, 3:6] * task.max_spin
    return {"speed": float(np.median(np.linalg.norm(velocity, axis=1))),
            "vz": float(np.median(velocity[:, 2])),
            "horizontal": float(np.median(np.linalg.norm(velocity[:, :2], axis=1))),
            "spin": float(np.median(np.linalg.norm(spin, axis=1)))}


def total_hits(task: ThrowTask, batch: Batch, thrower: Thrower) -> dict[str, Any]:
    """How often the dice's total is the batch's target total, among the throws counted.

    ``counted``: throws not void; ``hits``: of them, those whose total is the target; ``p`` and
    its Wilson 95 % ``ci``.
    """
    info = batch.throw(task, thrower)
    counted = np.asarray(info["void_reason"]) == ""
    hits = int(np.sum((np.asarray(info["total"]) == batch.targets) & counted))
    n = int(counted.sum())
    return {"counted": n, "hits": hits, "p": hits / n if n else float("nan"),
            "ci": wilson_bounds(hits, n)}


def avoided_total(
    config: Config, throwers: dict[str, Thrower], throws: int, seed: int,
    noises: Sequence[float] = AVOID_NOISES,
) -> dict[str, Any]:
    """P(the total to avoid) of each thrower at each hand and orientation noise in ``noises``.

    Every thrower on the same ``throws`` episodes per noise (:func:`total_hits`); under
    ``throwers``, per thrower its rows and the largest noise whose interval is still wholly
    below the fair dice's probability (``fair``).
    """
    task, episode = make_eval_task(config)
    fair = float(fair_totals(task)[int(episode["target_sum"]) - task.n_dice])
    out: dict[str, Any] = {"noises": list(noises), "throws": throws, "fair": fair,
                           "total": int(episode["target_sum"])}
    rows: dict[str, list[dict[str, Any]]] = {name: [] for name in throwers}
    for noise in noises:
        noisy, _ = make_eval_task(config, hand_noise=noise, orientation_noise=noise)
        batch = Batch.sample(noisy, throws, np.random.default_rng(seed), **episode)
        for name, thrower in throwers.items():
            rows[name].append({"noise": noise, **total_hits(noisy, batch, thrower)})
    out["throwers"] = {
        name: {"rows": per, "largest_noise_below": max(
            (r["noise"] for r in per if r["ci"][1] < fair), default=None)}
        for name, per in rows.items()}
    return out


def fair_totals(task: ThrowTask) -> np.ndarray:
    """The probabilities of the totals N … (the sum of the faces) with fair dice."""
    totals = np.ones(1)
    for faces in task.faces:
        totals = np.convolve(totals, np.full(faces, 1.0 / faces))
    return totals


def learning_curve(run: Path) -> dict[str, Any]:
    """Evaluation success against throws during training (``eval/evaluations.npz``).

    ``start``: the policy before PPO's first update (``eval/start.json``: after the warm start,
    or the initial policy), plotted at 0 throws.
    """
    curve: dict[str, Any] = {"timesteps": [], "success": [], "start": None}
    path = run / "eval" / "evaluations.npz"
    if path.exists():
        with np.load(path) as data:
            rates = data["successes"] if "successes" in data else data["results"]
            curve["timesteps"] = data["timesteps"].tolist()
            curve["success"] = np.asarray(rates, np.float64).mean(axis=1).tolist()
    start = run / "eval" / "start.json"
    if start.exists():
        curve["start"] = json.loads(start.read_text())
    return curve


def evaluate_run(
    run: Path, log: Callable[[str], None] = print, progress: bool = False,
    **overrides: int | None,
) -> dict[str, Any]:
    """Evaluate the run's model against the baselines and the oracle; write report.md.

    ``overrides``: the config's ``eval_throws``, ``oracle_observations``,
    ``robustness_throws``, ``gifs`` (None keeps the run's value).
    """
    from stable_baselines3 import PPO

    from agents import plots
    from agents.replay import save_throws

    run = Path(run)
    config = Config.load(run / "config.json")
    for key, value in overrides.items():
        if value is not None:
            setattr(config, key, value)
    throws, oracle_observations = config.eval_throws, config.oracle_observations
    task, episode = make_eval_task(config)
    model = PPO.load(run / "model.zip", device="cpu")
    rule = task_rule(task)
    throwers: dict[str, Thrower] = {"PPO": PolicyThrower(model)}
    if rule is not None:
        throwers[rule[0]] = rule[1]
    else:
        log(f"{task.n_dice} dice, target {task.target!r}: no rule to compare with")
    throwers["random"] = RandomThrower(config.seed, model.action_space.shape[0])
    seed = config.seed + 2 * 10**6
    start = time.perf_counter()
    log(f"evaluating {run}: {throws} throws per thrower")
    cem = task_budget(task)[1]
    result = compare(task, throwers, throws, oracle_observations, seed, cem, episode, progress,
                     log)
    raw = result["throws"]
    differences: dict[str, Any] = {}
    if rule is not None:
        differences[rule[0]] = {
            **paired_difference(raw["PPO"]["is_success"], raw[rule[0]]["is_success"]),
            "where": f"the same {throws} throws"}
    above_oracle = []
    if "common" in result:
        common = result["common_success"]
        differences["oracle"] = {**paired_difference(common["PPO"], common["oracle"]),
                                 "where": f"the oracle's {len(common['oracle'])} observations × "
                                          f"{ORACLE_SCORE_SAMPLES} throws"}
        above_oracle = [n for n in throwers if common[n].mean() > common["oracle"].mean()]
    views, figures = task_views(run, task, result)
    if task.target == "avoid_sum" and config.robustness_throws:
        log(f"P({episode['target_sum']}) against the hand's noise")
        views["avoided"] = avoided_total(
            config, {n: t for n, t in throwers.items() if n != "random"},
            config.robustness_throws, seed + 2)
    if config.robustness_throws:
        log("robustness sweeps")
    sweeps = robustness(config, throwers, config.robustness_throws, seed + 1, progress)
    curve = learning_curve(run)
    levels = {n: s["rate"] for n, s in result["summary"].items() if n != "PPO"}
    if "common" in result:
        levels["oracle"] = result["common"]["oracle"]["rate"]
    figures["learning"] = plots.learning(run / "learning.png", {"PPO": [curve]}, levels)
    figures["outcomes"] = plots.outcomes(run / "outcomes.png", raw)
    if sweeps:
        figures["robustness"] = plots.robustness(run / "robustness.png", sweeps,
                                                 trained_values(task))
    if config.gifs:
        log("saving throws as GIFs")
    gifs = save_throws(run, task, result["batch"], raw["PPO"], "PPO", config.gifs)
    evaluation = {
        "throws": throws, "oracle_observations": oracle_observations,
        "oracle_score_samples": ORACLE_SCORE_SAMPLES, "cem": cem.__dict__,
        "rule": None if rule is None else rule[0],
        "summary": result["summary"], "common": result.get("common", {}),
        "differences": differences, "above_oracle": above_oracle,
        "oracle_seconds": result.get("oracle_seconds"), **views,
        "learning": curve,
        "outcomes": {n: {"impacts_median": float(np.median(throw_impacts(r))),
                         "rest_time_median": float(np.median(r["rest_time"])),
                         "void": float(np.mean(r["void_reason"] != ""))}
                     for n, r in raw.items()},
        "robustness": sweeps,
        "gifs": [g.name for g in gifs],
        "seconds": time.perf_counter() - start,
    }
    write_json(run / "evaluation.json", evaluation, indent=2)
    write_report(run, config, evaluation, figures, gifs)
    log(f"wrote {run / 'report.md'}")
    log("\n".join(verdict(evaluation)))
    log(headline_table(evaluation.get("common") or evaluation["summary"]))
    return evaluation


def task_views(run: Path, task: ThrowTask,
               result: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Path]]:
    """The views that fit the task, from :func:`compare`'s ``result``, and their figures.

    Every task: ``release`` (medians of each thrower's intended release; the oracle's on its
    observations, beside the others' on the same ones). One die: ``turn`` (success by how far
    the target must turn) and ``strategy`` (:func:`strategy_table` of the throwers but random),
    with the confusion of faces. A total of several dice: the confusion of totals.
    """
    from agents import plots

    batch, raw = result["batch"], result["throws"]
    m = len(result.get("oracle_actions", ()))
    first = Batch(batch.targets[:m], batch.hands[:m], batch.observations[:m], batch.noise[:m])
    actions = {n: np.asarray(r["action"]) for n, r in raw.items()}
    views: dict[str, Any] = {"release": {n: release(a, task) for n, a in actions.items()}}
    if m:
        views["release_on_oracle_observations"] = {
            n: release(a[:m], task) for n, a in
            {**actions, "oracle": result["oracle_actions"]}.items()}
    figures: dict[str, Path] = {}
    shown = [n for n in raw if n != "random"]
    if task.n_dice == 1:
        angle = tilt(batch.observations, task)[0]
        views["turn"] = {name: by_turn(r["is_success"], angle) for name, r in raw.items()}
        strategies = {n: strategy(batch, actions[n], task) for n in shown}
        success = {n: raw[n]["is_success"] for n in shown}
        if m:
            views["turn"]["oracle"] = by_turn(result["common_success"]["oracle"], angle[:m])
            strategies["oracle"] = strategy(first, result["oracle_actions"], task)
            success["oracle"] = result["common_success"]["oracle"].mean(axis=1)
        views["strategy"] = {n: strategy_table(s) for n, s in strategies.items()}
        figures["turn"] = plots.by_turn(run / "turn.png", views["turn"])
        figures["strategy"] = plots.strategy(run / "strategy.png", strategies, success)
        figures["confusion"] = plots.confusion(
            run / "confusion.png", batch.targets, {n: raw[n]["face"] for n in shown},
            list(range(1, task.n_faces + 1)))
    elif task.target == "sum":
        figures["confusion"] = plots.confusion(
            run / "confusion.png", batch.targets, {n: raw[n]["total"] for n in raw},
            list(task.totals), "total")
    return views, figures


def main(argv: list[str] | None = None) -> None:
    """Command line: ``python -m agents.evaluate RUN_DIR``."""
    parser = argparse.ArgumentParser(prog="python -m agents.evaluate", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path, help="run folder (with config.json and model.zip)")
    docs = field_docs(Config)
    for key in ("eval_throws", "oracle_observations", "robustness_throws", "gifs"):
        parser.add_argument("--" + key.replace("_", "-"), type=int, default=None,
                            help=docs[key] + " (default: the run's)")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=True,
                        help="show progress bars")
    args = vars(parser.parse_args(argv))
    for key in ("eval_throws", "oracle_observations", "robustness_throws", "gifs"):
        low = 1 if key == "eval_throws" else 0
        if args[key] is not None and args[key] < low:
            parser.error(f"argument --{key.replace('_', '-')}: must be an integer >= {low}, "
                         f"got {args[key]}")
    if not (args["run"] / "model.zip").exists():
        parser.error(f"argument run: {args['run']} has no model.zip")
    evaluate_run(args.pop("run"), **args)


if __name__ == "__main__":
    main()

"""Evaluate a trained run against baselines and the oracle, explain its strategy, write a report.

    python -m agents.evaluate RUN_DIR [--throws 1000] [--oracle-observations 48]

All throwers face the same observations and the same hand noise (common random numbers). Writes
into RUN_DIR: ``report.md``, ``evaluation.json``, ``confusion.png``, ``strategy.png``,
``outcomes.png``, ``robustness.png`` and a few ``throw_*.gif``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agents.baselines import HandThrower, RandomThrower, Thrower, decode
from agents.config import Config, field_docs
from agents.oracle import CEM, score, search
from dice_env.die import FACE_NORMALS
from dice_env.envs.task import ThrowTask, make_task

Z95 = 1.959964  # two-sided 95% normal quantile
EPISODE_KEYWORDS = ("target_face", "orientation_mode")
ORACLE_SCORE_SAMPLES = 16  # fresh noise draws per oracle observation
ROBUSTNESS = {  # keyword: multiples of the trained value (1: as trained)
    "hand_noise": [0.0, 0.5, 1.0, 2.0, 4.0],
    "friction": [0.5, 1.0, 2.0],
    "damping": [0.5, 1.0, 2.0],
    "stiffness": [0.3, 1.0, 3.0],
}


class PolicyThrower:
    """A trained SB3 policy as a thrower (deterministic actions)."""

    def __init__(self, model: Any) -> None:
        self.model = model

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """The policy's mean action for each observation."""
        return self.model.predict(np.asarray(observations, np.float32), deterministic=True)[0]


@dataclass
class Batch:
    """``n`` episodes: targets (n,), hands (n, 3, 3), observations (n, 15), noise (n, 9)."""

    targets: np.ndarray
    hands: np.ndarray
    observations: np.ndarray
    noise: np.ndarray

    @classmethod
    def sample(cls, task: ThrowTask, n: int, rng: np.random.Generator,
               **episode: Any) -> Batch:
        """Draw ``n`` episodes as the env does (``target_face``, ``orientation_mode``)."""
        pairs = [task.sample_hand(rng, episode.get("target_face"),
                                  episode.get("orientation_mode", "uniform")) for _ in range(n)]
        targets = np.array([t for t, _ in pairs])
        hands = np.stack([h for _, h in pairs])
        return cls(targets, hands, task.observe(targets, hands), task.sample_noise(rng, n))

    def throw(self, task: ThrowTask, thrower: Thrower) -> dict[str, np.ndarray]:
        """The thrower's actions and the throws' info arrays."""
        actions = np.asarray(thrower(self.observations), np.float64)
        info = task.throw(actions, self.targets, self.hands, self.noise).info
        return {"action": actions, **info}


def wilson(successes: int, n: int) -> tuple[float, float]:
    """95% Wilson score interval of a binomial proportion."""
    if n == 0:
        return (0.0, 1.0)
    p = successes / n
    centre = (p + Z95**2 / (2 * n)) / (1 + Z95**2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + Z95**2 / (4 * n * n)) / (1 + Z95**2 / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def clustered(rates: np.ndarray) -> tuple[float, float]:
    """95% normal interval of a mean over independent observations' success rates."""
    if len(rates) < 2:
        return (0.0, 1.0)
    half = Z95 * float(np.std(rates, ddof=1)) / math.sqrt(len(rates))
    mean = float(np.mean(rates))
    return (max(0.0, mean - half), min(1.0, mean + half))


def summary(success: np.ndarray, targets: np.ndarray) -> dict[str, Any]:
    """Success rate with its interval, overall and per target. ``success`` (n,) or (n, k).

    With (n, k) (k throws per observation) the interval treats observations as the units.
    """
    def one(s: np.ndarray) -> dict[str, Any]:
        if s.ndim == 2:
            return {"rate": float(s.mean()), "ci": clustered(s.mean(axis=1)), "n": int(s.size),
                    "observations": len(s)}
        return {"rate": float(s.mean()), "ci": wilson(int(s.sum()), s.size), "n": int(s.size)}

    return {**one(success), "per_target": {
        int(f): one(success[targets == f]) for f in range(1, 7) if np.any(targets == f)}}


def make_eval_task(config: Config, **overrides: Any) -> tuple[ThrowTask, dict[str, Any]]:
    """The run's evaluation task (its ``--env`` keywords, no training shaping) and episode keys."""
    kwargs = {**config.env_kwargs(), **config.num_threads_kwargs(), **overrides}
    episode = {k: kwargs.pop(k) for k in EPISODE_KEYWORDS if k in kwargs}
    for key in ("render_mode", "render_width", "render_height"):
        kwargs.pop(key, None)
    return make_task(**kwargs), episode


def compare(
    task: ThrowTask, throwers: dict[str, Thrower], throws: int, oracle_observations: int,
    seed: int, cem: CEM | None = None, episode: dict[str, Any] | None = None,
    log: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Every thrower on the same ``throws`` episodes, plus the oracle on the first few.

    Returns per thrower its summary and raw throws, the oracle's summary, and a paired
    comparison of all throwers on the oracle's observations (same fresh-noise protocol).
    """
    cem = CEM() if cem is None else cem
    rng = np.random.default_rng(seed)
    batch = Batch.sample(task, throws, rng, **(episode or {}))
    out: dict[str, Any] = {"throws": {}, "summary": {}}
    for name, thrower in throwers.items():
        out["throws"][name] = batch.throw(task, thrower)
        out["summary"][name] = summary(out["throws"][name]["is_success"], batch.targets)
    if oracle_observations > 0:
        m = min(oracle_observations, throws)
        obs, targets = batch.observations[:m], batch.targets[:m]
        log(f"oracle: searching {m} observations × {cem.throws_per_observation} throws")
        start = time.perf_counter()
        actions = search(task, obs, rng, cem)
        paired = {"oracle": score(task, obs, actions, rng, ORACLE_SCORE_SAMPLES)}
        out["oracle_seconds"] = time.perf_counter() - start
        out["summary"]["oracle"] = summary(paired["oracle"], targets)
        for name, thrower in throwers.items():
            paired[name] = score(task, obs, np.asarray(thrower(obs), np.float64), rng,
                                 ORACLE_SCORE_SAMPLES)
        out["paired"] = {name: summary(s, targets) for name, s in paired.items()}
        out["oracle_actions"] = actions
    out["batch"] = batch
    return out


def robustness(
    config: Config, throwers: dict[str, Thrower], throws: int, seed: int
) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """Success of each thrower when one keyword (noise, table) departs from the trained value."""
    sweeps: dict[str, dict[str, list[dict[str, Any]]]] = {}
    trained = trained_values(make_eval_task(config)[0])
    for key, factors in ROBUSTNESS.items():
        sweeps[key] = {name: [] for name in throwers}
        for value in (factor * trained[key] for factor in factors):
            task, episode = make_eval_task(config, **{key: value})
            batch = Batch.sample(task, throws, np.random.default_rng(seed), **episode)
            for name, thrower in throwers.items():
                s = batch.throw(task, thrower)["is_success"]
                sweeps[key][name].append({"value": value, "rate": float(s.mean()),
                                          "ci": wilson(int(s.sum()), s.size)})
    return sweeps


def trained_values(task: ThrowTask) -> dict[str, float]:
    """The task's value of each keyword swept in :data:`ROBUSTNESS`."""
    ground = task.scene.ground
    return {"hand_noise": task.hand_noise, "friction": ground.friction,
            "damping": ground.damping, "stiffness": ground.stiffness}


def strategy(batch: Batch, throws: dict[str, np.ndarray], task: ThrowTask) -> dict[str, Any]:
    """How a thrower uses the orientation: its spin against the geometric turn of the target.

    ``tilt``: angle (rad) between the target's normal and the table normal at release;
    ``axis_cosine``: cosine between the release spin axis and ``n_target x up`` (1: the spin
    turns the target straight up); ``spin_tilt_corr``: correlation of spin magnitude and tilt.
    """
    targets, hands = decode(batch.observations)
    up = np.asarray(task.scene.ground.normal)
    normal = np.einsum("nij,nj->ni", hands, FACE_NORMALS[targets - 1])
    tilt = np.arccos(np.clip(normal @ up, -1, 1))
    turn_axis = np.cross(normal, up)
    spin = throws["release_spin"]
    spin_norm = np.linalg.norm(spin, axis=1)
    cos = np.einsum("ni,ni->n", spin, turn_axis) / np.maximum(
        spin_norm * np.linalg.norm(turn_axis, axis=1), 1e-12)
    speed = np.linalg.norm(throws["release_velocity"], axis=1)
    return {"tilt": tilt, "axis_cosine": cos, "spin": spin_norm, "speed": speed,
            "vz": throws["release_velocity"] @ up,
            "spin_tilt_corr": float(np.corrcoef(spin_norm, tilt)[0, 1])
            if spin_norm.std() > 0 else 0.0}


def evaluate_run(
    run: Path, log: Callable[[str], None] = print, **overrides: int | None
) -> dict[str, Any]:
    """Evaluate the run's model against the baselines and the oracle; write report.md.

    ``overrides``: the config's ``eval_throws``, ``oracle_observations``,
    ``robustness_throws``, ``gifs`` (None keeps the run's value).
    """
    from stable_baselines3 import PPO

    from agents import plots

    run = Path(run)
    config = Config.load(run / "config.json")
    for key, value in overrides.items():
        if value is not None:
            setattr(config, key, value)
    throws, oracle_observations = config.eval_throws, config.oracle_observations
    task, episode = make_eval_task(config)
    model = PPO.load(run / "model.zip", device="cpu")
    throwers: dict[str, Thrower] = {"PPO": PolicyThrower(model),
                                    "random": RandomThrower(config.seed),
                                    "hand-written": HandThrower(task)}
    seed = config.seed + 2 * 10**6
    start = time.perf_counter()
    log(f"evaluating {run}: {throws} throws per thrower")
    result = compare(task, throwers, throws, oracle_observations, seed, episode=episode, log=log)
    batch, raw = result["batch"], result["throws"]
    strategies = {name: strategy(batch, raw[name], task) for name in ("PPO", "hand-written")}
    log("robustness sweeps")
    sweeps = robustness(config, throwers, config.robustness_throws, seed + 1)
    figures = {
        "confusion": plots.confusion(run / "confusion.png", batch.targets,
                                     {n: raw[n]["face"] for n in ("PPO", "hand-written")}),
        "strategy": plots.strategy(run / "strategy.png", batch.targets, strategies),
        "outcomes": plots.outcomes(run / "outcomes.png", raw),
        "robustness": plots.robustness(run / "robustness.png", sweeps, trained_values(task)),
    }
    log("saving throws as GIFs")
    gif_paths = plots.save_throws(run, config.env_id, config.env_kwargs(), batch,
                                  throwers["PPO"], config.gifs)
    evaluation = {
        "throws": throws, "oracle_observations": oracle_observations,
        "oracle_score_samples": ORACLE_SCORE_SAMPLES, "cem": CEM().__dict__,
        "summary": result["summary"], "paired": result.get("paired", {}),
        "oracle_seconds": result.get("oracle_seconds"),
        "strategy": {n: {"axis_cosine_mean": float(np.nanmean(s["axis_cosine"])),
                         "spin_tilt_corr": s["spin_tilt_corr"],
                         "speed_median": float(np.median(s["speed"])),
                         "spin_median": float(np.median(s["spin"])),
                         "vz_median": float(np.median(s["vz"]))}
                     for n, s in strategies.items()},
        "outcomes": {n: {"impacts_median": float(np.median(r["impacts"])),
                         "rest_time_median": float(np.median(r["rest_time"])),
                         "void": float(np.mean(r["void_reason"] != ""))}
                     for n, r in raw.items()},
        "robustness": sweeps,
        "seconds": time.perf_counter() - start,
    }
    (run / "evaluation.json").write_text(json.dumps(evaluation, indent=2) + "\n")
    from agents.report import write_report

    write_report(run, config, evaluation, figures, gif_paths)
    log(f"wrote {run / 'report.md'}")
    log(headline_table(evaluation))
    return evaluation


def fmt(s: dict[str, Any]) -> str:
    """``0.712 [0.684, 0.739]``."""
    return f"{s['rate']:.3f} [{s['ci'][0]:.3f}, {s['ci'][1]:.3f}]"


def headline_table(evaluation: dict[str, Any]) -> str:
    """The Markdown table of success per thrower, overall and per target."""
    lines = ["| thrower | throws | success [95% CI] | " + " | ".join(
        f"target {f}" for f in range(1, 7)) + " |", "|---|---|---|" + "---|" * 6]
    for name, s in evaluation["summary"].items():
        n = f"{s['n']}" + (f" ({s['observations']} obs)" if "observations" in s else "")
        per = " | ".join(f"{s['per_target'][f]['rate']:.2f}" if f in s["per_target"] else "–"
                         for f in range(1, 7))
        lines.append(f"| {name} | {n} | {fmt(s)} | {per} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    """Command line: ``python -m agents.evaluate RUN_DIR``."""
    parser = argparse.ArgumentParser(prog="python -m agents.evaluate", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path, help="run folder (with config.json and model.zip)")
    docs = field_docs(Config)
    for key in ("eval_throws", "oracle_observations", "robustness_throws", "gifs"):
        parser.add_argument("--" + key.replace("_", "-"), type=int, default=None,
                            help=docs[key] + " (default: the run's)")
    args = vars(parser.parse_args(argv))
    evaluate_run(args.pop("run"), **args)


if __name__ == "__main__":
    main()

"""The run's report.md: headline table, strategy, outcomes, robustness, figures."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from agents.config import Config


def training_summary(run: Path) -> tuple[int, float]:
    """Throws trained and wall-clock seconds, summed over the run's sessions (resumes)."""
    path = run / "training.jsonl"
    if not path.exists():
        return 0, 0.0
    sessions = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return (sessions[-1]["throws"] if sessions else 0,
            sum(s["seconds"] for s in sessions))


def write_report(run: Path, config: Config, evaluation: dict[str, Any],
                 figures: dict[str, Path], gifs: list[Path]) -> Path:
    """Write ``run/report.md`` from the evaluation and its figures."""
    from agents.evaluate import fmt, headline_table

    throws, seconds = training_summary(run)
    params = config.hyperparams()
    summary = evaluation["summary"]
    lines = [
        f"# {config.name}: PPO on {config.env_id}", "",
        f"Trained on {throws} throws in {seconds / 60:.1f} min (preset `{config.preset}`, seed "
        f"{config.seed}); env keywords `{config.env_kwargs() or 'defaults'}`, training-only "
        f"keywords `{params['train_env']}`. Evaluation: {evaluation['throws']} throws per "
        f"thrower, all throwers on the same observations and hand noise.", "",
        "## Success (target face up at rest)", "",
        headline_table(evaluation), "",
        "95% intervals: Wilson for independent throws. The oracle searched "
        f"{evaluation['oracle_observations']} observations (CEM from the hand-written thrower, "
        f"{evaluation['cem']['iterations']} rounds × {evaluation['cem']['population']} candidates"
        f" × {evaluation['cem']['noise_samples']} noise draws, finalists re-scored on fresh "
        "draws) and is scored on "
        f"{evaluation['oracle_score_samples']} further fresh draws per observation; its interval "
        "treats the observations as the units.",
    ]
    if "PPO" in summary and "oracle" in summary:
        paired = evaluation["paired"]
        ratio = paired["PPO"]["rate"] / max(paired["oracle"]["rate"], 1e-12)
        lines += ["", "On the oracle's observations, with the same protocol for everyone:", "",
                  "| thrower | success [95% CI] |", "|---|---|",
                  *[f"| {n} | {fmt(s)} |" for n, s in paired.items()], "",
                  f"PPO / oracle = **{ratio:.2f}** on these observations."]
    strat = evaluation["strategy"]
    lines += ["", "## Strategy", "", f"![strategy]({figures['strategy'].name})", "",
              "| thrower | median speed (m/s) | median vertical speed (m/s) | median spin (rad/s) |"
              " mean cos(spin axis, n_target × up) | corr(spin, tilt of target) |",
              "|---|---|---|---|---|---|",
              *[f"| {n} | {s['speed_median']:.3f} | {s['vz_median']:.3f} | "
                f"{s['spin_median']:.1f} | {s['axis_cosine_mean']:.2f} | "
                f"{s['spin_tilt_corr']:.2f} |" for n, s in strat.items()], "",
              "The hand-written thrower spins about `n_target × up` (cosine 1) at a rate "
              "proportional to the angle the target must turn. A cosine near 1 and a strong "
              "spin–tilt correlation for PPO mean it learned the same geometric rule from the "
              "orientation in its observation; a lower value means it found another way.", "",
              "## Outcomes", "", f"![confusion]({figures['confusion'].name})", "",
              f"![outcomes]({figures['outcomes'].name})", "",
              "| thrower | median impacts | median rest time (s) | void throws |",
              "|---|---|---|---|",
              *[f"| {n} | {o['impacts_median']:.0f} | {o['rest_time_median']:.2f} | "
                f"{o['void']:.3f} |" for n, o in evaluation["outcomes"].items()], "",
              "## Robustness (keywords not trained on)", "",
              f"![robustness]({figures['robustness'].name})", ""]
    for key, per in evaluation["robustness"].items():
        values = [p["value"] for p in next(iter(per.values()))]
        lines += [f"| {key} | " + " | ".join(f"{v:g}" for v in values) + " |",
                  "|---|" + "---|" * len(values),
                  *[f"| {n} | " + " | ".join(f"{p['rate']:.2f}" for p in pts) + " |"
                    for n, pts in per.items()], ""]
    if gifs:
        lines += ["## Throws", "", *[f"![throw]({g.name})" for g in gifs], ""]
    lines += [f"Evaluation took {evaluation['seconds']:.0f} s"
              + (f" (oracle {evaluation['oracle_seconds']:.0f} s)."
                 if evaluation.get("oracle_seconds") else "."),
              f"Reproduce: `python -m agents.evaluate {run}`.", ""]
    path = run / "report.md"
    path.write_text("\n".join(lines))
    return path

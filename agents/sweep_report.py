"""The report of a group of runs (``--seeds``, ``--sweep``): one table over settings and seeds."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from agents.config import Config
from agents.kept import write_json, write_text

THROWERS = ("PPO", "hand-written", "oracle", "random")


def _member_results(config: Config) -> list[tuple[dict[str, Any], Config, dict[str, Any]]]:
    """(setting, member config, evaluation) of every evaluated member, in the group's order."""
    from agents.evaluate import learning_curve

    settings = config.sweep_grid()
    out = []
    for i, member in enumerate(config.members()):
        run = Path(member.runs) / str(member.name)
        path = run / "evaluation.json"
        if path.exists():
            evaluation = json.loads(path.read_text())
            evaluation["learning"] = learning_curve(run)
            out.append((settings[i // config.seeds], member, evaluation))
    return out


def _rate(evaluation: dict[str, Any], name: str) -> float:
    """A thrower's success: the oracle's on its throws, the others' on the evaluation's."""
    table = evaluation["common"] if name == "oracle" else evaluation["summary"]
    return table[name]["rate"] if name in table else float("nan")


def _cell(rates: list[float]) -> str:
    """Mean ± standard deviation over seeds [min, max] (one seed: the rate)."""
    a = np.array(rates)
    if len(a) == 1:
        return f"{a[0]:.3f}"
    return f"{a.mean():.3f} ± {a.std(ddof=1):.3f} [{a.min():.3f}, {a.max():.3f}]"


def _label(setting: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in setting.items()) or "PPO"


def _title(config: Config) -> str:
    seeds = (f"{config.seeds} seeds ({config.seed}–{config.seed + config.seeds - 1})"
             if config.seeds > 1 else f"seed {config.seed}")
    if config.sweep:
        keys = " × ".join(item.partition("=")[0] for item in config.sweep)
        return f"Sweep over {keys} ({seeds} each)"
    return f"PPO over {seeds}"


def write_group_report(group: Path) -> Path:
    """Write ``group/report.md``, ``group/learning.png`` and ``group/summary.json``.

    Success per setting (mean and spread over seeds), the verdicts, every run's learning curve;
    the summary keeps each seed's rates, the config and the code version in a small JSON.
    """
    from agents import plots
    from dice_env.provenance import code_version

    config = Config.load(group / "config.json")
    results = _member_results(config)
    keys = [item.partition("=")[0] for item in config.sweep]
    by_setting: dict[str, tuple[dict[str, Any], list[dict[str, Any]]]] = {}
    for setting, _, evaluation in results:
        by_setting.setdefault(_label(setting), (setting, []))[1].append(evaluation)
    header = [*keys, *THROWERS, "PPO − rule", "PPO / oracle (its throws)"]
    lines = [f"# {config.name}: {_title(config)}", "",
             f"{len(results)} of {len(config.members())} runs evaluated (PPO on "
             f"{config.env_id}, preset `{config.preset}`, env keywords "
             f"`{config.env_kwargs() or 'defaults'}`). Success: PPO, hand-written and random on "
             f"{config.eval_throws} throws each, the oracle on its {config.oracle_observations} "
             "observations; mean ± standard deviation over seeds [min, max].", "",
             "## Headline", ""]
    rows, flags = [], []
    for label, (setting, evaluations) in by_setting.items():
        rates = {n: [_rate(e, n) for e in evaluations] for n in THROWERS}
        ppo, rule = np.mean(rates["PPO"]), np.mean(rates["hand-written"])
        # PPO against the oracle on the oracle's throws (the same throws for both).
        ppo_there = np.mean([e["common"]["PPO"]["rate"] if e["common"] else np.nan
                             for e in evaluations])
        oracle = np.mean(rates["oracle"])
        rows.append("| " + " | ".join([*(f"{v}" for v in setting.values()),
                                        *(_cell(rates[n]) for n in THROWERS),
                                        f"{ppo - rule:+.3f}", f"{ppo_there / oracle:.2f}"]) + " |")
        where = f" at {label}" if keys else ""
        if ppo < rule:
            flags.append(f"- **PPO is below the hand-written rule{where}**: {ppo:.3f} against "
                         f"{rule:.3f} (mean over seeds).")
        if ppo_there < oracle:
            flags.append(f"- **PPO is below the oracle{where}**: {ppo_there:.3f} against "
                         f"{oracle:.3f} on the oracle's throws.")
    lines += flags or ["- PPO is at or above the hand-written rule and the oracle everywhere."]
    lines += ["", f"## {_title(config)}", "", "| " + " | ".join(header) + " |",
              "|" + "---|" * len(header), *rows, "",
              "PPO − rule: on the same throws; PPO / oracle: PPO on the oracle's throws; means "
              "over seeds. Each run's report (its folder) "
              "gives intervals, the paired comparison on the same throws, the learning curve, "
              "success by turn and the strategy.", ""]
    curves: dict[str, list[dict[str, Any]]] = {}
    for setting, _, evaluation in results:
        curves.setdefault(_label(setting), []).append(evaluation["learning"])
    if curves:
        figure = plots.learning(group / "learning.png", curves, {})
        lines += ["## Learning curves (evaluation success against training throws, every run)",
                  "", f"![learning]({figure.name})", "",
                  "Thin lines: seeds; thick: their mean, the band their range; squares: before "
                  "PPO's first update.", ""]
    lines += ["Runs: " + ", ".join(f"[{m.name}]({m.name}/report.md)" for _, m, _ in results),
              ""]
    path = group / "report.md"
    write_text(path, "\n".join(lines))
    summary = {"config": json.loads((group / "config.json").read_text()),
               "commit": code_version(), "settings": [
                   {"setting": setting,
                    "rates": {n: [_rate(e, n) for e in evaluations] for n in THROWERS},
                    "ppo_on_oracle_throws": [e["common"]["PPO"]["rate"] for e in evaluations
                                             if e["common"]],
                    "evaluation_seconds": [e["seconds"] for e in evaluations]}
                   for setting, evaluations in by_setting.values()]}
    write_json(group / "summary.json", summary)
    return path

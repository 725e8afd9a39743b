"""The run's report.md: headline, success with the oracle, learning curve, task views, GIFs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from agents.config import Config
from agents.kept import read_sessions, write_text


def training_summary(run: Path) -> tuple[int, float]:
    """Throws trained and wall-clock seconds, summed over the run's sessions (resumes)."""
    sessions = read_sessions(run)
    return (sessions[-1]["throws"] if sessions else 0,
            sum(s["seconds"] for s in sessions))


def _rate(s: dict[str, Any] | None, digits: int = 2) -> str:
    """``0.71 [0.68, 0.74]`` (``digits`` decimals), ``–`` for no score."""
    if s is None:
        return "–"
    return f"{s['rate']:.{digits}f} [{s['ci'][0]:.{digits}f}, {s['ci'][1]:.{digits}f}]"


def headline_table(summaries: dict[str, dict[str, Any]]) -> str:
    """The Markdown table of success per thrower, overall and per target."""
    faces = sorted({f for s in summaries.values() for f in s["per_target"]})
    header = ["thrower", "throws", "success [95% CI]", *(f"target {f}" for f in faces)]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for name, s in summaries.items():
        n = f"{s['n']}" + (f" ({s['observations']} obs)" if "observations" in s else "")
        per = [f"{s['per_target'][f]['rate']:.2f}" if f in s["per_target"] else "–"
               for f in faces]
        lines.append("| " + " | ".join([name, n, _rate(s, 3), *per]) + " |")
    return "\n".join(lines)


def verdict(evaluation: dict[str, Any]) -> list[str]:
    """The report's headline: PPO against the rule and the oracle, on the same throws."""
    lines = []
    diffs = evaluation.get("differences", {})
    rule = evaluation.get("rule")
    for other, where in ((rule, f"the {rule} rule"), ("oracle", "the oracle")):
        d = diffs.get(other)
        if d is None:
            continue
        lo, hi = d["ci"]
        if d["same"]:
            word = f"PPO throws exactly as well as {where} on these throws"
        elif d["diff"] < 0:
            word = (f"**PPO is below {where}**" + (" (significantly)" if hi < 0
                                                    else " (within noise)"))
        elif d["diff"] > 0:
            word = f"PPO is above {where}" + (" (significantly)" if lo > 0 else " (within noise)")
        else:
            word = f"PPO is level with {where}"
        lines.append(f"- {word}: difference {d['diff']:+.3f} [{lo:+.3f}, {hi:+.3f}] "
                     f"on {d['where']}.")
    for name in evaluation.get("above_oracle", []):
        lines.append(f"- **The oracle is not a ceiling here: {name} scores above it** on the "
                     "oracle's throws.")
    return lines


def _rates_line(evaluation: dict[str, Any]) -> str:
    """Every thrower's success in one line."""
    summary, common = evaluation["summary"], evaluation.get("common")
    line = ", ".join(f"{n} {_rate(s)}" for n, s in summary.items())
    line = f"Success on {evaluation['throws']} throws each: {line}."
    if common:
        line += (f" On the oracle's throws: oracle {_rate(common['oracle'])}, PPO "
                 f"{_rate(common['PPO'])} (PPO / oracle = "
                 f"{common['PPO']['rate'] / max(common['oracle']['rate'], 1e-12):.2f}).")
    return line


def _section_success(evaluation: dict[str, Any]) -> list[str]:
    lines = []
    common = evaluation.get("common")
    if common:
        cem = evaluation["cem"]
        m, k = evaluation["oracle_observations"], evaluation["oracle_score_samples"]
        lines += [f"## Success on the same throws, with the oracle ({m} observations × {k} "
                  "throws each)", "", headline_table(common), "",
                  "Every thrower and the oracle are scored on the same throws (the same "
                  "observations and the same hand noise). The oracle searches each observation "
                  "under the env's own noise: it screens every other thrower's action ("
                  f"{', '.join(n for n in common if n != 'oracle')}) and "
                  f"{cem['global_candidates']} uniform actions, runs "
                  f"{cem['restarts']} cross-entropy searches ({cem['iterations']} rounds × "
                  f"{cem['population']} candidates × {cem['noise_samples']} noise draws) from "
                  "the best of them, and keeps the best finalist (every start included) on "
                  f"{cem['validation_samples']} fresh draws; its score here is on further fresh "
                  "draws. Intervals (95 %): Wilson on the pooled throws, their number divided "
                  "by the design effect of the observations (throws of one observation are not "
                  "independent).", ""]
    lines += [f"## Success on {evaluation['throws']} throws per thrower, by target", "",
              headline_table(evaluation["summary"]), "",
              "The same observations and hand noise for every thrower; 95 % Wilson intervals.",
              ""]
    return lines


def _section_learning(run: Path, evaluation: dict[str, Any], figure: Path) -> list[str]:
    curve = evaluation["learning"]
    lines = ["## Learning curve (evaluation success against training throws)", "",
             f"![learning]({figure.name})", ""]
    start = curve.get("start")
    if start:
        kind = (f"after the warm start (imitation of the {evaluation['rule']} throw)"
                if start.get("warm_start") else "the initial policy (PPO from scratch)")
        lines.append(f"Before PPO's first update, {kind}: {start['success']:.3f} on "
                     f"{start['episodes']} throws.")
    if curve["timesteps"]:
        best = max(range(len(curve["success"])), key=curve["success"].__getitem__)
        lines.append(f"{len(curve['timesteps'])} evaluations during training; last "
                     f"{curve['success'][-1]:.3f} at {curve['timesteps'][-1]} throws, best "
                     f"{curve['success'][best]:.3f} at {curve['timesteps'][best]}.")
    lines += ["", f"From `{run}/eval/evaluations.npz` (SB3's EvalCallback, deterministic policy,"
              " no shaping) and `eval/start.json`; TensorBoard: `tensorboard --logdir "
              f"{run}/tb`.", ""]
    return lines


def _section_turn(evaluation: dict[str, Any], figure: Path) -> list[str]:
    turn = evaluation["turn"]
    classes = list(next(iter(turn.values())))
    return ["## Success by how far the target face must turn (its angle from up in the hand: "
            + ", ".join(classes) + ")", "", f"![turn]({figure.name})", "",
            "| thrower | " + " | ".join(f"target {c}" for c in classes) + " |",
            "|---|" + "---|" * len(classes),
            *[f"| {n} | " + " | ".join(_rate(per.get(c)) for c in classes) + " |"
              for n, per in turn.items()], "",
            "Classes: already up (< 45°), on a side (45–135°), down (> 135°). The oracle's row "
            "is on its own observations.", ""]


def _section_strategy(evaluation: dict[str, Any], figure: Path) -> list[str]:
    lines = ["## Strategy: toss, sideways push and spin against the target's tilt (PPO, the "
             "hand-written rule and the oracle)", "", f"![strategy]({figure.name})", "",
             "| thrower | target | median toss v_z (m/s) | median push along the roll (m/s) | "
             "median spin (rad/s) | median cos(spin axis, n_target × up) |",
             "|---|---|---|---|---|---|"]
    for name, per in evaluation["strategy"].items():
        lines += [f"| {name} | {c} | {v['vz']:.3f} | {v['push']:.3f} | {v['spin']:.1f} | "
                  f"{v['axis_cosine']:.2f} |" for c, v in per.items()]
    lines += ["", "The intended release (before hand noise) against the target face's angle "
              "from up in the hand (the oracle's on its own observations). The hand-written "
              "rule spins about `n_target × up` "
              "(cosine 1) at a rate proportional to that angle, with no toss and no push. "
              "A learned policy that tosses upward more, or pushes along the roll direction "
              "(`(n_target × up) × up`, where the die rolls as it turns the target up), the "
              "further the target must turn has found more than the rule.", ""]
    return lines


def _section_release(evaluation: dict[str, Any]) -> list[str]:
    """Each thrower's intended release; with the oracle, on its observations."""
    kinds = [("release", f"the {evaluation['throws']} throws")]
    if "release_on_oracle_observations" in evaluation:
        kinds.append(("release_on_oracle_observations", "the oracle's observations"))
    lines = ["## Release: what each thrower does (medians of the intended release, before hand "
             "noise)", "",
             "| thrower | on | speed (m/s) | vertical (m/s) | horizontal (m/s) | spin (rad/s) |",
             "|---|---|---|---|---|---|"]
    for key, where in kinds:
        lines += [f"| {name} | {where} | {r['speed']:.3f} | {r['vz']:.3f} | "
                  f"{r['horizontal']:.3f} | {r['spin']:.1f} |"
                  for name, r in evaluation[key].items()]
    return [*lines, ""]


def _section_avoided(avoided: dict[str, Any]) -> list[str]:
    """P(the total to avoid) against the hand's noise, per thrower."""
    total, fair = avoided["total"], avoided["fair"]
    names = list(avoided["throwers"])
    lines = [f"## P({total}) against the hand's noise (hand and orientation noise, "
             f"{avoided['throws']} throws each; fair dice {fair:.3f})", "",
             "| noise | " + " | ".join(f"{n} P({total}) [95% CI]" for n in names) + " |",
             "|---|" + "---|" * len(names)]
    for i, noise in enumerate(avoided["noises"]):
        cells = []
        for name in names:
            r = avoided["throwers"][name]["rows"][i]
            cells.append(f"{r['p']:.3f} [{r['ci'][0]:.3f}, {r['ci'][1]:.3f}] ({r['counted']})")
        lines.append(f"| {noise:g} | " + " | ".join(cells) + " |")
    largest = {n: avoided["throwers"][n]["largest_noise_below"] for n in names}
    lines += ["", "In brackets the throws counted (not void). The largest noise at which P("
              f"{total})'s interval is still wholly below fair dice's: "
              + ", ".join(f"{n} {'none' if x is None else f'{x:g}'}" for n, x in largest.items())
              + ".", ""]
    return lines


def write_report(run: Path, config: Config, evaluation: dict[str, Any],
                 figures: dict[str, Path], gifs: list[Path]) -> Path:
    """Write ``run/report.md`` from the evaluation and its figures."""
    throws, seconds = training_summary(run)
    params = config.hyperparams()
    start = evaluation["learning"].get("start") or {}
    warm = (f"warm-started by imitating the {evaluation['rule']} throw"
            if start.get("warm_start") else "from scratch")
    lines = [
        f"# {config.name}: PPO on {config.env_id}", "",
        f"Trained on {throws} throws in {seconds / 60:.1f} min ({warm}; preset "
        f"`{config.preset}`, seed {config.seed}); env keywords "
        f"`{config.env_kwargs() or 'defaults'}`, training-only keywords `{params['env_kwargs']}`.",
        "", "## Headline", "", _rates_line(evaluation), "", *verdict(evaluation), "",
        *_section_success(evaluation),
        *_section_learning(run, evaluation, figures["learning"]),
        *(_section_turn(evaluation, figures["turn"]) if "turn" in figures else []),
        *(_section_strategy(evaluation, figures["strategy"]) if "strategy" in figures else []),
        *_section_release(evaluation),
        *(_section_avoided(evaluation["avoided"]) if "avoided" in evaluation else []),
        "## Outcomes", "",
        *([f"![confusion]({figures['confusion'].name})", "",
           "P(landed | target) on the throws above, one panel per thrower.", ""]
          if "confusion" in figures else []),
        f"![outcomes]({figures['outcomes'].name})", "",
        "| thrower | median impacts | median rest time (s) | void throws |", "|---|---|---|---|",
        *[f"| {n} | {o['impacts_median']:.0f} | {o['rest_time_median']:.2f} | {o['void']:.3f} |"
          for n, o in evaluation["outcomes"].items()], "",
    ]
    if evaluation["robustness"]:
        lines += ["## Robustness: success when one keyword departs from the trained value ("
                  + ", ".join(evaluation["robustness"]) + ")", "",
                  f"![robustness]({figures['robustness'].name})", ""]
        for key, per in evaluation["robustness"].items():
            values = [p["value"] for p in next(iter(per.values()))]
            lines += [f"| {key} | " + " | ".join(f"{v:g}" for v in values) + " |",
                      "|---|" + "---|" * len(values),
                      *[f"| {n} | " + " | ".join(f"{p['rate']:.2f}" for p in pts) + " |"
                        for n, pts in per.items()], ""]
    if gifs:
        lines += ["## Throws (failures first)", "",
                  *[f"![{g.stem}]({g.name}) `{g.stem}`" for g in gifs], "",
                  f"More: `python -m agents.replay {run}` (fresh throws with the saved model, "
                  "GIFs in `replay/`).", ""]
    lines += [f"Evaluation took {evaluation['seconds']:.0f} s"
              + (f" (oracle {evaluation['oracle_seconds']:.0f} s)."
                 if evaluation.get("oracle_seconds") else "."),
              f"Reproduce: `python -m agents.evaluate {run}`.", ""]
    path = run / "report.md"
    write_text(path, "\n".join(lines))
    return path

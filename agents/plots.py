"""Figures of the evaluation: learning curves, success by turn, strategy, outcomes, robustness."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from agents.episodes import throw_impacts
from agents.kept import write_saved

COLOURS = {"PPO": "tab:blue", "hand-written": "tab:orange", "set": "tab:orange",
           "random": "tab:gray", "oracle": "tab:green"}
TILT_BINS = np.linspace(0.0, 180.0, 13)  # degrees, 15° wide


def save(fig: Any, path: Path) -> Path:
    """Lay out ``fig``, write it as a PNG at ``path`` (creating the folder), close it."""
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    write_saved(path, lambda f: fig.savefig(f, format="png", dpi=110))
    plt.close(fig)
    return path


def learning(path: Path, curves: dict[str, list[dict[str, Any]]],
             levels: dict[str, float]) -> Path:
    """Evaluation success against training throws; each label's runs (seeds) and their mean.

    The point at 0 throws is the policy before PPO's first update (after the warm start when
    there is one); ``levels`` (the other throwers' final success) are drawn as lines.
    """
    fig, ax = plt.subplots(figsize=(7, 4))
    palette = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (label, runs) in enumerate(curves.items()):
        colour = COLOURS.get(label, palette[k % len(palette)])
        series = []
        for curve in runs:
            x, y = list(curve["timesteps"]), list(curve["success"])
            if curve.get("start"):
                x, y = [0, *x], [curve["start"]["success"], *y]
            series.append((np.array(x), np.array(y)))
            ax.plot(x, y, color=colour, lw=1.6 if len(runs) == 1 else 0.7,
                    alpha=1.0 if len(runs) == 1 else 0.45, marker="." if len(runs) == 1 else "",
                    label=label if len(runs) == 1 else None)
            if curve.get("start"):
                ax.plot([0], [curve["start"]["success"]], marker="s", ms=6, color=colour,
                        mfc="white")
        if len(runs) > 1:
            n = min(len(x) for x, _ in series)
            ys = np.stack([y[:n] for _, y in series])
            ax.plot(series[0][0][:n], ys.mean(axis=0), color=colour, lw=2,
                    label=f"{label} (mean of {len(runs)})")
            ax.fill_between(series[0][0][:n], ys.min(axis=0), ys.max(axis=0), color=colour,
                            alpha=0.15)
    for name, rate in levels.items():
        ax.axhline(rate, color=COLOURS.get(name, "k"), ls="--", lw=1,
                   label=f"{name} (final evaluation)")
    warm = any(c.get("start", {}) and c["start"].get("warm_start")
               for runs in curves.values() for c in runs)
    ax.set(xlabel="training throws", ylabel="evaluation success", ylim=(0, 1.02),
           title="learning curve (square: before PPO's first update"
                 + (", after the warm start)" if warm else ")"))
    ax.legend(fontsize=8, loc="lower right")
    return save(fig, path)


def by_turn(path: Path, turn: dict[str, dict[str, dict[str, Any]]]) -> Path:
    """Success per thrower against how far the target face must turn, with 95% intervals."""
    fig, ax = plt.subplots(figsize=(7, 3.6))
    classes = list(next(iter(turn.values())))
    width = 0.8 / len(turn)
    for k, (name, per) in enumerate(turn.items()):
        x = np.arange(len(classes)) + (k - (len(turn) - 1) / 2) * width
        rates = np.array([per[c]["rate"] if c in per else np.nan for c in classes])
        lo = rates - np.array([per[c]["ci"][0] if c in per else np.nan for c in classes])
        hi = np.array([per[c]["ci"][1] if c in per else np.nan for c in classes]) - rates
        ax.bar(x, rates, width * 0.9, yerr=np.maximum(0.0, [lo, hi]), capsize=2,
               color=COLOURS.get(name), label=name, alpha=0.8)
    ax.set(xticks=range(len(classes)), xticklabels=[f"target {c}" for c in classes],
           ylabel="success", ylim=(0, 1.05), title="success by how far the target face must turn")
    ax.legend(fontsize=8, ncol=len(turn))
    return save(fig, path)


def _binned(ax: Any, angle: np.ndarray, values: np.ndarray, colour: str, label: str) -> None:
    """Median and quartiles of ``values`` in bins of the target's tilt (degrees)."""
    centres, med, q1, q3 = [], [], [], []
    for lo, hi in itertools.pairwise(TILT_BINS):
        v = values[(angle >= lo) & (angle < hi)]
        v = v[np.isfinite(v)]
        if len(v) >= 3:
            centres.append((lo + hi) / 2)
            med.append(np.median(v))
            q1.append(np.percentile(v, 25))
            q3.append(np.percentile(v, 75))
    ax.plot(centres, med, marker="o", ms=3, color=colour, label=label)
    ax.fill_between(centres, q1, q3, color=colour, alpha=0.2)


def strategy(path: Path, strategies: dict[str, dict[str, np.ndarray]],
             success: dict[str, np.ndarray]) -> Path:
    """What each thrower does against the target's tilt from up: toss, push, spin, success."""
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.2), sharex=True)
    panels = (("vz", "vertical toss (m/s)", "toss upward against how far the target turns"),
              ("push", "push along the roll (m/s)",
               "sideways push along the roll direction"),
              ("spin", "spin (rad/s)", "spin against how far the target turns"))
    for name, s in strategies.items():
        angle = np.degrees(s["tilt"])
        colour = COLOURS.get(name, "tab:purple")
        for ax, (key, label, title) in zip(axes.flat, panels, strict=False):
            _binned(ax, angle, s[key], colour, name)
            ax.set(ylabel=label, title=title)
        idx = np.digitize(angle, TILT_BINS[1:-1])
        rates = [success[name][idx == i].mean() if np.any(idx == i) else np.nan
                 for i in range(len(TILT_BINS) - 1)]
        axes[1, 1].plot((TILT_BINS[:-1] + TILT_BINS[1:]) / 2, rates, marker="o", ms=3,
                        color=colour, label=name)
    axes[1, 1].set(ylabel="success", ylim=(0, 1.05), title="success against the target's tilt")
    for ax in axes[1]:
        ax.set_xlabel("target face's angle from up in the hand (deg)")
    for ax in axes.flat:
        ax.axvline(45, color="k", lw=0.5, ls=":")
        ax.axvline(135, color="k", lw=0.5, ls=":")
    axes[0, 0].legend(fontsize=8)
    return save(fig, path)


def confusion(path: Path, targets: np.ndarray, landed: dict[str, np.ndarray],
              labels: Sequence[int], what: str = "face") -> Path:
    """Heatmaps of P(landed | target), one per thrower; ``labels``: the faces or totals."""
    fig, axes = plt.subplots(1, len(landed), figsize=(4.2 * len(landed), 3.8), squeeze=False)
    size = len(labels)
    for ax, (name, values) in zip(axes[0], landed.items(), strict=True):
        counts = np.array([[np.sum((targets == t) & (values == v)) for v in labels]
                           for t in labels], dtype=np.float64)
        rates = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)
        ax.imshow(rates, vmin=0, vmax=1, cmap="viridis")
        if size <= 12:  # a d20's 400 cells would be unreadable
            for i in range(size):
                for j in range(size):
                    ax.text(j, i, f"{rates[i, j]:.2f}", ha="center", va="center", fontsize=7,
                            color="white" if rates[i, j] < 0.5 else "black")
        ax.set(xticks=range(size), xticklabels=labels, yticks=range(size), yticklabels=labels,
               xlabel=f"landed {what}", ylabel=f"target {what}", title=name)
    return save(fig, path)


def outcomes(path: Path, throws: dict[str, dict[str, np.ndarray]]) -> Path:
    """Histograms of the number of impacts and of the rest time per thrower."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    per_throw = {name: throw_impacts(t) for name, t in throws.items()}
    impacts = np.concatenate(list(per_throw.values()))
    rest = np.concatenate([t["rest_time"] for t in throws.values()])
    for name, t in throws.items():
        axes[0].hist(per_throw[name], bins=np.linspace(0, max(1, np.percentile(impacts, 99)), 40),
                     alpha=0.5, color=COLOURS.get(name), label=name)
        axes[1].hist(t["rest_time"], bins=np.linspace(0, max(1e-3, np.percentile(rest, 99)), 40),
                     alpha=0.5, color=COLOURS.get(name), label=name)
    axes[0].set(xlabel="corner impacts", ylabel="throws", title="impacts per throw")
    axes[1].set(xlabel="rest time (s)", ylabel="throws", title="time to rest")
    axes[1].legend()
    return save(fig, path)


def robustness(path: Path, sweeps: dict[str, dict[str, list[dict[str, Any]]]],
               trained: dict[str, float]) -> Path:
    """Success against each swept keyword, with 95% intervals; the trained value dashed."""
    fig, axes = plt.subplots(1, len(sweeps), figsize=(3.6 * len(sweeps), 3.4), squeeze=False)
    for ax, (key, per_thrower) in zip(axes[0], sweeps.items(), strict=True):
        for name, points in per_thrower.items():
            x = [p["value"] for p in points]
            y = np.array([p["rate"] for p in points])
            lo = y - np.array([p["ci"][0] for p in points])
            hi = np.array([p["ci"][1] for p in points]) - y
            ax.errorbar(x, y, yerr=np.maximum(0.0, [lo, hi]), marker="o", ms=3, capsize=2,
                        color=COLOURS.get(name), label=name)
        if key in trained:
            ax.axvline(trained[key], color="k", ls="--", lw=0.8)
        ax.set(xlabel=key, ylim=(0, 1), title=f"success vs {key}")
        if key == "stiffness":
            ax.set_xscale("log")
            ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    axes[0, 0].set_ylabel("success")
    axes[0, 0].legend(fontsize=8)
    return save(fig, path)

"""Figures of the evaluation: confusion matrices, strategy, outcomes, robustness, GIFs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

COLOURS = {"PPO": "tab:blue", "hand-written": "tab:orange", "random": "tab:gray",
           "oracle": "tab:green"}
FACES = np.arange(1, 7)


def confusion(path: Path, targets: np.ndarray, landed: dict[str, np.ndarray]) -> Path:
    """Heatmaps of P(landed face | target), one per thrower."""
    fig, axes = plt.subplots(1, len(landed), figsize=(4.2 * len(landed), 3.8), squeeze=False)
    for ax, (name, faces) in zip(axes[0], landed.items(), strict=True):
        counts = np.zeros((6, 6))
        np.add.at(counts, (targets - 1, faces - 1), 1)
        rates = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)
        ax.imshow(rates, vmin=0, vmax=1, cmap="viridis")
        for i in range(6):
            for j in range(6):
                ax.text(j, i, f"{rates[i, j]:.2f}", ha="center", va="center", fontsize=7,
                        color="white" if rates[i, j] < 0.5 else "black")
        ax.set(xticks=range(6), xticklabels=FACES, yticks=range(6), yticklabels=FACES,
               xlabel="landed face", ylabel="target face", title=name)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def strategy(path: Path, targets: np.ndarray, strategies: dict[str, dict[str, Any]]) -> Path:
    """Release speed and spin per target; spin against the target's tilt; spin-axis alignment."""
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5))
    width = 0.8 / len(strategies)
    for k, (name, s) in enumerate(strategies.items()):
        offset = (k - (len(strategies) - 1) / 2) * width
        for ax, key, label in ((axes[0, 0], "speed", "release speed (m/s)"),
                               (axes[0, 1], "spin", "release spin (rad/s)")):
            ax.boxplot([s[key][targets == f] for f in FACES], positions=FACES + offset,
                       widths=width * 0.9, patch_artist=True, showfliers=False,
                       boxprops={"facecolor": COLOURS.get(name, "tab:purple"), "alpha": 0.6})
            ax.set(xticks=FACES, xticklabels=FACES, xlabel="target face", ylabel=label)
        axes[1, 0].scatter(np.degrees(s["tilt"]), s["spin"], s=4, alpha=0.4,
                           color=COLOURS.get(name), label=f"{name} (r={s['spin_tilt_corr']:.2f})")
        axes[1, 1].hist(s["axis_cosine"], bins=40, range=(-1, 1), alpha=0.5,
                        color=COLOURS.get(name), label=name)
    from matplotlib.patches import Patch

    handles = [Patch(color=COLOURS.get(n, "tab:purple"), alpha=0.6, label=n) for n in strategies]
    axes[0, 0].set_title("speed per target")
    axes[0, 0].legend(handles=handles, fontsize=8)
    axes[0, 1].set_title("spin per target")
    axes[1, 0].set(xlabel="target face's angle from up at release (deg)",
                   ylabel="release spin (rad/s)", title="spin against how far the target must turn")
    axes[1, 0].legend(fontsize=8)
    axes[1, 1].set(xlabel="cos(spin axis, n_target × up)", ylabel="throws",
                   title="does the spin turn the target face up?")
    axes[1, 1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def outcomes(path: Path, throws: dict[str, dict[str, np.ndarray]]) -> Path:
    """Histograms of the number of impacts and of the rest time per thrower."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    impacts = np.concatenate([t["impacts"] for t in throws.values()])
    rest = np.concatenate([t["rest_time"] for t in throws.values()])
    for name, t in throws.items():
        axes[0].hist(t["impacts"], bins=np.linspace(0, np.percentile(impacts, 99), 40),
                     alpha=0.5, color=COLOURS.get(name), label=name)
        axes[1].hist(t["rest_time"], bins=np.linspace(0, np.percentile(rest, 99), 40),
                     alpha=0.5, color=COLOURS.get(name), label=name)
    axes[0].set(xlabel="corner impacts", ylabel="throws", title="impacts per throw")
    axes[1].set(xlabel="rest time (s)", ylabel="throws", title="time to rest")
    axes[1].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


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
            ax.errorbar(x, y, yerr=[lo, hi], marker="o", ms=3, capsize=2,
                        color=COLOURS.get(name), label=name)
        if key in trained:
            ax.axvline(trained[key], color="k", ls="--", lw=0.8)
        ax.axhline(1 / 6, color="k", ls=":", lw=0.8)
        ax.set(xlabel=key, ylim=(0, 1), title=f"success vs {key}")
        if key == "stiffness":
            ax.set_xscale("log")
            ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    axes[0, 0].set_ylabel("success")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def save_throws(run: Path, env_id: str, env_kwargs: dict[str, Any], batch: Any, thrower: Any,
                count: int) -> list[Path]:
    """Replay the first ``count`` evaluation episodes of ``thrower`` in the env and save GIFs.

    Same hands and targets as the evaluation; the hand noise is the env's own draw.
    """
    import gymnasium as gym

    from dice_env.envs.video import save_video

    paths = []
    env = gym.make(env_id, render_mode="rgb_array_list", **env_kwargs)
    for i in range(min(count, len(batch.targets))):
        obs, _ = env.reset(seed=i, options={"target_face": int(batch.targets[i]),
                                            "orientation": batch.hands[i]})
        _, _, _, _, info = env.step(thrower(obs[None])[0])
        path = run / f"throw_{i}_target{info['target_face']}_landed{info['face']}.gif"
        save_video(env.render(), path, fps=env.metadata["render_fps"])
        paths.append(path)
    env.close()
    return paths

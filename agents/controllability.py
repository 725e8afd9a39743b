"""How controllable is a die? Success over release height × hand noise.

For the hand-written thrower, the oracle and (optionally) a trained PPO policy:

    python -m agents.controllability [--run RUN_DIR] [--die d6] [--out docs]

Writes ``controllability.json`` (the map), ``controllability.md`` and ``controllability.png``
(drawn from the JSON: :func:`figure`) into ``--out``. The noise level sets
both ``hand_noise`` (fraction of each action range) and ``orientation_noise`` (rad). Release
heights below the die's lowest (its default, :class:`dice_env.envs.throw_task.ThrowTask`) are raised
to it.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from agents.baselines import HandThrower, Thrower
from agents.episodes import Batch, PolicyThrower
from agents.evaluate import clustered
from agents.kept import write_json, write_text
from agents.oracle import CEM, score, score_noise, search
from dice_env.envs.throw_task import ThrowTask, make_task
from dice_env.intervals import wilson_bounds

HEIGHTS = (0.015, 0.02, 0.03, 0.05, 0.15)  # release height of the die's centre (m)
NOISES = (0.01, 0.03, 0.05, 0.1)  # hand noise level (0.05: the env default)
MAP_CEM = CEM(global_candidates=32, iterations=4, population=16, noise_samples=12,
              validation_samples=32)


def controllability(
    heights: tuple[float, ...] = HEIGHTS, noises: tuple[float, ...] = NOISES,
    throws: int = 500, oracle_observations: int = 10, ppo: Thrower | None = None,
    seed: int = 0, num_threads: int | None = None, die: str = "d6",
) -> dict[str, np.ndarray]:
    """Success (rate, low, high) per cell (height, noise) for each thrower: arrays (h, n, 3).

    ``die``: the env's ``die`` keyword; ``heights`` must be at least its release height.
    """
    names = ["hand-written", "oracle"] + (["PPO"] if ppo is not None else [])
    maps = {name: np.zeros((len(heights), len(noises), 3)) for name in names}
    for i, height in enumerate(heights):
        for j, noise in enumerate(noises):
            start = time.perf_counter()
            task = make_task(die=die, release_height=height, hand_noise=noise,
                             orientation_noise=noise)
            rng = np.random.default_rng(seed)
            batch = Batch.sample(task, throws, rng, num_threads=num_threads)
            throwers: dict[str, Thrower] = {"hand-written": HandThrower(task)}
            if ppo is not None:
                throwers["PPO"] = ppo
            for name, thrower in throwers.items():
                s = batch.throw(task, thrower)["is_success"]
                maps[name][i, j] = (s.mean(), *wilson_bounds(int(s.sum()), s.size))
            obs = batch.observations[:oracle_observations]
            starts = {name: thrower(obs) for name, thrower in throwers.items()}
            success = score(task, obs, search(task, obs, rng, MAP_CEM, starts=starts),
                            score_noise(task, rng, len(obs), 16))
            maps["oracle"][i, j] = (success.mean(), *clustered(success))
            print(f"height {height:.3f} m, noise {noise:.2f}: " + ", ".join(
                f"{n} {m[i, j, 0]:.2f}" for n, m in maps.items())
                + f" ({time.perf_counter() - start:.0f} s)", flush=True)
    return maps


def heights_for(task: ThrowTask, heights: tuple[float, ...] = HEIGHTS) -> tuple[float, ...]:
    """``heights`` with those below ``task``'s release height raised to it (no repeats)."""
    return tuple(sorted({max(h, task.release_height) for h in heights}))


def plot(path: Path, maps: dict[str, np.ndarray], heights: tuple[float, ...],
         noises: tuple[float, ...], faces: int) -> Path:
    """One heatmap of success per thrower, chance (1 / ``faces``) at the colour map's low end."""
    from agents.plots import plt, save

    fig, axes = plt.subplots(1, len(maps), figsize=(4.0 * len(maps), 3.8), squeeze=False)
    for ax, (name, m) in zip(axes[0], maps.items(), strict=True):
        ax.imshow(m[..., 0], vmin=1 / faces, vmax=1, cmap="magma", origin="lower",
                  aspect="auto")
        for i in range(len(heights)):
            for j in range(len(noises)):
                ax.text(j, i, f"{m[i, j, 0]:.2f}", ha="center", va="center", fontsize=8,
                        color="white" if m[i, j, 0] < 0.6 else "black")
        ax.set(xticks=range(len(noises)), xticklabels=[f"{n:g}" for n in noises],
               yticks=range(len(heights)), yticklabels=[f"{100 * h:g}" for h in heights],
               xlabel="hand noise level", ylabel="release height (cm, centre)", title=name)
    return save(fig, path)


def map_data(maps: dict[str, np.ndarray], heights: tuple[float, ...],
             noises: tuple[float, ...], faces: int, command: str, seconds: float) -> dict:
    """The map and how it was made, JSON-ready: kept as ``controllability.json``."""
    return {"command": command, "seconds": seconds, "heights": list(heights),
            "noises": list(noises), "faces": faces,
            "maps": {name: m.tolist() for name, m in maps.items()}}


def figure(data: dict, path: Path) -> Path:
    """Draw ``controllability.png`` from the map's JSON ``data`` (:func:`map_data`)."""
    maps = {name: np.array(m) for name, m in data["maps"].items()}
    return plot(path, maps, tuple(data["heights"]), tuple(data["noises"]), data["faces"])


def write_markdown(path: Path, maps: dict[str, np.ndarray], heights: tuple[float, ...],
                   noises: tuple[float, ...], task: ThrowTask, command: str,
                   seconds: float) -> Path:
    """The map as tables (rate [95% CI]) with how it was made; ``task``: the lowest cell's."""
    die, faces = task.scene.die, task.n_faces
    reach = die.reach
    lines = ["# How controllable is a die?", "",
             "Success (target face read at rest) of a thrower that sees the target and the "
             "die's orientation in the hand, over the release height (of the die's centre above "
             f"the table; the die is a {die.name} of {1e3 * die.size:g} mm, its corners reach "
             f"{100 * reach:.2g} cm from its centre) and the hand-noise level (`hand_noise` = "
             f"`orientation_noise`). Chance is 1/{faces} ≈ {1 / faces:.3f}. Other keywords at "
             "DiceThrow-v0's defaults.", "",
             f"![controllability]({path.with_suffix('.png').name})", "",
             f"Drawn by `{command}` from `{path.with_suffix('.json').name}` (the tables below).",
             ""]
    for name, m in maps.items():
        lines += [f"## {name}", "", "| height (cm) | " + " | ".join(
            f"noise {n:g}" for n in noises) + " |", "|---|" + "---|" * len(noises)]
        for i, h in enumerate(heights):
            lines.append(f"| {100 * h:g} | " + " | ".join(
                f"{m[i, j, 0]:.2f} [{m[i, j, 1]:.2f}, {m[i, j, 2]:.2f}]"
                for j in range(len(noises))) + " |")
        lines.append("")
    best = np.max(np.stack([m[..., 0] for m in maps.values()]), axis=0)
    lines += ["## In short", "", "Best success over the throwers, per release height:", ""]
    for i, h in enumerate(heights):
        lines.append(f"- {100 * h:g} cm: " + ", ".join(
            f"{best[i, j]:.2f} at noise {n:g}" for j, n in enumerate(noises)))
    lines += ["", "A die released gently just above the table is controllable: the target comes "
              "up in most throws while the hand is steady, and the hand noise takes that away. "
              "Released high, it bounces and tumbles long enough that success falls to about "
              f"chance (1/{faces}) unless the hand is very steady: the fair, vigorous throw.", ""]
    if "PPO" in maps:
        lines += ["PPO is the policy of the given run, trained in one setting (its env keywords); "
                  "the release height and the noise are not in its observation, so elsewhere it "
                  "throws as if it were there (this is a test of transfer, not of what PPO can "
                  "learn in each cell).", ""]
    lines += ["Intervals: Wilson over the throws (hand-written, PPO); for the oracle (a global "
              "screen and cross-entropy searches started from the other throwers' actions, each "
              "observation scored on 16 fresh noise draws), Wilson on the pooled throws divided "
              "by the design effect of the observations (agents/evaluate.py, `clustered`).", "",
              f"Made with `{command}` in {seconds / 60:.0f} min.", ""]
    write_text(path, "\n".join(lines))
    return path


def main(argv: list[str] | None = None) -> None:
    """Command line: compute the map, write the Markdown and the PNG."""
    parser = argparse.ArgumentParser(prog="python -m agents.controllability",
                                     description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", type=Path, help="a trained run whose PPO is mapped too")
    parser.add_argument("--out", type=Path, default=Path("docs"), help="output folder")
    parser.add_argument("--throws", type=int, default=500, help="throws per cell and thrower")
    parser.add_argument("--oracle-observations", type=int, default=10,
                        help="observations the oracle searches per cell")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--die", default="d6", help="the env's die keyword (d4 ... d20)")
    args = parser.parse_args(argv)
    ppo = None
    if args.run is not None:
        from stable_baselines3 import PPO

        ppo = PolicyThrower(PPO.load(args.run / "model.zip", device="cpu"))
    try:
        task = make_task(die=args.die)
    except ValueError as error:
        parser.error(f"argument --die: {error}")
    heights = heights_for(task)
    start = time.perf_counter()
    maps = controllability(heights, throws=args.throws, ppo=ppo, seed=args.seed, die=args.die,
                           oracle_observations=args.oracle_observations)
    seconds = time.perf_counter() - start
    command = " ".join(["python -m agents.controllability",
                        *(sys.argv[1:] if argv is None else argv)])
    data = map_data(maps, heights, NOISES, task.n_faces, command, seconds)
    args.out.mkdir(parents=True, exist_ok=True)
    write_json(args.out / "controllability.json", data)
    png = figure(data, args.out / "controllability.png")
    md = write_markdown(png.with_suffix(".md"), maps, heights, NOISES, task, command, seconds)
    print(f"wrote {md}, {png} and controllability.json")


if __name__ == "__main__":
    main()

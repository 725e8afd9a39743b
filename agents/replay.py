"""Replay throws of a trained run and save them as GIFs, or as one interactive 3D page.

    python -m agents.replay RUN [--throws 4] [--seed 0] [--target 3] [--thrower hand-written]
    python -m agents.replay RUN --html

Draws fresh episodes of the run's evaluation task (its ``--env`` keywords), throws them with the
run's saved model (or a baseline), prints each outcome and writes ``RUN/replay/*.gif``, or with
``--html`` the page ``RUN/replay/throws.html`` of them, failures first (:mod:`dice_env.viewer`;
the page replays exactly: ``python -m dice_env.viewer --replay PAGE``). The
evaluation uses the same code for its GIFs (:func:`save_throws`), replaying its own throws
exactly: the same hand, target and hand noise.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from agents.baselines import HandThrower, RandomThrower
from agents.config import Config
from agents.episodes import Batch, PolicyThrower, make_eval_task
from agents.kept import RunError, readable_zip
from dice_env.envs.throw_task import ThrowTask

FPS = 30  # frames per second of the GIFs (the env's render_fps)
HOLD = 0.6  # seconds the landed die is shown at the end


def record_throw(task: ThrowTask, action: np.ndarray, target: Any, hand: np.ndarray,
                 noise: np.ndarray, size: tuple[int, int] = (240, 320)) -> tuple[list, dict]:
    """The frames of one throw (the same throw as ``task.throw`` with this noise) and its info.

    One die or several (``target`` and ``hand`` as one row of :class:`Batch`'s).
    """
    from dice_env.envs.render import render_task

    every = max(1, round(1.0 / (FPS * task.step)))
    throw = task.throw(np.asarray(action)[None], np.asarray(target)[None],
                       np.asarray(hand)[None], np.asarray(noise)[None], record_every=every)
    result = throw.result
    shown = int(result.steps[0]) // every
    poses = [(task.hand_position, hand),
             *zip(result.x_cm[0, :shown], result.orientations[0, :shown], strict=True)]
    poses += [(result.final.position[0], result.final.orientation[0])] * round(HOLD * FPS)
    frames = [render_task(task, p, q, size=size) for p, q in poses]
    return frames, {key: value[0] for key, value in throw.info.items()}


def gif_name(prefix: str, index: int, thrower: str, info: dict[str, Any]) -> str:
    """``throw_0_PPO_target3_landed5_failure.gif``.

    Several dice: ``target3-5_landed2-5``, or for a total ``sum7_landed2-4``.
    """
    outcome = "success" if info["is_success"] else "failure"
    if "target_sum" in info:
        target = f"sum{int(info['target_sum'])}"
    else:
        target = "target" + "-".join(str(int(f)) for f in np.ravel(info["target_face"]))
    landed = "-".join(str(int(f)) for f in np.ravel(info["face"]))
    return (f"{prefix}_{index}_{thrower.replace(' ', '-')}_{target}_landed{landed}_"
            f"{outcome}.gif")


def pick_throws(success: np.ndarray, count: int) -> list[int]:
    """Indices of ``count`` throws, failures first, each kind in the evaluation's order.

    Failures take half of them (at least one when there is any), successes the rest.
    """
    failures = np.flatnonzero(~success)
    successes = np.flatnonzero(success)
    n_fail = min(len(failures), max(1, count // 2) if count else 0)
    picked = [*failures[:n_fail], *successes[:count - n_fail], *failures[n_fail:]]
    return [int(i) for i in picked[:count]]


def save_throws(run: Path, task: ThrowTask, batch: Batch, throws: dict[str, np.ndarray],
                thrower: str, count: int) -> list[Path]:
    """GIFs of ``count`` of the evaluation's throws by ``thrower``, failures first.

    ``throws``: that thrower's actions and info from :meth:`agents.episodes.Batch.throw`; each
    throw is replayed exactly (its hand, target and noise).
    """
    from dice_env.envs.video import save_video

    paths = []
    for k, i in enumerate(pick_throws(np.asarray(throws["is_success"]), count)):
        frames, info = record_throw(task, throws["action"][i], batch.targets[i], batch.hands[i],
                                    batch.noise[i])
        paths.append(save_video(frames, run / gif_name("throw", k, thrower, info), fps=FPS))
    return paths


def replay(run: Path, throws: int, seed: int, target: int | None, thrower: str,
           out: Path | None = None, html: bool = False) -> list[Path]:
    """Throw ``throws`` fresh episodes with the run's model (or a baseline); write GIFs.

    ``html``: one page of them instead, failures first.
    """
    from dice_env.envs.video import save_video

    task, episode = make_eval_task(Config.load(run / "config.json"))
    if target is not None:
        episode["target_face"] = target
    batch = Batch.sample(task, throws, np.random.default_rng(seed), **episode)
    if thrower == "PPO":
        act = PolicyThrower(load_model(run / "model.zip"))
    elif thrower == "hand-written":
        act = HandThrower(task)
    else:
        act = RandomThrower(seed, task.action_dim)
    actions = np.asarray(act(batch.observations), np.float64)
    out = out or run / "replay"
    out.mkdir(parents=True, exist_ok=True)
    if html:
        return [write_page(task, batch, actions, thrower, out / "throws.html")]
    paths = []
    for i in range(throws):
        frames, info = record_throw(task, actions[i], batch.targets[i], batch.hands[i],
                                    batch.noise[i])
        path = save_video(frames, out / gif_name(f"replay_s{seed}", i, thrower, info), fps=FPS)
        target = info.get("target_sum", info.get("target_face"))
        print(f"throw {i}: target {target}, landed {info['face']} "
              f"({'success' if info['is_success'] else 'failure'}) -> {path}")
        paths.append(path)
    return paths


def load_model(path: Path) -> Any:
    """The PPO model saved at ``path``; :class:`RunError` naming it if SB3 cannot load it."""
    from stable_baselines3 import PPO

    try:
        return PPO.load(path, device="cpu")
    except Exception as error:  # a foreign or corrupt file fails in many ways
        raise RunError(f"{path} is not a PPO model ({type(error).__name__}: {error}): retrain "
                       "the run, or pass --thrower random") from None


def write_page(task: ThrowTask, batch: Batch, actions: np.ndarray, thrower: str,
               path: Path) -> Path:
    """The page of ``batch``'s throws by ``thrower`` (its ``actions``), failures first."""
    from dice_env.viewer.html import write_html
    from dice_env.viewer.throws import task_throws

    recordings = task_throws(task, actions, batch.targets, batch.hands, batch.noise)
    success = np.array([rec.outcome["success"] for rec in recordings])
    ordered = [recordings[i] for i in np.argsort(success, kind="stable")]  # failures first
    for k, rec in enumerate(ordered):
        print(f"throw {k}: target {rec.outcome['target']}, landed {rec.outcome['faces']} "
              f"({'success' if rec.outcome['success'] else 'failure'})")
    path = write_html(ordered, path, title=f"{thrower}: {run_title(task)}")
    print(f"page: {path}")
    return path


def run_title(task: ThrowTask) -> str:
    """A caption of the task: its dice and walls."""
    dice = ", ".join(die.name for die in task.dice)
    walls = f", {len(task.scene.walls)} walls" if task.scene.walls else ""
    return f"{dice}{walls}"


def main(argv: list[str] | None = None) -> None:
    """Command line: ``python -m agents.replay RUN``."""
    parser = argparse.ArgumentParser(prog="python -m agents.replay", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path, help="run folder (with config.json and model.zip)")
    parser.add_argument("--throws", type=int, default=4, help="throws to replay (>= 1)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the episodes (>= 0)")
    parser.add_argument("--target", type=int, default=None, help="fix the target face")
    parser.add_argument("--thrower", choices=("PPO", "hand-written", "random"), default="PPO",
                        help="who throws (hand-written: one die only)")
    parser.add_argument("--out", type=Path, default=None, help="folder (default: RUN/replay)")
    parser.add_argument("--html", action="store_true",
                        help="one interactive 3D page of the throws, failures first")
    args = parser.parse_args(argv)
    if not (args.run / "config.json").is_file():
        parser.error(f"argument run: {args.run} is not a run folder (no config.json)")
    if args.thrower == "PPO":
        try:
            readable_zip(args.run / "model.zip", "retrain the run, or pass --thrower random")
        except RunError as error:
            parser.error(f"argument run: {error}")
    if args.throws < 1:
        parser.error(f"argument --throws: must be an integer >= 1, got {args.throws}")
    if args.seed < 0:
        parser.error(f"argument --seed: must be an integer >= 0, got {args.seed}")
    try:
        task = make_eval_task(Config.load(args.run / "config.json"))[0]
    except (OSError, ValueError, TypeError) as error:  # not JSON, or not train.py's options
        parser.error(f"argument run: {args.run / 'config.json'} is not a run's config "
                     f"({type(error).__name__}: {error}): pass a folder train.py wrote")
    if args.thrower == "hand-written" and task.n_dice > 1:
        parser.error(f"argument --thrower: hand-written is a one-die rule; the run throws "
                     f"{task.n_dice} dice (target {task.target!r}; use PPO or random)")
    if args.target is not None:
        if task.n_dice > 1:
            parser.error("argument --target: fixes one die's face; the run throws "
                         f"{task.n_dice} dice, whose targets are the run's own (train.py's "
                         "--env target_sum=... or target_face=... fixes them)")
        faces = task.n_faces
        if not 1 <= args.target <= faces:
            parser.error(f"argument --target: must be a face of the run's die, in [1, {faces}], "
                         f"got {args.target}")
    try:
        replay(args.run, args.throws, args.seed, args.target, args.thrower, args.out, args.html)
    except RunError as error:
        parser.error(f"argument run: {error}")


if __name__ == "__main__":
    main()

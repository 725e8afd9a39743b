"""Write a page (and a glTF export) of random throws, or replay a recorded file.

    python -m dice_env.viewer --die d20 --walls tray --seed 0 --out d20.html
    python -m dice_env.viewer --num-dice 2 --throws 3 --layout side --out two.html --glb two.glb
    python -m dice_env.viewer --replay d20.html
    python -m dice_env.viewer --num-dice 2 --walls tray --out tray.html --screenshot tray.png \
        --at 0.2

A throw's action (release velocity and spin) is drawn uniformly, its hand as the env draws
it (``gym.make("DiceThrow-v0", die=..., walls=..., num_dice=...)``). Every argument is checked
before any work; a file that exists is overwritten only with --force. ``--replay`` throws a
page's or an export's throws again and checks that the faces are the ones recorded: exit 0
when they are, 1 when one is not, 2 (with the reason) for a file it cannot use.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

from dice_env.envs.throw_task import MAX_NUM_DICE, ThrowTask, make_task
from dice_env.model.die import STANDARD_SIZES
from dice_env.model.surroundings import WALLS
from dice_env.viewer.files import RecordingError, ReplayError, replay
from dice_env.viewer.html import write_html
from dice_env.viewer.recording import FPS, check_fps, max_throws
from dice_env.viewer.throws import random_throws


def main(argv: list[str] | None = None) -> int:
    """Command line: ``python -m dice_env.viewer``; returns the exit status."""
    parser = argparse.ArgumentParser(prog="python -m dice_env.viewer", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--die", choices=sorted(STANDARD_SIZES), default="d6",
                        help="the die (default d6)")
    parser.add_argument("--walls", choices=sorted(WALLS), default="none",
                        help="walls around the table (default none)")
    parser.add_argument("--num-dice", type=int, default=1,
                        help=f"dice thrown together (1 to {MAX_NUM_DICE})")
    parser.add_argument("--throws", type=int, default=1,
                        help="throws on the page (1 to what fits the memory for records)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the throws (>= 0)")
    parser.add_argument("--fps", type=float, default=FPS,
                        help=f"frames per simulated second (default {FPS:g})")
    parser.add_argument("--layout", choices=("sequence", "side"), default="sequence",
                        help="several throws one after another or side by side")
    parser.add_argument("--out", type=Path, default=Path("throw.html"),
                        help="the page (default throw.html)")
    parser.add_argument("--glb", type=Path, default=None,
                        help="also export the first throw as binary glTF to this path")
    parser.add_argument("--screenshot", type=Path, default=None, metavar="PNG",
                        help="also a picture of the page, in headless Chromium")
    parser.add_argument("--at", type=float, default=None, metavar="T",
                        help="the screenshot's simulated time in s, 0 to t_max (default: the end)")
    parser.add_argument("--force", action="store_true",
                        help="overwrite --out, --glb and --screenshot files that exist")
    parser.add_argument("--replay", type=Path, default=None, metavar="FILE",
                        help="replay a page, .glb or .json of recordings and check its faces")
    args = parser.parse_args(argv)
    if args.replay is not None:
        return _replay(parser, args.replay)
    task = _check(parser, args)
    recordings = random_throws(task, args.throws, args.seed, fps=args.fps)
    for k, rec in enumerate(recordings):
        print(f"throw {k}: faces {rec.outcome['faces']} after {rec.outcome['time']:.2f} s "
              f"({rec.outcome['void'] or 'counts'})")
    page = write_html(recordings, args.out, layout=args.layout)
    print(f"page: {page}")
    if args.glb is not None:
        from dice_env.viewer.gltf import write_glb

        print(f"glTF: {write_glb(recordings[0], args.glb)}")
    if args.screenshot is not None:
        from dice_env.viewer.browser import screenshot

        print(f"screenshot: {screenshot(page, args.screenshot, t=args.at)}")
    return 0


def _check(parser: argparse.ArgumentParser, args: argparse.Namespace) -> ThrowTask:
    """The task of ``args``, every argument checked first (a usage error, exit 2, if not)."""
    if not 1 <= args.num_dice <= MAX_NUM_DICE:
        parser.error(f"argument --num-dice: must be in [1, {MAX_NUM_DICE}], got {args.num_dice}")
    if args.seed < 0:
        parser.error(f"argument --seed: must be an integer >= 0, got {args.seed}")
    task = make_task(die=args.die, walls=args.walls, num_dice=args.num_dice)
    t_max = task.scene.t_max
    try:
        check_fps(args.fps, t_max)
    except ValueError as error:
        parser.error(f"argument --fps: {str(error).removeprefix('fps ')}")
    most = max_throws(task.scene, task.dice, fps=args.fps)
    if not 1 <= args.throws <= most:
        parser.error(f"argument --throws: must be in [1, {most}] (their frames fit "
                     f"the memory for records), got {args.throws}")
    if args.at is not None and (args.screenshot is None or not 0 <= args.at <= t_max):
        parser.error(f"argument --at: must be in [0, {t_max:g}] s (t_max) with --screenshot, "
                     f"got {args.at:g}" + ("" if args.screenshot else " without it"))
    for name, path, suffix in (("out", args.out, ".html"), ("glb", args.glb, ".glb"),
                               ("screenshot", args.screenshot, ".png")):
        if path is None:
            continue
        if path.suffix.lower() != suffix:
            parser.error(f"argument --{name}: must end in {suffix}, got {path.name!r}")
        if not path.parent.is_dir():
            parser.error(f"argument --{name}: no folder {str(path.parent)!r} to write "
                         f"{path.name!r} in")
        if path.is_dir():
            parser.error(f"argument --{name}: {str(path)!r} is a folder: give a file's path")
        if path.exists() and not args.force:
            parser.error(f"argument --{name}: {str(path)!r} exists: pass --force to overwrite "
                         "it, or another path")
    if args.glb is not None and importlib.util.find_spec("pygltflib") is None:
        parser.error("argument --glb: needs pygltflib (pip install 'dice_env[gltf]')")
    if args.screenshot is not None:
        from dice_env.viewer.browser import missing

        if missing():
            parser.error(f"argument --screenshot: {missing()}")
    return task


def _replay(parser: argparse.ArgumentParser, path: Path) -> int:
    """Replay ``path``'s throws; 0 when every face is the recorded one, 1 when one is not."""
    if not path.is_file():
        parser.error(f"argument --replay: no file {path}")
    try:
        again = replay(path)
    except RecordingError as error:
        parser.error(f"argument --replay: {error}")
    except ReplayError as error:
        print(error, file=sys.stderr)
        return 1
    for k, rec in enumerate(again):
        print(f"throw {k}: faces {rec.outcome['faces']}, as recorded")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The README's and the guide's pictures, drawn by the env's renderer.

``python -m studies.readme_figures NAME --out PATH`` writes one of :data:`FIGURES` as a PNG.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

from dice_env import Die, Scene, State
from dice_env.envs.render import render_dice, render_die, resting
from dice_env.model.rotations import axis_angle
from dice_env.model.surroundings import walls
from dice_env.simulation.group import GroupState, simulate_group


def _figure_resting(scene: Scene, label: int, turn: float, at: tuple[float, float] = (0.0, 0.0),
                    **view: Any) -> np.ndarray:
    """The scene's die at rest showing ``label`` (:func:`resting`), seen through ``view``."""
    return render_die(scene, *resting(scene.die, label, at, turn), **view)


def _figure_pair() -> np.ndarray:
    """Two d6 thrown together into the tray, six frames of a seeded throw side by side."""
    scene = Scene(walls=walls("tray"), t_max=3.0)
    dice = (Die(), Die())
    rng = np.random.default_rng(11)
    hands = [State.release(scene, [-0.09, 0.022 * side, 0.06], [0.9, -0.22 * side, 0.0],
                           rng.normal(0.0, 25.0, 3), axis_angle(rng.normal(size=3), 2.0))
             for side in (1.0, -1.0)]
    every = 40
    result = simulate_group(scene, dice, GroupState.of(hands), until="decided",
                            record_every=every, orientations=True)
    last = max(1, int(result.steps[0]) // every - 1)
    shown = np.linspace(0, last, 6).round().astype(int)
    images = [render_dice(scene, dice, result.x_cm[0, j], result.orientations[0, j],
                          size=(240, 240), elevation=60.0, view_edges=6.0) for j in shown]
    gap = np.full((240, 6, 3), 255, np.uint8)
    return np.concatenate([part for image in images for part in (image, gap)][:-1], axis=1)


FIGURES = {  # a d20 seen close, a d6 in the whole tray, a pair's throw
    "die-d20": lambda: _figure_resting(Scene(die=Die.standard("d20")), 20, 0.3 + math.pi,
                                       size=(360, 480), elevation=40.0, view_edges=2.6),
    "tray": lambda: _figure_resting(Scene(walls=walls("tray")), 5, 0.4, (-0.01, 0.01),
                                    size=(480, 640), elevation=50.0, view_edges=25.0),
    "pair": _figure_pair}


def main(argv: list[str] | None = None) -> None:
    """Write one of :data:`FIGURES` as a PNG."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name", choices=sorted(FIGURES))
    parser.add_argument("--out", required=True, help="PNG file to write")
    args = parser.parse_args(argv)
    from PIL import Image

    Image.fromarray(FIGURES[args.name]()).save(args.out, format="PNG")


if __name__ == "__main__":
    main()

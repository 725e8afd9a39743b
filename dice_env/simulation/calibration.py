"""Calibration against the simulator: the table scene for any die, the restitution it produces."""

from __future__ import annotations

import math

import numpy as np

from dice_env.model.checks import check_positive
from dice_env.model.defaults import (
    DIE_EDGE,
    DIE_MASS,
    FRICTION,
    RESTITUTION,
    STIFFNESS,
    damping_for_restitution,
    rebound,
)
from dice_env.model.die import Die
from dice_env.model.rotations import up_rotation
from dice_env.model.scene import Ground, Scene
from dice_env.simulation.simulate import State, simulate


def table_scene(*, edge: float = DIE_EDGE, mass: float = DIE_MASS,
                restitution: float = RESTITUTION, friction: float = FRICTION,
                stiffness: float = STIFFNESS, **scene_options: object) -> Scene:
    """A uniform d6 of ``edge`` and ``mass`` on a table of the given restitution and friction.

    The damping is recomputed for the die's mass; ``scene_options`` go to :class:`Scene`
    (``dt``, ``safety``, ``t_max``, ...). ``Scene()`` equals ``table_scene()``.
    """
    ground = Ground(stiffness=stiffness, friction=friction,
                    damping=damping_for_restitution(restitution, stiffness, mass))
    return Scene(die=Die(edge=edge, mass=mass), ground=ground, **scene_options)


def measured_restitution(scene: Scene, speed: float = 1.0) -> float:
    """Restitution the simulator produces for a flat, spin-free landing at ``speed`` (m/s).

    The die falls from up to 1 mm onto its lowest resting face on a horizontal plane; the result
    is its upward speed back at its resting height (gravity undone) over ``speed``.
    """
    check_positive("speed", speed)
    if scene.ground.normal != (0.0, 0.0, 1.0):
        raise ValueError(f"scene.ground.normal must be (0, 0, 1), got {scene.ground.normal}")
    die, g = scene.die, scene.gravity
    heights = die.resting_heights
    face = int(np.argmin(heights))
    height = float(heights[face])
    gap = min(1e-3, 0.25 * speed**2 / g) if g > 0 else 1e-3
    start = math.sqrt(speed**2 - 2.0 * g * gap)
    state = State.release(scene, np.array([0.0, 0.0, height + gap]), np.array([0.0, 0.0, -start]),
                          orientation=up_rotation(die.reading[face]))
    # contact lasts about pi sqrt(m / 4 S); simulate ten times that, plus the fall
    span = 10.0 * math.pi * math.sqrt(die.mass / (4.0 * scene.ground.stiffness))
    span += (speed - start) / g if g > 0 else gap / speed
    result = simulate(scene, state, t_max=span, until="t_max", record_every=1, record=())
    z = result.x_cm[0, :, 2]
    e = rebound(z, np.diff(z, prepend=height + gap) / scene.step, height, g, speed)
    if e is None:
        raise ValueError(f"the die did not leave the table within {span:.3g} s at speed {speed}")
    return e

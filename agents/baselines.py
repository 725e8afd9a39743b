"""Baseline throwers: a random one and a hand-written one, the bar a person could write.

A thrower maps observations (n, 15) to actions (n, 6) in [-1, 1], like a trained policy's
``predict``; see :class:`Thrower`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from dice_env.die import FACE_NORMALS
from dice_env.envs.task import ThrowTask


class Thrower(Protocol):
    """Anything that throws: observations (n, 15) -> actions (n, 6) in [-1, 1]."""

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """Actions for a batch of observations."""
        ...


def decode(observations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Targets (n,) in 1–6 and hand orientations (n, 3, 3) from observations (n, 15).

    The float32 matrices are projected back onto rotations (nearest in Frobenius norm), so they
    can be thrown again with :meth:`ThrowTask.throw`.
    """
    observations = np.asarray(observations, dtype=np.float64).reshape(-1, 15)
    u, _, vt = np.linalg.svd(observations[:, 6:].reshape(-1, 3, 3))
    return observations[:, :6].argmax(axis=1) + 1, u @ vt


@dataclass
class RandomThrower:
    """Uniform actions in [-1, 1]: the chance level (about 1/6)."""

    seed: int = 0

    def __post_init__(self) -> None:
        self.rng = np.random.default_rng(self.seed)

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """Uniform random actions, one per observation."""
        return self.rng.uniform(-1.0, 1.0, (len(np.atleast_2d(observations)), 6))


@dataclass(frozen=True)
class HandThrower:
    """Toss the die up a little and spin it so the target face turns up as it lands.

    The target's normal in the world, ``n = R e_target``, is turned toward the table normal
    ``z`` about the axis ``n x z`` by the angle between them, at the constant rate that completes
    the turn in ``turn`` times the flight time of a toss at vertical speed ``toss`` (m/s) from
    the release height (the die then lands with the target near the top and settles there).
    """

    task: ThrowTask
    toss: float = 0.0
    turn: float = 1.0

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """Actions (n, 6): a vertical toss and the spin that brings the target face up."""
        targets, hands = decode(observations)
        up = np.asarray(self.task.scene.ground.normal, dtype=np.float64)
        normal = np.einsum("nij,nj->ni", hands, FACE_NORMALS[targets - 1])
        axis = np.cross(normal, up)
        sine = np.linalg.norm(axis, axis=1)
        angle = np.arctan2(sine, normal @ up)
        # Target straight down: any horizontal axis does; pick one perpendicular to up.
        fallback = np.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 1.0, 0.0])
        axis = np.where(sine[:, None] > 1e-9, axis / np.maximum(sine, 1e-12)[:, None],
                        fallback / np.linalg.norm(fallback))
        actions = np.zeros((len(targets), 6))
        actions[:, :3] = up * self.toss / self.task.max_speed
        spin = angle / (self.turn * self.flight_time())
        spin_actions = axis * spin[:, None] / self.task.max_spin
        # Too fast for the hand: scale the spin down, keeping its axis.
        actions[:, 3:] = spin_actions / np.maximum(1.0, np.abs(spin_actions).max(axis=1))[:, None]
        return np.clip(actions, -1.0, 1.0)

    def flight_time(self) -> float:
        """Time (s) until the die's lowest point would reach the table, tossed at ``toss``."""
        scene = self.task.scene
        drop = self.task.release_height - scene.die.edge / 2
        g = scene.gravity * float(np.asarray(scene.ground.normal)[2])
        return (self.toss + math.sqrt(self.toss**2 + 2 * g * drop)) / g

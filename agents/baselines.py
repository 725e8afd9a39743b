"""Baseline throwers: random, the hand-written one (one die) and the set craps throw.

A thrower maps observations (n, faces + 9) to actions (n, 6) in [-1, 1], like a trained policy's
``predict``; see :class:`Thrower`. Sizes come from the observations (the one-hot's length is the
number of faces) and the task (the action size), never from fixed numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from dice_env.envs.hand import ACTION_DIM, SET_ANGLE
from dice_env.envs.throw_task import ORIENTATION_DIM, ThrowTask
from dice_env.model.rotations import matrix_to_rotation_vector
from dice_env.throws import SET_THROW, crossed_set, sevens_set

ROTATION_DIM = ORIENTATION_DIM  # the hand's orientation, a row-major 3x3 matrix, after the one-hot


class Thrower(Protocol):
    """Anything that throws: observations (n, faces + 9) -> actions (n, 6) in [-1, 1]."""

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """Actions for a batch of observations."""
        ...


def n_faces(observation_size: int) -> int:
    """Faces of the die from the observation's size: the one-hot before the orientation."""
    faces = observation_size - ROTATION_DIM
    if faces < 1:
        raise ValueError(f"observation size must exceed {ROTATION_DIM} (a one-hot target and a "
                         f"3x3 orientation), got {observation_size}")
    return faces


def decode(observations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Targets (n,) from 1 and hand orientations (n, 3, 3) from observations (n, faces + 9).

    The float32 matrices are projected back onto rotations (nearest in Frobenius norm), so they
    can be thrown again with :meth:`ThrowTask.throw`.
    """
    observations = np.atleast_2d(np.asarray(observations, dtype=np.float64))
    faces = n_faces(observations.shape[1])
    u, _, vt = np.linalg.svd(observations[:, faces:].reshape(-1, 3, 3))
    return observations[:, :faces].argmax(axis=1) + 1, u @ vt


@dataclass
class RandomThrower:
    """Uniform actions in [-1, 1]^action_size: the chance level (about 1 / faces)."""

    seed: int = 0
    action_size: int = ACTION_DIM

    def __post_init__(self) -> None:
        self.rng = np.random.default_rng(self.seed)

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """Uniform random actions, one per observation."""
        return self.rng.uniform(-1.0, 1.0, (len(np.atleast_2d(observations)),
                                            self.action_size))


@dataclass(frozen=True)
class HandThrower:
    """Toss the die up a little and spin it so the target face turns up as it lands.

    The target's reading direction in the world, ``n = R r_target`` (its outward normal; minus
    it for the d4, read face down), is turned toward the table normal
    ``z`` about the axis ``n x z`` by the angle between them, at the constant rate that completes
    the turn in ``turn`` times the flight time of a toss at vertical speed ``toss`` (m/s) from
    the release height (the die then lands with the target near the top and settles there).
    A one-die rule: a task of several dice is refused.
    """

    task: ThrowTask
    toss: float = 0.0
    turn: float = 1.0

    def __post_init__(self) -> None:
        if self.task.n_dice > 1:
            raise ValueError(f"the hand-written thrower is a one-die rule; this task throws "
                             f"{self.task.n_dice} dice (target {self.task.target!r})")

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """Actions (n, 6): a vertical toss and the spin that brings the target face up."""
        targets, hands = decode(observations)
        up = np.asarray(self.task.scene.ground.normal, dtype=np.float64)
        normal = np.einsum("nij,nj->ni", hands, self.task.scene.die.reading[targets - 1])
        axis = np.cross(normal, up)
        sine = np.linalg.norm(axis, axis=1)
        angle = np.arctan2(sine, normal @ up)
        # Target straight down: any horizontal axis does; pick one perpendicular to up.
        fallback = np.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 1.0, 0.0])
        axis = np.where(sine[:, None] > 1e-9, axis / np.maximum(sine, 1e-12)[:, None],
                        fallback / np.linalg.norm(fallback))
        actions = np.zeros((len(targets), ACTION_DIM))
        actions[:, :3] = up * self.toss / self.task.max_speed
        spin = angle / (self.turn * self.flight_time())
        spin_actions = axis * spin[:, None] / self.task.max_spin
        # Too fast for the hand: scale the spin down, keeping its axis.
        actions[:, 3:] = spin_actions / np.maximum(1.0, np.abs(spin_actions).max(axis=1))[:, None]
        return np.clip(actions, -1.0, 1.0)

    def flight_time(self) -> float:
        """Time (s) until the die's lowest point would reach the table, tossed at ``toss``.

        The lowest point of the die lying on a face: its least resting height.
        """
        scene = self.task.scene
        drop = self.task.release_height - float(scene.die.resting_heights.min())
        g = scene.gravity * float(np.asarray(scene.ground.normal)[2])
        return (self.toss + math.sqrt(self.toss**2 + 2 * g * drop)) / g


@dataclass(frozen=True)
class SetThrower:
    """The craps study's throw with the dice set (two d6, ``set_dice``).

    Each die's setting turns its drawn orientation into the set's: :func:`sevens_set` where
    the task rewards its total, :func:`crossed_set` where it rewards avoiding it
    (``target="avoid_sum"``). The hand moves as :data:`SET_THROW`
    (:class:`~dice_env.throws.SetThrow`), scaled to the task's maxima.
    """

    task: ThrowTask

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """Actions (n, 12): the throw, then each die's setting as a rotation vector / pi."""
        _, hands = self.task.decode(observations)
        chosen = crossed_set() if self.task.target == "avoid_sum" else sevens_set()
        turns = chosen @ np.swapaxes(hands, -1, -2)
        setting = (matrix_to_rotation_vector(turns) / SET_ANGLE).reshape(len(hands), -1)
        scale = np.r_[[SET_THROW.max_speed / self.task.max_speed] * 3,
                      [SET_THROW.max_spin / self.task.max_spin] * 3]
        throw = SET_THROW.action() * scale
        return np.hstack([np.tile(throw, (len(hands), 1)), setting])


def task_rule(task: ThrowTask) -> tuple[str, Thrower] | None:
    """The task's rule and its name: hand-written for one die, the set throw for two set dice.

    None where the task has none (two dice thrown as drawn, three or more dice).
    """
    if task.n_dice == 1:
        return "hand-written", HandThrower(task)
    if task.set_dice and task.n_dice == 2:
        return "set", SetThrower(task)
    return None


def rule_throwers(task: ThrowTask, seed: int = 0) -> dict[str, Thrower]:
    """Random actions and the task's rule (:func:`task_rule`), where it has one."""
    out: dict[str, Thrower] = {"random": RandomThrower(seed, task.action_dim)}
    rule = task_rule(task)
    if rule is not None:
        out[rule[0]] = rule[1]
    return out

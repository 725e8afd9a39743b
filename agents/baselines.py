"""Baseline throwers: random, the hand-written ones (one die; two dice for a total), the set throw.

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


def spin_up(task: ThrowTask, normals: np.ndarray, toss: float = 0.0,
            turn: float = 1.0) -> np.ndarray:
    """Actions (n, 6): toss at ``toss`` m/s and spin ``normals`` (n, 3) toward the table normal.

    About the axis ``normal x up`` by the angle between them, at the constant rate that
    completes the turn in ``turn`` times the flight time (:func:`flight_time`); a spin too fast
    for the hand is scaled down, keeping its axis.
    """
    up = np.asarray(task.scene.ground.normal, dtype=np.float64)
    axis = np.cross(normals, up)
    sine = np.linalg.norm(axis, axis=1)
    angle = np.arctan2(sine, normals @ up)
    # Straight down: any horizontal axis does; pick one perpendicular to up.
    fallback = np.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 1.0, 0.0])
    axis = np.where(sine[:, None] > 1e-9, axis / np.maximum(sine, 1e-12)[:, None],
                    fallback / np.linalg.norm(fallback))
    actions = np.zeros((len(normals), ACTION_DIM))
    actions[:, :3] = up * toss / task.max_speed
    spin = angle / (turn * flight_time(task, toss))
    spin_actions = axis * spin[:, None] / task.max_spin
    actions[:, 3:] = spin_actions / np.maximum(1.0, np.abs(spin_actions).max(axis=1))[:, None]
    return np.clip(actions, -1.0, 1.0)


def flight_time(task: ThrowTask, toss: float = 0.0) -> float:
    """Time (s) until the die's lowest point would reach the table, tossed at ``toss`` m/s.

    The lowest point of the die lying on a face: its least resting height.
    """
    scene = task.scene
    drop = task.release_height - float(scene.die.resting_heights.min())
    g = scene.gravity * float(np.asarray(scene.ground.normal)[2])
    return (toss + math.sqrt(toss**2 + 2 * g * drop)) / g


@dataclass(frozen=True)
class HandThrower:
    """Toss the die up a little and spin it so the target face turns up as it lands.

    The target's reading direction in the world, ``n = R r_target`` (its outward normal; minus
    it for the d4, read face down), is turned toward the table normal by :func:`spin_up`, at
    vertical speed ``toss`` (m/s) and in ``turn`` times the flight time (the die then lands with
    the target near the top and settles there). A one-die rule: a task of several dice is
    refused.
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
        normal = np.einsum("nij,nj->ni", hands, self.task.scene.die.reading[targets - 1])
        return spin_up(self.task, normal, self.toss, self.turn)

    def flight_time(self) -> float:
        """:func:`flight_time` of this thrower's toss."""
        return flight_time(self.task, self.toss)


@dataclass(frozen=True)
class TotalThrower:
    """Two dice for a total from one hand: spin the best pair of faces up together.

    Of the pairs of faces that make the target total, the one whose reading directions in the
    world lie closest together; their mean direction is spun up as :class:`HandThrower` spins
    one target (:func:`spin_up`), so both faces near the top as the dice land.
    """

    task: ThrowTask

    def __post_init__(self) -> None:
        if self.task.n_dice != 2 or self.task.target != "sum" or self.task.set_dice:
            raise ValueError("the total thrower is a rule for two dice thrown from one hand for "
                             f"a total (target='sum'); this task throws {self.task.n_dice} dice "
                             f"for {self.task.target!r}, set_dice={self.task.set_dice}")

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """Actions (n, 6): the spin that brings the closest pair making the total up."""
        totals, hands = self.task.decode(observations)
        first, second = (np.einsum("nij,fj->nfi", hands[:, k], die.reading)
                         for k, die in enumerate(self.task.dice))
        cosine = np.einsum("nai,nbi->nab", first, second)
        labels = [np.arange(1, f + 1) for f in self.task.faces]
        makes = labels[0][None, :, None] + labels[1][None, None, :] == totals[:, None, None]
        best = np.where(makes, cosine, -np.inf).reshape(len(totals), -1).argmax(axis=1)
        a, b = np.unravel_index(best, cosine.shape[1:])
        rows = np.arange(len(totals))
        mean = first[rows, a] + second[rows, b]
        norm = np.linalg.norm(mean, axis=1, keepdims=True)
        normals = np.where(norm > 1e-9, mean / np.maximum(norm, 1e-12), first[rows, a])
        return spin_up(self.task, normals)


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
    """The task's rule and its name: hand-written for one die or two for a total, the set throw.

    None where the task has none (two dice for faces or to avoid a total, three or more dice).
    """
    if task.n_dice == 1:
        return "hand-written", HandThrower(task)
    if task.set_dice and task.n_dice == 2:
        return "set", SetThrower(task)
    if task.n_dice == 2 and task.target == "sum":
        return "hand-written", TotalThrower(task)
    return None


def rule_throwers(task: ThrowTask, seed: int = 0) -> dict[str, Thrower]:
    """Random actions and the task's rule (:func:`task_rule`), where it has one."""
    out: dict[str, Thrower] = {"random": RandomThrower(seed, task.action_dim)}
    rule = task_rule(task)
    if rule is not None:
        out[rule[0]] = rule[1]
    return out

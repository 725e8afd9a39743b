"""The hand: how actions become releases of the dice (geometry, hand noise, set dice).

World frame, z up. The dice sit in rows across the throw (:func:`~dice_env.throws.layout`), the
hand's centre ``release_height`` along the table normal; an action is the hand's velocity and
spin, and with ``set_dice`` a turn of each die before the throw.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dice_env.envs.keywords import check_face
from dice_env.model.checks import as_batch, as_floats, check_nonnegative, check_positive
from dice_env.model.die import Die
from dice_env.model.rotations import rotation_vector_to_matrix, uniform_rotations, up_rotation
from dice_env.model.scene import Scene
from dice_env.simulation.group import GroupState
from dice_env.simulation.simulate import State
from dice_env.throws import layout

ACTION_DIM = 6  # release velocity (3) + angular velocity (3), world frame, in [-1, 1]
NOISE_DIM = 9  # standard normals: velocity (3), spin (3), orientation rotation vector (3)
ORIENTATION_MODES = ("uniform", "flat", "identity")
# Default release height (m) of the d6, and the gap (m) it leaves below its lowest corner; a die
# that reaches further is released higher by default, with the same gap.
RELEASE_HEIGHT = 0.015
RELEASE_GAP = RELEASE_HEIGHT - math.sqrt(3.0) * 0.008
HAND_GAP = 0.002  # m: the least gap between neighbours in the hand, in any orientations
SET_ANGLE = math.pi  # rad: a dice-setting action of 1 turns its die by this much


def default_release_height(dice: Sequence[Die]) -> float:
    """:data:`RELEASE_HEIGHT`, or :data:`RELEASE_GAP` above the dice's farthest corner if higher."""
    clearance = max(die.reach for die in dice)
    return max(RELEASE_HEIGHT, round(clearance + RELEASE_GAP, 4),
               clearance * (1 + 1e-9))  # above a giant die's reach too


@dataclass(frozen=True)
class TaskHand:
    """The dice in the hand and how an action (:attr:`action_dim`) releases them.

    ``scenes``: the scene with each die (the first is the task's scene). The fields are the
    ``gym.make`` keywords of the same names, with their defaults in
    :class:`~dice_env.envs.throw_task.ThrowTask` (``docs/environment.md``). An agent's actions
    drive it; :class:`dice_env.throws.Hand` draws the studies' throws at random.
    """

    scenes: tuple[Scene, ...]
    release_height: float
    max_speed: float
    max_spin: float
    hand_noise: float
    orientation_noise: float
    set_dice: bool

    def __post_init__(self) -> None:
        check_positive("release_height", self.release_height)
        clearance = max(die.reach for die in self.dice)
        if self.release_height <= clearance:
            raise ValueError(
                f"release_height must be > {clearance:.6g} m, the die's farthest corner from its "
                f"centre of mass (no corner may start in the table), got {self.release_height!r}")
        for name in ("max_speed", "max_spin"):
            check_positive(name, getattr(self, name))
        for name in ("hand_noise", "orientation_noise"):
            check_nonnegative(name, getattr(self, name))

    def check_walls(self) -> None:
        """Refuse a hand whose dice would reach through a wall of the scene."""
        for i, (centre, die) in enumerate(zip(self.positions, self.dice, strict=True)):
            for wall in self.scenes[0].walls:  # every die clears every wall by its reach
                gap = float(np.asarray(wall.normal) @ centre - wall.offset)
                if gap <= die.reach:
                    raise ValueError(f"die {i} in the hand (centre {centre.round(4)} m) would "
                                     f"reach through a wall (walls) by {die.reach - gap:.3g} m")

    @property
    def dice(self) -> tuple[Die, ...]:
        """The dice in the hand."""
        return tuple(scene.die for scene in self.scenes)

    @property
    def die_shape(self) -> tuple[int, ...]:
        """The die axis of per-die arrays: () for one die, (N,) for several."""
        return () if len(self.scenes) == 1 else (len(self.scenes),)

    @property
    def action_dim(self) -> int:
        """The hand's velocity and spin (:data:`ACTION_DIM`), and 3 per die with ``set_dice``."""
        return ACTION_DIM + (3 * len(self.scenes) if self.set_dice else 0)

    @property
    def noise_dim(self) -> int:
        """Hand noise per throw: :data:`NOISE_DIM` standard normals per die."""
        return NOISE_DIM * len(self.scenes)

    @property
    def centre(self) -> np.ndarray:
        """The hand's centre at release: ``release_height`` along the table normal (3,)."""
        return self.release_height * np.asarray(self.scenes[0].ground.normal)

    @property
    def spacing(self) -> float:
        """Distance (m) between neighbours' centres: twice the largest reach + :data:`HAND_GAP`."""
        return 2.0 * max(die.reach for die in self.dice) + HAND_GAP

    @property
    def offsets(self) -> np.ndarray:
        """Each die's centre in the hand relative to :attr:`centre`, (N, 3) m (:func:`layout`)."""
        return layout(len(self.scenes), self.spacing, self.scenes[0].ground.normal)

    @property
    def positions(self) -> np.ndarray:
        """Each die's centre at release, (N, 3) m."""
        return self.centre + self.offsets

    def sample_noise(self, rng: np.random.Generator, n: int = 1) -> np.ndarray:
        """Hand noise for ``n`` throws: standard normals (n, :attr:`noise_dim`)."""
        return rng.standard_normal((n, self.noise_dim))

    def draw(self, rng: np.random.Generator, mode: str) -> np.ndarray:
        """One hand's draws (N, 3), die by die: three uniforms, a face and a turn, or nothing."""
        draws = np.zeros((len(self.scenes), 3))
        for j, die in enumerate(self.dice):
            if mode == "uniform":
                draws[j] = rng.random(3)
            elif mode == "flat":
                draws[j, :2] = rng.integers(0, die.n_faces), rng.uniform(0, 2 * np.pi)
        return draws

    def orientations(self, mode: str, draws: np.ndarray) -> np.ndarray:
        """The hands (n, N, 3, 3) of :meth:`draw`'s draws (n, N, 3) in ``mode``."""
        if mode == "identity":
            return np.tile(np.eye(3), (len(draws), len(self.scenes), 1, 1))
        if mode == "uniform":
            return np.stack([uniform_rotations(draws[:, j].T) for j in range(len(self.scenes))],
                            axis=1)
        return np.stack([[_z_turn(turn) @ face_up_rotation(die, int(f) + 1) for f, turn, _ in
                          draws[:, j]] for j, die in enumerate(self.dice)], axis=1)

    def release(self, actions: np.ndarray, hands: np.ndarray,
                noise: np.ndarray | Sequence[np.random.Generator], *,
                action_shape: tuple[int, ...] | None = None,
                ) -> tuple[State | GroupState, np.ndarray]:
        """Releases for ``actions`` (n, :attr:`action_dim`), ``hands`` (n, [N,] 3, 3), ``noise``.

        ``noise``: (n, :attr:`noise_dim`) standard normals, or one generator per throw (drawn
        once the actions are checked). Actions are clipped to [-1, 1]; NaN/inf, or another shape
        than ``action_shape`` (if given), raise ``ValueError``. Returns the State or GroupState,
        and which actions were clipped (n,).
        """
        actions = as_floats("action", actions)
        if action_shape is not None and actions.shape != action_shape:
            raise ValueError(f"action{'s' if len(action_shape) > 1 else ''} must have shape "
                             f"{action_shape}, got {actions.shape}")
        actions = as_batch("action", actions, (self.action_dim,))
        actions, clipped = np.clip(actions, -1.0, 1.0), np.any(np.abs(actions) > 1.0, axis=1)
        if len(noise) and isinstance(noise[0], np.random.Generator):
            noise = np.concatenate([self.sample_noise(rng) for rng in noise])
        n, dice = len(actions), len(self.scenes)
        noise = np.asarray(noise, dtype=np.float64).reshape(n, dice, NOISE_DIM)
        noisy = actions[:, None, :ACTION_DIM] + self.hand_noise * noise[..., :ACTION_DIM]
        spin = noisy[..., 3:] * self.max_spin
        velocity = noisy[..., :3] * self.max_speed + np.cross(spin, self.offsets)
        hands = np.asarray(hands, dtype=np.float64).reshape(n, dice, 3, 3)
        if self.set_dice:
            turns = SET_ANGLE * actions[:, ACTION_DIM:].reshape(n, dice, 3)
            hands = rotation_vector_to_matrix(turns) @ hands
        orientation = rotation_vector_to_matrix(self.orientation_noise * noise[..., 6:]) @ hands
        positions = self.positions
        states = [State.release(scene, positions[i], velocity[:, i], spin[:, i], orientation[:, i])
                  for i, scene in enumerate(self.scenes)]
        return (GroupState.of(states) if dice > 1 else states[0]), clipped


def face_up_rotation(die: Die, face: int) -> np.ndarray:
    """An orientation (body to world, 3x3) in which ``die`` reads ``face``: its reading up."""
    return up_rotation(die.reading[check_face("face", face, die.n_faces) - 1])


def _z_turn(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

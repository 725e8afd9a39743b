"""The DiceThrow task over a batch: hands, noise, releases, throws, rewards.

The single env, the vector env, the SB3 adapter and the oracle share this code path: a
context from :meth:`ThrowTask.sample_hand`, then :meth:`ThrowTask.throw`. World frame, z up.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from functools import cached_property
from typing import Any

import numpy as np

from dice_env.envs.keywords import ENV_MAX_STEPS, SceneKeywords, check_face, check_scene
from dice_env.model.checks import (
    as_batch,
    as_floats,
    check_choice,
    check_int,
    check_nonnegative,
    check_positive,
)
from dice_env.model.die import Die
from dice_env.model.rotations import (
    orthonormality_error,
    quaternion_to_matrix,
    uniform_rotations,
    up_rotation,
)
from dice_env.model.scene import Scene
from dice_env.simulation.group import GroupResult, GroupState, group_step, simulate_group
from dice_env.simulation.simulate import (
    LOCK_MARGIN,
    UP,
    Result,
    State,
    lock_energy,
    simulate,
    thread_count,
)

ORIENTATION_DIM = 9  # the observation's orientation, row-major 3x3, after the target's one-hot
ACTION_DIM = 6  # release velocity (3) + angular velocity (3), world frame, in [-1, 1]
NOISE_DIM = 9  # standard normals: velocity (3), spin (3), orientation rotation vector (3)
ORIENTATION_MODES = ("uniform", "flat", "identity")
# How far a throw is simulated -> the void reason of one that does not get there in t_max.
UNTIL = {"rest": "not_settled", "decided": "not_decided"}
# Default release height (m) of the d6, and the gap (m) it leaves below its lowest corner; a die
# that reaches further is released higher by default, with the same gap.
RELEASE_HEIGHT = 0.015
RELEASE_GAP = RELEASE_HEIGHT - math.sqrt(3.0) * 0.008
MAX_NUM_DICE = 12
TARGETS = ("faces", "sum", "avoid_sum")
HAND_ROW = 4  # dice per row in the hand
HAND_GAP = 0.002  # m: the least gap between neighbours in the hand, in any orientations
SET_ANGLE = math.pi  # rad: a dice-setting action of 1 turns its die by this much


@dataclass(frozen=True)
class ThrowTask:
    """A throw of N dice from the hand: how actions become releases and how a landing is scored.

    ``dice``: 1 … :data:`MAX_NUM_DICE` dice (default: the scene's die; the scene takes the
    first). Per-die arrays have a die axis only for several dice. ``release_height=None`` is
    :data:`RELEASE_HEIGHT`, or :data:`RELEASE_GAP` above any die's farthest corner if higher.
    Every field, the hand, the targets and void throws: ``docs/environment.md``.
    """

    scene: Scene
    release_height: float | None = None
    max_speed: float = 1.0
    max_spin: float = 40.0
    hand_noise: float = 0.05
    orientation_noise: float = 0.05
    min_speed: float = 0.0
    min_spin: float = 0.0
    shaping: float = 0.0
    num_threads: int | None = None
    until: str = "rest"
    dice: tuple[Die, ...] = ()
    target: str | None = None
    set_dice: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.scene, Scene):
            raise ValueError(f"scene must be a Scene, got {type(self.scene).__name__}")
        self._check_dice()
        clearance = max(die.reach for die in self.dice)
        if self.release_height is None:
            object.__setattr__(self, "release_height",
                               max(RELEASE_HEIGHT, round(clearance + RELEASE_GAP, 4),
                                   clearance * (1 + 1e-9)))  # above a giant die's reach too
        check_positive("release_height", self.release_height)
        if self.release_height <= clearance:
            raise ValueError(
                f"release_height must be > {clearance:.6g} m, the die's farthest corner from its "
                f"centre of mass (no corner may start in the table), got {self.release_height!r}")
        for name in ("max_speed", "max_spin"):
            check_positive(name, getattr(self, name))
        for name in ("hand_noise", "orientation_noise", "min_speed", "min_spin", "shaping"):
            check_nonnegative(name, getattr(self, name))
        check_choice("until", self.until, UNTIL)
        if self.until == "decided" and not all(np.isfinite(lock_energy(s)).all()
                                               for s in self.die_scenes):
            raise ValueError("until='decided' needs a horizontal table with gravity (no energy "
                             "bound decides the face on a slope); use until='rest'")
        thread_count(self.num_threads)  # refuses a count numba does not have
        for scene in self.die_scenes:
            check_scene(scene, self.release_height)
        if self.scene.t_max / self.step > ENV_MAX_STEPS:
            raise ValueError(
                f"t_max must be at most {ENV_MAX_STEPS:.0e} steps: t_max={self.scene.t_max:g} s "
                f"over the {self.n_dice} dice's step of {self.step:.3g} s is "
                f"{self.scene.t_max / self.step:.3g} steps; lower t_max or num_dice")
        for i, (centre, die) in enumerate(zip(self.release_positions, self.dice, strict=True)):
            for wall in self.scene.walls:  # every die in the hand clears every wall by its reach
                gap = float(np.asarray(wall.normal) @ centre - wall.offset)
                if gap <= die.reach:
                    raise ValueError(f"die {i} in the hand (centre {centre.round(4)} m) would "
                                     f"reach through a wall (walls) by {die.reach - gap:.3g} m")

    def _check_dice(self) -> None:
        """Check ``dice``, ``target`` and ``set_dice``; set their defaults and the scene's die."""
        dice = self.dice or (self.scene.die,)
        if not (isinstance(dice, tuple) and all(isinstance(d, Die) for d in dice)
                and 1 <= len(dice) <= MAX_NUM_DICE):
            raise ValueError(f"dice must be a tuple of 1 to {MAX_NUM_DICE} Die, got {dice!r}")
        if self.scene.die is not dice[0]:
            object.__setattr__(self, "scene", self.scene.with_(die=dice[0]))
        object.__setattr__(self, "dice", dice)
        several = len(dice) > 1
        if self.target is None:
            object.__setattr__(self, "target", "sum" if several else "faces")
        check_choice("target", self.target, TARGETS)
        if not isinstance(self.set_dice, bool):
            raise ValueError(f"set_dice must be True or False, got {self.set_dice!r}")
        if not several and self.target != "faces":
            raise ValueError(f"target must be 'faces' for one die (target={self.target!r} "
                             f"needs num_dice >= 2)")
        if not several and self.set_dice:
            raise ValueError(f"set_dice needs num_dice >= 2, got set_dice={self.set_dice!r}")

    @cached_property
    def die_scenes(self) -> tuple[Scene, ...]:
        """The scene with each die of :attr:`dice` (the first is :attr:`scene`)."""
        return (self.scene, *(self.scene.with_(die=die) for die in self.dice[1:]))

    @cached_property
    def step(self) -> float:
        """The integration step of a throw (s): the dice's, die against die included."""
        return group_step(self.scene, self.dice)

    @property
    def n_dice(self) -> int:
        """Dice per throw."""
        return len(self.dice)

    @property
    def die_shape(self) -> tuple[int, ...]:
        """The die axis of per-die arrays: () for one die, (N,) for several."""
        return () if self.n_dice == 1 else (self.n_dice,)

    @property
    def faces(self) -> tuple[int, ...]:
        """Faces of each die."""
        return tuple(die.n_faces for die in self.dice)

    @property
    def n_faces(self) -> int:
        """Faces of the one die: its targets are 1 … ``n_faces`` (several dice: :attr:`faces`)."""
        if self.n_dice > 1:
            raise ValueError("n_faces is one die's; several dice have faces, one count per die")
        return self.faces[0]

    @property
    def totals(self) -> range:
        """The totals the faces can add up to: N … the sum of the faces."""
        return range(self.n_dice, sum(self.faces) + 1)

    @property
    def target_shape(self) -> tuple[int, ...]:
        """One throw's target: a face per die (:attr:`die_shape`) or a total (())."""
        return self.die_shape if self.target == "faces" else ()

    @property
    def target_dim(self) -> int:
        """One one-hot per die ("faces") or one over :attr:`totals` (a total's targets)."""
        return sum(self.faces) if self.target == "faces" else len(self.totals)

    @property
    def action_dim(self) -> int:
        """The hand's velocity and spin (:data:`ACTION_DIM`), and 3 per die with ``set_dice``."""
        return ACTION_DIM + (3 * self.n_dice if self.set_dice else 0)

    @property
    def noise_dim(self) -> int:
        """Hand noise per throw: :data:`NOISE_DIM` standard normals per die."""
        return NOISE_DIM * self.n_dice

    @property
    def obs_dim(self) -> int:
        """Observation size: the target's encoding and each die's orientation (9 per die)."""
        return self.target_dim + ORIENTATION_DIM * self.n_dice

    @property
    def release_position(self) -> np.ndarray:
        """The hand's centre at release: ``release_height`` along the table normal (3,)."""
        return self.release_height * np.asarray(self.scene.ground.normal)

    @property
    def hand_spacing(self) -> float:
        """Distance (m) between neighbours' centres: twice the largest reach + :data:`HAND_GAP`."""
        return 2.0 * max(die.reach for die in self.dice) + HAND_GAP

    @property
    def hand_offsets(self) -> np.ndarray:
        """Each die's centre in the hand relative to :attr:`release_position`, (N, 3) m."""
        normal = np.asarray(self.scene.ground.normal)
        x_axis = np.cross([0.0, 1.0, 0.0], normal)
        x_axis /= np.linalg.norm(x_axis)
        y_axis = np.cross(normal, x_axis)
        n, rows = self.n_dice, -(-self.n_dice // HAND_ROW)
        row, column = np.divmod(np.arange(n), HAND_ROW)
        in_row = np.minimum(HAND_ROW, n - row * HAND_ROW)
        return self.hand_spacing * ((row - (rows - 1) / 2)[:, None] * x_axis
                                    + (column - (in_row - 1) / 2)[:, None] * y_axis)

    @property
    def release_positions(self) -> np.ndarray:
        """Each die's centre at release, (N, 3) m."""
        return self.release_position + self.hand_offsets

    @property
    def hand_position(self) -> np.ndarray:
        """The dice's centres in the hand as a pose's position: (3,) for one die, (N, 3)."""
        return self.release_positions.reshape(*self.die_shape, 3)

    def fixed_target(self, target_face: object = None, target_sum: object = None) -> Any:
        """The episode keywords ``target_face``/``target_sum`` as a fixed target (None: drawn).

        "faces": ``target_face``, a face (one die) or a sequence of N faces; "sum" and
        "avoid_sum": ``target_sum``, an int in :attr:`totals`. The other is refused.
        """
        if self.target != "faces":
            if target_face is not None:
                raise ValueError(f"target_face needs target='faces'; target is {self.target!r} "
                                 f"(fix the total with target_sum), got {target_face!r}")
            if target_sum is None:
                return None
            return check_int("target_sum", target_sum, self.totals[0], self.totals[-1])
        if target_sum is not None:
            raise ValueError(f"target_sum needs target='sum' or 'avoid_sum'; target is 'faces' "
                             f"(fix the faces with target_face), got {target_sum!r}")
        if target_face is None:
            return None
        if self.n_dice == 1:
            return check_face("target_face", target_face, self.faces[0])
        if (not isinstance(target_face, Sequence | np.ndarray) or len(target_face) != self.n_dice
                or isinstance(target_face, (str, bytes))):
            raise ValueError(f"target_face must be a sequence of {self.n_dice} faces, one per "
                             f"die (faces {self.faces}), got {target_face!r}")
        return tuple(check_face("target_face", f, n)
                     for f, n in zip(target_face, self.faces, strict=True))

    def sample_hand(self, rng: np.random.Generator, target: Any = None,
                    orientation_mode: str = "uniform") -> tuple[Any, np.ndarray]:
        """One episode's context: the target and the hand (3, 3), or hands (N, 3, 3).

        ``orientation_mode``: "uniform" (all rotations), "flat" (a uniform face up and turn) or
        "identity".
        """
        targets, hands = self.sample_hands([rng], target, orientation_mode)
        return targets[0].tolist() if targets.ndim == 1 else targets[0], hands[0]

    def sample_hands(self, rngs: Sequence[np.random.Generator], target: Any = None,
                     orientation_mode: str = "uniform") -> tuple[np.ndarray, np.ndarray]:
        """One context per generator: targets (n, :attr:`target_shape`), hands (n, N, 3, 3).

        ``target``: fixed, as :meth:`fixed_target` returns it, or None (drawn uniformly). Each
        generator draws the target, then each die's orientation in turn.
        """
        check_choice("orientation_mode", orientation_mode, ORIENTATION_MODES)
        n, by_face = len(rngs), self.target == "faces"
        low, high = (1, np.array(self.faces)) if by_face else (self.totals[0], self.totals[-1])
        targets = np.zeros((n, self.n_dice) if by_face else n, np.int64)
        draws = np.zeros((self.n_dice, n, 3))
        for i, rng in enumerate(rngs):
            targets[i] = rng.integers(low, high + 1) if target is None else target
            for j in range(self.n_dice):  # three uniforms, or a face and a turn, or nothing
                if orientation_mode == "uniform":
                    draws[j, i] = rng.random(3)
                elif orientation_mode == "flat":
                    draws[j, i, :2] = rng.integers(0, self.faces[j]), rng.uniform(0, 2 * np.pi)
        hands = np.stack([_orientations(orientation_mode, draws[j], die)
                          for j, die in enumerate(self.dice)], axis=1)
        return (targets.reshape(n, *self.target_shape), hands.reshape(n, *self.die_shape, 3, 3))

    def sample_noise(self, rng: np.random.Generator, n: int = 1) -> np.ndarray:
        """Hand noise for ``n`` throws: standard normals (n, :attr:`noise_dim`)."""
        return rng.standard_normal((n, self.noise_dim))

    def observe(self, targets: np.ndarray, orientations: np.ndarray) -> np.ndarray:
        """Observations (n, :attr:`obs_dim`) float32: the target's one-hot(s), orientations."""
        orientations = np.asarray(orientations).reshape(-1, ORIENTATION_DIM * self.n_dice)
        n = len(orientations)
        obs = np.zeros((n, self.obs_dim), np.float32)
        # A target's column: its one-hot's start, plus the target less the lowest one.
        shift = np.cumsum([0, *self.faces[:-1]]) - 1 if self.target == "faces" else -self.totals[0]
        obs[np.arange(n)[:, None], np.asarray(targets).reshape(n, -1) + shift] = 1.0
        obs[:, self.target_dim:] = np.clip(orientations, -1.0, 1.0)
        return obs

    def decode(self, observations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Targets and hands (the nearest rotations) from :meth:`observe`'s observations."""
        observations = np.atleast_2d(np.asarray(observations, dtype=np.float64))
        if observations.shape[1] != self.obs_dim:
            raise ValueError(f"observations must have {self.obs_dim} columns, got "
                             f"{observations.shape[1]}")
        n, encoding = len(observations), observations[:, :self.target_dim]
        u, _, vt = np.linalg.svd(observations[:, self.target_dim:].reshape(-1, 3, 3))
        by_face = self.target == "faces"  # a one-hot per die, or one over the totals
        one_hots = np.split(encoding, np.cumsum(self.faces[:-1]) if by_face else [], axis=1)
        lowest = 1 if by_face else self.totals[0]
        targets = np.stack([one_hot.argmax(axis=1) + lowest for one_hot in one_hots], axis=1)
        return (targets.reshape(n, *self.target_shape), (u @ vt).reshape(n, *self.die_shape, 3, 3))

    def release(self, actions: np.ndarray, hands: np.ndarray,
                noise: np.ndarray | Sequence[np.random.Generator], *,
                action_shape: tuple[int, ...] | None = None,
                ) -> tuple[State | GroupState, np.ndarray]:
        """Releases for ``actions`` (n, :attr:`action_dim`), ``hands`` (n, [N,] 3, 3), ``noise``.

        ``noise``: (n, :attr:`noise_dim`) standard normals, or one generator per throw (drawn
        once the actions are checked: finite, of ``action_shape`` if given). Returns the State or
        GroupState, and which actions were clipped to [-1, 1] (n,).
        """
        actions = as_floats("action", actions)
        if action_shape is not None and actions.shape != action_shape:
            raise ValueError(f"action{'s' if len(action_shape) > 1 else ''} must have shape "
                             f"{action_shape}, got {actions.shape}")
        actions = as_batch("action", actions, (self.action_dim,))
        clipped = np.any(np.abs(actions) > 1.0, axis=1)
        actions = np.clip(actions, -1.0, 1.0)
        if len(noise) and isinstance(noise[0], np.random.Generator):
            noise = np.concatenate([self.sample_noise(rng) for rng in noise])
        n, dice = len(actions), self.n_dice
        noise = np.asarray(noise, dtype=np.float64).reshape(n, dice, NOISE_DIM)
        noisy = actions[:, None, :ACTION_DIM] + self.hand_noise * noise[..., :ACTION_DIM]
        spin = noisy[..., 3:] * self.max_spin
        velocity = noisy[..., :3] * self.max_speed + np.cross(spin, self.hand_offsets)
        hands = np.asarray(hands, dtype=np.float64).reshape(n, dice, 3, 3)
        if self.set_dice:
            hands = _rotation_matrices(SET_ANGLE * actions[:, ACTION_DIM:].reshape(n, dice, 3)) \
                @ hands
        orientation = _rotation_matrices(self.orientation_noise * noise[..., 6:]) @ hands
        positions = self.release_positions
        states = [State.release(scene, positions[i], velocity[:, i], spin[:, i], orientation[:, i])
                  for i, scene in enumerate(self.die_scenes)]
        return (GroupState.of(states) if dice > 1 else states[0]), clipped

    def throw(self, actions: np.ndarray, targets: np.ndarray, hands: np.ndarray,
              noise: np.ndarray | Sequence[np.random.Generator], *, record_every: int = 0,
              action_shape: tuple[int, ...] | None = None) -> Throw:
        """Simulate ``n`` throws of the dice in one kernel call and score them.

        ``targets`` (n, :attr:`target_shape`), the rest as :meth:`release`'s; ``record_every`` > 0
        records the centres and orientations every that many steps. Info: the env's keys over n
        (``docs/environment.md``), per-die ones with a die axis (:attr:`die_shape`).
        """
        state, clipped = self.release(actions, hands, noise, action_shape=action_shape)
        n, by_face = len(clipped), self.target == "faces"
        targets = np.array(targets, dtype=np.int64).reshape(n, *self.target_shape)
        speed = np.linalg.norm(state.velocity, axis=-1).reshape(n, -1)
        spin = np.linalg.norm(state.angular_velocity, axis=-1).reshape(n, -1)
        fair = np.all((speed >= self.min_speed) & (spin >= self.min_spin), axis=1)
        result, void = judge(self.scene, self.dice, self._simulate(state, record_every),
                             self.run_until, fair=fair)
        sunk = result.sunk.reshape(n, -1).any(axis=1)
        counts = void == ""
        faces = result.face.reshape(n, -1)
        if by_face:
            per_die = targets.reshape(n, -1)
            hit = np.all(faces == per_die, axis=1)
            normal = np.asarray(self.scene.ground.normal)
            final = result.final.orientation.reshape(n, -1, 3, 3)
            alignment = np.mean([  # n_target . n_table: 1 with the target up, -1 down
                np.einsum("bij,bj,i->b", final[:, i], die.reading[per_die[:, i] - 1], normal)
                for i, die in enumerate(self.dice)], axis=0)
        else:
            hit = (faces.sum(axis=1) == targets) == (self.target == "sum")
            alignment = np.zeros(n)
        success = counts & hit
        reward_success = success.astype(np.float64)
        shaping = np.where(counts, self.shaping * alignment, 0.0)
        several = {"total": faces.sum(axis=1), "leaning": ~result.read} if self.n_dice > 1 else {}
        info = {"is_success": success, "target_face" if by_face else "target_sum": targets,
                "face": result.face, **several, "settled": result.settled,
                "unstable": result.unstable, "sunk": sunk,
                "max_sink": result.max_penetration.reshape(n, -1).max(axis=1), "fair": fair,
                "void_reason": void, "rest_time": result.rest_time, "impacts": result.impacts,
                "reward_success": reward_success, "reward_shaping": shaping,
                "release_velocity": state.velocity, "release_spin": state.angular_velocity,
                "release_orientation": state.orientation, "action_clipped": clipped}
        return Throw(reward=reward_success + shaping, info=info, result=result,
                     observation=self.observe(targets, result.final.orientation))

    @property
    def run_until(self) -> str:
        """The kernel's ``until`` of a throw: ``until``, but ``"early_rest"`` for one die to rest.

        Early rest gives the same face, rest time and impacts, faster (docs/performance.md).
        """
        return "early_rest" if self.until == "rest" and self.n_dice == 1 else self.until

    def _simulate(self, state: State | GroupState, record_every: int) -> Result | GroupResult:
        """The kernel's run of the released dice (:attr:`run_until`): one die's, or the group's."""
        if isinstance(state, GroupState):
            return simulate_group(self.scene, self.dice, state, until=self.run_until,
                                  record_every=record_every, orientations=bool(record_every),
                                  num_threads=self.num_threads)
        return simulate(self.scene, state, until=self.run_until, record_every=record_every,
                        record=("orientations",) if record_every else ("energy",),
                        num_threads=self.num_threads)


@dataclass
class Throw:
    """Outcome of n throws: ``reward`` (n,), the env's ``info`` over n, ``observation`` at rest."""

    reward: np.ndarray
    info: dict[str, np.ndarray]
    result: Result | GroupResult
    observation: np.ndarray


# ThrowTask's fields that make_task takes as keywords.
TASK_KEYWORDS = tuple(f.name for f in fields(ThrowTask) if f.name not in ("scene", "dice"))


def judge(scene: Scene, dice: Sequence[Die], result: Result | GroupResult, until: str, *,
          fair: np.ndarray | None = None, t_max: float | None = None,
          ) -> tuple[Result | GroupResult, np.ndarray]:
    """Whether each throw counts, as the env, the recordings and their replays all count it.

    ``result``: a run of ``dice`` in ``scene`` to ``until`` (a kernel ending of
    :data:`~dice_env.simulation.simulate.ENDINGS`; ``t_max`` overrides the scene's), ``fair``
    (n,): releases within the task's speed and spin (default all). Returns ``result`` (an early
    rest's ``settled`` as if the hold were waited out) and why each throw does not count, (n,)
    strings, ``""`` where it counts; the first of "foul", "unstable", "sunk", "not_settled"
    (``"not_decided"`` for ``until="decided"``), "leaning", and "not_decided" for a face that
    :func:`decided_reads` does not read.
    """
    if until == "early_rest":
        result = _held_within_t_max(result, scene, t_max)
    n = len(result.unstable)
    fair = np.ones(n, np.bool_) if fair is None else fair
    sunk = result.sunk.reshape(n, -1).any(axis=1)
    ended = result.decided if until == "decided" else result.settled
    leaning = ~result.read.all(axis=1) if isinstance(result, GroupResult) else np.zeros(n, bool)
    read = decided_reads(dice, result.final.orientation.reshape(n, len(dice), 3, 3))
    return result, np.select(
        [~fair, result.unstable, sunk, ~ended, leaning, ~read.all(axis=1)],
        ["foul", "unstable", "sunk", UNTIL["decided" if until == "decided" else "rest"],
         "leaning", UNTIL["decided"]], "")


def decided_reads(dice: Sequence[Die], orientation: np.ndarray) -> np.ndarray:
    """Whether each die's face is read beyond doubt in ``orientation`` (n, N, 3, 3): (n, N).

    Its reading direction must beat every other face's along up (against gravity, as faces are
    read) by :data:`~dice_env.simulation.simulate.LOCK_MARGIN` of what it beats its nearest
    neighbour's by when read straight up: the share of the way to a tie that the decided-face
    rule keeps. A die resting on a steep table or cocked against a wall may fall short.
    """
    decided = np.empty(orientation.shape[:2], np.bool_)
    for i, die in enumerate(dice):
        reading = die.reading
        closeness = reading @ reading.T
        np.fill_diagonal(closeness, -np.inf)
        margin = LOCK_MARGIN * (1.0 - closeness.max(axis=1))  # (F,)
        up = np.einsum("bij,fj,i->bf", orientation[:, i], reading, UP)
        top = np.sort(up, axis=1)
        decided[:, i] = top[:, -1] - top[:, -2] >= margin[np.argmax(up, axis=1)]
    return decided


def check_rotation(name: str, value: object, shape: tuple[int, ...] = ()) -> np.ndarray:
    """``value`` as rotation matrices of ``(*shape, 3, 3)``, or ``ValueError`` naming ``name``."""
    rot = as_floats(name, value)
    if (rot.shape != (*shape, 3, 3) or not np.all(np.isfinite(rot))
            or np.max(orthonormality_error(rot)) > 1e-9):
        what = f"{shape[0]} rotation matrices" if shape else "a rotation matrix"
        raise ValueError(f"{name} must be {what}, shape {(*shape, 3, 3)} (R R^T = I, det R = +1),"
                         f" got shape {rot.shape}")
    return rot


def make_task(*, num_dice: int | None = None, scene: Scene | None = None,
              **keywords: Any) -> ThrowTask:
    """A validated :class:`ThrowTask` from flat keywords (the env's ``gym.make`` keywords).

    ``keywords``: :data:`TASK_KEYWORDS` and :class:`~dice_env.envs.keywords.SceneKeywords`'
    fields; the latter modify ``scene`` (default ``Scene(t_max=DEFAULT_T_MAX)``), keeping its
    other fields. ``num_dice`` (None: 1, or the length of a ``die`` tuple) repeats the die;
    ``die`` may be a tuple, one per die (the die keywords apply to each).
    """
    check_task_keywords(keywords)
    fields_given = {name: keywords.pop(name) for name in TASK_KEYWORDS if name in keywords}
    dice = check_num_dice(num_dice, keywords.pop("die", None))
    scenes = [SceneKeywords(die=die, **keywords).build(scene) for die in dice]
    return ThrowTask(scene=scenes[0], dice=tuple(s.die for s in scenes), **fields_given)


def check_num_dice(num_dice: object, die: object) -> tuple[Any, ...]:
    """The ``die`` keyword per die: ``num_dice`` copies of it, or its entries if a tuple."""
    if num_dice is not None:
        check_int("num_dice", num_dice, 1, MAX_NUM_DICE)
    if not isinstance(die, (tuple, list)):
        return (die,) * (1 if num_dice is None else int(num_dice))
    if not 1 <= len(die) <= MAX_NUM_DICE:
        raise ValueError(f"die must be a name, a Die, or a tuple of 1 to {MAX_NUM_DICE} of "
                         f"them, got {len(die)} entries")
    if num_dice is not None and len(die) != num_dice:
        raise ValueError(f"die must hold num_dice={num_dice} dice, got {len(die)}: {die!r}")
    return tuple(die)


def task_keywords() -> set[str]:
    """The keywords :func:`make_task` takes: the task's, ``num_dice``, and the scene's."""
    return {*TASK_KEYWORDS, *inspect.signature(make_task).parameters,
            *(f.name for f in fields(SceneKeywords))} - {"keywords"}


def check_task_keywords(keywords: dict[str, object]) -> dict[str, object]:
    """``keywords`` unchanged if :func:`make_task` takes them all, else ``ValueError``."""
    unknown = sorted(set(keywords) - task_keywords())
    if unknown:
        raise ValueError(f"unknown keyword(s) {unknown}; DiceThrow-v0 takes "
                         f"{sorted(task_keywords())} plus target_face, target_sum, "
                         "orientation_mode, render_mode, render_width, render_height")
    return keywords


def _held_within_t_max(result: Result, scene: Scene, t_max: float | None = None) -> Result:
    """``result`` of an early-rest run, ``settled`` as if the rest hold had been waited out.

    A die whose hold (``ceil(hold / dt)`` quiet steps) ends after ``t_max`` (default the
    scene's) is not settled.
    """
    dt = scene.step
    hold_steps = math.ceil(scene.rest.hold / dt)
    n_steps = max(1, round((scene.t_max if t_max is None else t_max) / dt))
    late = result.settled & (np.rint(result.rest_time / dt) + 1 + hold_steps > n_steps)
    if not late.any():
        return result
    return replace(result, settled=result.settled & ~late,
                   rest_time=np.where(late, n_steps * dt, result.rest_time))


def _rotation_matrices(vectors: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of rotation vectors (..., 3)."""
    flat = np.reshape(vectors, (-1, 3))
    angle = np.linalg.norm(flat, axis=1, keepdims=True)
    safe = np.where(angle > 0, angle, 1.0)
    quaternions = np.hstack([np.cos(angle / 2), np.sin(angle / 2) * flat / safe])
    return quaternion_to_matrix(quaternions).reshape(*np.shape(vectors)[:-1], 3, 3)


def _orientations(mode: str, draws: np.ndarray, die: Die) -> np.ndarray:
    """Hand orientations (n, 3, 3) of ``die`` from :meth:`ThrowTask.sample_hands`' draws (n, 3)."""
    if mode == "uniform":
        return uniform_rotations(draws.T)
    if mode == "flat":
        return np.stack([_z_turn(turn) @ face_up_rotation(die, int(f) + 1) for f, turn, _ in draws])
    return np.tile(np.eye(3), (len(draws), 1, 1))


def _z_turn(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def face_up_rotation(die: Die, face: int) -> np.ndarray:
    """An orientation (body to world, 3x3) in which ``die`` reads ``face``: its reading up."""
    return up_rotation(die.reading[check_face("face", face, die.n_faces) - 1])

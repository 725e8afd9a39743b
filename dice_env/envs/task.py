"""The DiceThrow task as pure functions over a batch: hands, noise, releases, throws, rewards.

Everything the environments do with physics lives here, so the single env, the vector env, the
SB3 adapter and an oracle that searches throws under the env's own hand noise share one code path:

    task = make_task(release_height=0.015)
    target, hand = task.sample_hand(rng)                 # one episode's context
    noise = task.sample_noise(rng, n)                    # (n, 9) standard normals
    throw = task.throw(actions, targets, hands, noise)   # (n, 6) actions -> rewards, info

Frames: world frame, z up on a level table; the table's unit normal is ``task.scene.ground.normal``.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numba
import numpy as np

from dice_env.die import Die
from dice_env.envs.keywords import build_scene, check_face, check_scene
from dice_env.rotations import (
    orthonormality_error,
    quaternion_to_matrix,
    uniform_rotations,
    up_rotation,
)
from dice_env.scene import Scene
from dice_env.simulate import Result, State, lock_energy, simulate
from dice_env.validation import check_nonnegative, check_positive

ORIENTATION_DIM = 9  # the observation's orientation, row-major 3x3, after the target's one-hot
ACTION_DIM = 6  # release velocity (3) + angular velocity (3), world frame, in [-1, 1]
NOISE_DIM = 9  # standard normals: velocity (3), spin (3), orientation rotation vector (3)
ORIENTATION_MODES = ("uniform", "flat", "identity")
# How far a throw is simulated, and the void reason of one that does not get there in t_max.
UNTIL = {"rest": "not_settled", "decided": "not_decided"}
# Default release height (m) of the d6, and the least gap (m) it leaves below the lowest corner
# in any orientation: 1.5 cm against a half diagonal of 1.386 cm. A die whose corners reach
# further is released higher by default, with the same gap.
RELEASE_HEIGHT = 0.015
RELEASE_GAP = RELEASE_HEIGHT - math.sqrt(3.0) * 0.008


@dataclass(frozen=True)
class ThrowTask:
    """A throw from the hand: how actions become releases and how a landing is scored.

    ``release_height`` (m): height of the die's centre above the table at release (None:
    :data:`RELEASE_HEIGHT`, or :data:`RELEASE_GAP` above the die's farthest corner, rounded
    to 0.1 mm, if that is higher).
    ``max_speed`` (m/s) and ``max_spin`` (rad/s): release velocity and angular velocity per
    component at action ±1. ``hand_noise``: standard deviation of the noise added to each action
    component before scaling (so 0.05 is 5% of that component's maximum). ``orientation_noise``
    (rad): standard deviation of each component of a random rotation vector applied to the
    hand's orientation. ``min_speed`` (m/s) and ``min_spin`` (rad/s): the fair-throw rule; a
    release slower than either is a foul (void, reward 0). ``shaping``: weight of the dense term
    ``n_target . n_table`` at rest (1 target up, 0 on a side, -1 down). ``num_threads`` caps the
    kernel's threads (None: all cores). ``until``: "rest" simulates each throw to rest;
    "decided" ends it as soon as its face is decided (``simulate(stop_when_decided=True)``: the
    same face, 2–3 times faster; the die's final state, rest time and impacts are those of that
    moment, and the shaping term is taken there; horizontal table only).
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

    def __post_init__(self) -> None:
        if not isinstance(self.scene, Scene):
            raise ValueError(f"scene must be a Scene, got {type(self.scene).__name__}")
        clearance = float(np.linalg.norm(self.scene.die.vertices_body, axis=1).max())
        if self.release_height is None:
            object.__setattr__(self, "release_height",
                               max(RELEASE_HEIGHT, round(clearance + RELEASE_GAP, 4),
                                   clearance * (1 + 1e-9)))  # above a giant die's reach too
        check_positive("release_height", self.release_height)
        if self.release_height <= clearance:
            raise ValueError(
                f"release_height must be > {clearance:.6g} m, the distance of the die's "
                f"farthest corner from its centre of mass, so that no corner starts in the "
                f"table; got {self.release_height!r}. Raise release_height, or make the die "
                f"smaller (size={self.scene.die.size:g} m) or its load (load_fraction, "
                "load_depth) lighter")
        check_positive("max_speed", self.max_speed)
        check_positive("max_spin", self.max_spin)
        check_nonnegative("hand_noise", self.hand_noise)
        check_nonnegative("orientation_noise", self.orientation_noise)
        check_nonnegative("min_speed", self.min_speed)
        check_nonnegative("min_spin", self.min_spin)
        check_nonnegative("shaping", self.shaping)
        if not isinstance(self.until, str) or self.until not in UNTIL:
            raise ValueError(f"until must be one of {list(UNTIL)}, got {self.until!r}")
        if self.until == "decided" and not np.isfinite(lock_energy(self.scene)).all():
            raise ValueError("until='decided' needs a horizontal table with gravity (no energy "
                             "bound decides the face on a slope); use until='rest'")
        check_num_threads(self.num_threads)
        check_scene(self.scene, self.release_height)

    @property
    def n_faces(self) -> int:
        """Number of faces of the die: targets are 1 … ``n_faces``."""
        return self.scene.die.n_faces

    @property
    def obs_dim(self) -> int:
        """Observation size: the target's one-hot (``n_faces``) and the orientation (9)."""
        return self.n_faces + ORIENTATION_DIM

    @property
    def release_position(self) -> np.ndarray:
        """Centre of the die at release: ``release_height`` along the table normal (3,)."""
        return self.release_height * np.asarray(self.scene.ground.normal)

    def sample_hand(
        self,
        rng: np.random.Generator,
        target_face: int | None = None,
        orientation_mode: str = "uniform",
    ) -> tuple[int, np.ndarray]:
        """One episode's context: the target face and the hand's orientation (3, 3).

        The target is uniform over 1 … ``n_faces`` unless ``target_face`` is given.
        ``orientation_mode`` "uniform": over all rotations; "flat": a uniform face read (its
        reading direction along world z) with a uniform turn about the vertical; "identity":
        the body frame, no draw.
        """
        targets, hands = self.sample_hands([rng], target_face, orientation_mode)
        return int(targets[0]), hands[0]

    def sample_hands(
        self,
        rngs: Sequence[np.random.Generator],
        target_face: int | None = None,
        orientation_mode: str = "uniform",
    ) -> tuple[np.ndarray, np.ndarray]:
        """One context per generator: targets (n,) and hands (n, 3, 3).

        Each is drawn from its generator as :meth:`sample_hand` draws it; the rotations are
        built in one batch.
        """
        if target_face is not None:
            check_face("target_face", target_face, self.n_faces)
        check_orientation_mode(orientation_mode)
        targets = np.full(len(rngs), target_face or 0, np.int64)
        draws = np.zeros((len(rngs), 3))
        for i, rng in enumerate(rngs):
            if target_face is None:
                targets[i] = rng.integers(1, self.n_faces + 1)
            if orientation_mode == "uniform":
                draws[i] = rng.random(3)
            elif orientation_mode == "flat":
                draws[i, 0] = rng.integers(0, self.n_faces)
                draws[i, 1] = rng.uniform(0, 2 * np.pi)
        if orientation_mode == "uniform":
            return targets, uniform_rotations(draws.T)
        if orientation_mode == "flat":
            return targets, np.stack([_z_turn(turn) @ face_up_rotation(self.scene.die, int(f) + 1)
                                      for f, turn, _ in draws])
        return targets, np.tile(np.eye(3), (len(rngs), 1, 1))

    @staticmethod
    def sample_noise(rng: np.random.Generator, n: int = 1) -> np.ndarray:
        """Hand noise for ``n`` throws: standard normals (n, 9), scaled by :meth:`release`."""
        return rng.standard_normal((n, NOISE_DIM))

    def observe(self, targets: np.ndarray, orientations: np.ndarray) -> np.ndarray:
        """Observations (n, :attr:`obs_dim`) float32: one-hot target, orientation row-major."""
        targets = np.asarray(targets).reshape(-1)
        obs = np.zeros((targets.size, self.obs_dim), np.float32)
        obs[np.arange(targets.size), targets - 1] = 1.0
        obs[:, self.n_faces:] = np.clip(np.asarray(orientations).reshape(-1, 9), -1.0, 1.0)
        return obs

    def release(
        self, actions: np.ndarray, hands: np.ndarray, noise: np.ndarray
    ) -> tuple[State, np.ndarray]:
        """Releases actually used for ``actions`` (n, 6), ``hands`` (n, 3, 3), ``noise`` (n, 9).

        Actions are checked (finite, shape) and clipped to [-1, 1]; returns the batch State and a
        bool (n,) saying which actions were clipped.
        """
        actions = check_actions(actions)
        clipped = np.any(np.abs(actions) > 1.0, axis=1)
        noisy = np.clip(actions, -1.0, 1.0) + self.hand_noise * noise[:, :6]
        tilt = quaternion_to_matrix(_rotation_vector_quaternion(
            self.orientation_noise * noise[:, 6:]))
        state = State.release(
            self.scene, self.release_position, noisy[:, :3] * self.max_speed,
            noisy[:, 3:] * self.max_spin, tilt @ np.asarray(hands).reshape(-1, 3, 3),
        )
        return state, clipped

    def throw(
        self,
        actions: np.ndarray,
        targets: np.ndarray,
        hands: np.ndarray,
        noise: np.ndarray,
        *,
        record_every: int = 0,
    ) -> Throw:
        """Simulate ``n`` throws to rest in one kernel call and score them.

        ``actions`` (n, 6) in [-1, 1]; ``targets`` (n,) in 1 … n_faces; ``hands`` (n, 3, 3)
        orientations in the hand; ``noise`` (n, 9) from :meth:`sample_noise`. ``record_every``
        > 0 records the centre and orientation every that many steps (for rendering).
        """
        targets = np.array(targets, dtype=np.int64).reshape(-1)  # a copy: envs redraw theirs
        state, clipped = self.release(actions, hands, noise)
        record = ("orientations",) if record_every else ("energy",)
        # Early rest: the same face, rest time and impacts as waiting out the rest hold, ~3x
        # faster (docs/performance.md); the state at rest is taken when rest is proven.
        decided = self.until == "decided"
        result = simulate(self.scene, state, record_every=record_every, record=record,
                          num_threads=self.num_threads, early_rest=not decided,
                          stop_when_decided=decided)
        if not decided:
            result = _held_within_t_max(result, self.scene)
        normal = np.asarray(self.scene.ground.normal)
        speed = np.linalg.norm(state.velocity, axis=1)
        spin = np.linalg.norm(state.angular_velocity, axis=1)
        fair = (speed >= self.min_speed) & (spin >= self.min_spin)
        ended = result.decided if decided else result.settled
        void = np.where(~fair, "foul", np.where(
            result.unstable, "unstable", np.where(
                result.sunk, "sunk", np.where(ended, "", UNTIL[self.until]))))
        counts = void == ""
        success = counts & (result.face == targets)
        alignment = np.einsum("bij,bj,i->b", result.final.orientation,
                              self.scene.die.reading[targets - 1], normal)
        shaping = np.where(counts, self.shaping * alignment, 0.0)
        reward_success = success.astype(np.float64)
        info = {
            "is_success": success,
            "target_face": targets,
            "face": result.face,
            "settled": result.settled,
            "unstable": result.unstable,
            "sunk": result.sunk,
            "max_sink": result.max_penetration,
            "fair": fair,
            "void_reason": void,
            "rest_time": result.rest_time,
            "impacts": result.impacts,
            "reward_success": reward_success,
            "reward_shaping": shaping,
            "release_velocity": state.velocity,
            "release_spin": state.angular_velocity,
            "release_orientation": state.orientation,
            "action_clipped": clipped,
        }
        return Throw(reward=reward_success + shaping, info=info, result=result,
                     observation=self.observe(targets, result.final.orientation))


@dataclass
class Throw:
    """Outcome of a batch of n throws.

    ``reward`` (n,); ``info`` arrays over n, keys as in the env's ``info``; ``observation``
    (n, obs_dim) of the dice at rest; ``result`` from the kernel.
    """

    reward: np.ndarray
    info: dict[str, np.ndarray]
    result: Result
    observation: np.ndarray


def check_actions(actions: np.ndarray) -> np.ndarray:
    """Actions as a float64 (n, 6) array; NaN/inf or a wrong shape raise ``ValueError``."""
    try:
        array = np.asarray(actions, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"action must be an array of numbers, shape (6,) or (n, 6), got "
                         f"{actions!r}") from error
    if array.shape == (ACTION_DIM,):
        array = array[None]
    if array.ndim != 2 or array.shape[1] != ACTION_DIM:
        raise ValueError(f"action must have shape (6,) or (n, 6), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"action must be finite (no NaN or inf), got {actions!r}")
    return array


def check_orientation_mode(value: object) -> None:
    """``ValueError`` unless ``value`` is one of :data:`ORIENTATION_MODES`."""
    if not (isinstance(value, str) and value in ORIENTATION_MODES):
        raise ValueError(f"orientation_mode must be one of {ORIENTATION_MODES}, got {value!r}")


def check_rotation(name: str, value: object) -> np.ndarray:
    """``value`` as a (3, 3) rotation matrix, or ``ValueError`` naming ``name``."""
    rot = np.asarray(value, dtype=np.float64)
    if rot.shape != (3, 3) or not np.all(np.isfinite(rot)) or orthonormality_error(rot) > 1e-9:
        raise ValueError(f"{name} must be a 3x3 rotation matrix (R R^T = I, det R = +1)")
    return rot


def make_task(
    *,
    release_height: float | None = None,
    max_speed: float = 1.0,
    max_spin: float = 40.0,
    hand_noise: float = 0.05,
    orientation_noise: float = 0.05,
    min_speed: float = 0.0,
    min_spin: float = 0.0,
    shaping: float = 0.0,
    num_threads: int | None = None,
    until: str = "rest",
    scene: Scene | None = None,
    **physics: Any,
) -> ThrowTask:
    """A validated :class:`ThrowTask` from flat keywords (the env's ``gym.make`` keywords).

    ``physics`` are :func:`~dice_env.envs.keywords.build_scene`'s keywords (``t_max``, ``mass``,
    ``stiffness``, ...): each one given modifies ``scene`` (default: ``Scene()`` with ``t_max``
    5 s), whose other fields are kept, so changes to the default scene flow through.
    """
    check_task_keywords(physics)
    return ThrowTask(build_scene(scene, **physics), release_height, max_speed, max_spin,
                     hand_noise, orientation_noise, min_speed, min_spin, shaping, num_threads,
                     until)


def check_num_threads(value: object) -> None:
    """``ValueError`` unless ``value`` is None or an int in [1, numba's thread count]."""
    limit = numba.config.NUMBA_NUM_THREADS
    if value is not None and (isinstance(value, bool) or not isinstance(
            value, (int, np.integer)) or not 1 <= value <= limit):
        raise ValueError(f"num_threads must be None or an int in [1, {limit}] "
                         f"(numba.config.NUMBA_NUM_THREADS), got {value!r}")


def check_task_keywords(keywords: dict[str, object]) -> dict[str, object]:
    """``keywords`` unchanged if :func:`make_task` takes them all, else ``ValueError``."""
    known = {*inspect.signature(make_task).parameters,
             *inspect.signature(build_scene).parameters} - {"physics"}
    unknown = sorted(set(keywords) - set(known))
    if unknown:
        raise ValueError(f"unknown keyword(s) {unknown}; DiceThrow-v0 takes {sorted(known)} "
                         "plus target_face, orientation_mode, render_mode, render_width, "
                         "render_height")
    return keywords


def _held_within_t_max(result: Result, scene: Scene) -> Result:
    """``result`` of an early-rest run with ``settled`` as if the rest hold had been waited out.

    Early rest settles a die the moment its energy proves it stays quiet, with the same face
    and rest time as waiting out ``scene.rest.hold``; waiting it out also needs the hold to end
    within ``t_max`` (``simulate`` counts ``ceil(hold / dt)`` quiet steps after the first). A die
    that went quiet later is not settled, its rest time ``t_max``, as without early rest.
    """
    dt = scene.step
    hold_steps = math.ceil(scene.rest.hold / dt)
    n_steps = max(1, round(scene.t_max / dt))
    late = result.settled & (np.rint(result.rest_time / dt) + 1 + hold_steps > n_steps)
    if not late.any():
        return result
    return replace(result, settled=result.settled & ~late,
                   rest_time=np.where(late, n_steps * dt, result.rest_time))


def _rotation_vector_quaternion(vectors: np.ndarray) -> np.ndarray:
    """Unit quaternions (n, 4), (w, x, y, z), of rotations by rotation vectors (n, 3)."""
    angle = np.linalg.norm(vectors, axis=1, keepdims=True)
    safe = np.where(angle > 0, angle, 1.0)
    return np.hstack([np.cos(angle / 2), np.sin(angle / 2) * vectors / safe])


def _z_turn(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def face_up_rotation(die: Die, face: int) -> np.ndarray:
    """An orientation (body to world, 3x3) in which ``die`` reads ``face`` (a label).

    The face's reading direction (:attr:`Die.reading`) points to world +z
    (:func:`dice_env.rotations.up_rotation`).
    """
    return up_rotation(die.reading[check_face("face", face, die.n_faces) - 1])

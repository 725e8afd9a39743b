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
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from dice_env.die import FACE_NORMALS, Die
from dice_env.rotations import orthonormality_error, quaternion_to_matrix, uniform_rotations
from dice_env.scene import ContactLaw, FrictionLaw, Ground, Rest, Scene, Scheme
from dice_env.simulate import Result, State, lock_energy, simulate
from dice_env.validation import check_nonnegative, check_positive, check_range

OBS_DIM = 15  # target one-hot (6) + hand orientation, row-major 3x3 (9)
ACTION_DIM = 6  # release velocity (3) + angular velocity (3), world frame, in [-1, 1]
NOISE_DIM = 9  # standard normals: velocity (3), spin (3), orientation rotation vector (3)
ORIENTATION_MODES = ("uniform", "flat", "identity")
# How far a throw is simulated, and the void reason of one that does not get there in t_max.
UNTIL = {"rest": "not_settled", "decided": "not_decided"}


@dataclass(frozen=True)
class ThrowTask:
    """A throw from the hand: how actions become releases and how a landing is scored.

    ``release_height`` (m): height of the die's centre above the table at release.
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
    release_height: float = 0.015
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
        clearance = float(np.linalg.norm(self.scene.die.corners_body, axis=1).max())
        check_positive("release_height", self.release_height)
        if self.release_height <= clearance:
            raise ValueError(f"release_height must be > {clearance:.6g} m (the farthest "
                             "corner from the centre of mass, so no corner starts in the "
                             f"table), got {self.release_height!r}")
        check_positive("max_speed", self.max_speed)
        check_positive("max_spin", self.max_spin)
        check_nonnegative("hand_noise", self.hand_noise)
        check_nonnegative("orientation_noise", self.orientation_noise)
        check_nonnegative("min_speed", self.min_speed)
        check_nonnegative("min_spin", self.min_spin)
        check_nonnegative("shaping", self.shaping)
        if self.until not in UNTIL:
            raise ValueError(f"until must be one of {list(UNTIL)}, got {self.until!r}")
        if self.until == "decided" and not np.isfinite(lock_energy(self.scene)).all():
            raise ValueError("until='decided' needs a horizontal table with gravity (no energy "
                             "bound decides the face on a slope); use until='rest'")
        if self.num_threads is not None and (
            not isinstance(self.num_threads, (int, np.integer)) or self.num_threads < 1
        ):
            raise ValueError(f"num_threads must be None or an int >= 1, got {self.num_threads!r}")

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

        The target is uniform over 1–6 unless ``target_face`` is given. ``orientation_mode``
        "uniform": over all rotations; "flat": a uniform face up (relative to world z) with a
        uniform turn about the vertical; "identity": face 1 up, no draw.
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
            check_face("target_face", target_face)
        if orientation_mode not in ORIENTATION_MODES:
            raise ValueError(f"orientation_mode must be one of {ORIENTATION_MODES}, "
                             f"got {orientation_mode!r}")
        targets = np.full(len(rngs), target_face or 0, np.int64)
        draws = np.zeros((len(rngs), 3))
        for i, rng in enumerate(rngs):
            if target_face is None:
                targets[i] = rng.integers(1, 7)
            if orientation_mode == "uniform":
                draws[i] = rng.random(3)
            elif orientation_mode == "flat":
                draws[i, 0], draws[i, 1] = rng.integers(0, 6), rng.uniform(0, 2 * np.pi)
        if orientation_mode == "uniform":
            return targets, uniform_rotations(draws.T)
        if orientation_mode == "flat":
            return targets, np.stack([_z_turn(turn) @ _FACE_UP[int(face)]
                                      for face, turn, _ in draws])
        return targets, np.tile(np.eye(3), (len(rngs), 1, 1))

    @staticmethod
    def sample_noise(rng: np.random.Generator, n: int = 1) -> np.ndarray:
        """Hand noise for ``n`` throws: standard normals (n, 9), scaled by :meth:`release`."""
        return rng.standard_normal((n, NOISE_DIM))

    @staticmethod
    def observe(targets: np.ndarray, orientations: np.ndarray) -> np.ndarray:
        """Observations (n, 15) float32: one-hot target (6), then the orientation row-major (9)."""
        targets = np.asarray(targets).reshape(-1)
        obs = np.zeros((targets.size, OBS_DIM), np.float32)
        obs[np.arange(targets.size), targets - 1] = 1.0
        obs[:, 6:] = np.clip(np.asarray(orientations).reshape(-1, 9), -1.0, 1.0)
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

        ``actions`` (n, 6) in [-1, 1]; ``targets`` (n,) in 1–6; ``hands`` (n, 3, 3) orientations
        in the hand; ``noise`` (n, 9) from :meth:`sample_noise`. ``record_every`` > 0 records the
        centre and orientation every that many steps (for rendering).
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
        normal = np.asarray(self.scene.ground.normal)
        speed = np.linalg.norm(state.velocity, axis=1)
        spin = np.linalg.norm(state.angular_velocity, axis=1)
        fair = (speed >= self.min_speed) & (spin >= self.min_spin)
        ended = result.decided if decided else result.settled
        void = np.where(~fair, "foul", np.where(result.unstable, "unstable",
                                                np.where(ended, "", UNTIL[self.until])))
        counts = void == ""
        success = counts & (result.face == targets)
        alignment = np.einsum("bij,bj,i->b", result.final.orientation,
                              FACE_NORMALS[targets - 1], normal)
        shaping = np.where(counts, self.shaping * alignment, 0.0)
        reward_success = success.astype(np.float64)
        info = {
            "is_success": success,
            "target_face": targets,
            "face": result.face,
            "settled": result.settled,
            "unstable": result.unstable,
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
    (n, 15) of the dice at rest; ``result`` from the kernel.
    """

    reward: np.ndarray
    info: dict[str, np.ndarray]
    result: Result
    observation: np.ndarray


def check_actions(actions: np.ndarray) -> np.ndarray:
    """Actions as a float64 (n, 6) array; NaN/inf or a wrong shape raise ``ValueError``."""
    array = np.asarray(actions, dtype=np.float64)
    if array.shape == (ACTION_DIM,):
        array = array[None]
    if array.ndim != 2 or array.shape[1] != ACTION_DIM:
        raise ValueError(f"action must have shape (6,) or (n, 6), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"action must be finite (no NaN or inf), got {actions!r}")
    return array


def check_rotation(name: str, value: object) -> np.ndarray:
    """``value`` as a (3, 3) rotation matrix, or ``ValueError`` naming ``name``."""
    rot = np.asarray(value, dtype=np.float64)
    if rot.shape != (3, 3) or not np.all(np.isfinite(rot)) or orthonormality_error(rot) > 1e-9:
        raise ValueError(f"{name} must be a 3x3 rotation matrix (R R^T = I, det R = +1)")
    return rot


def make_task(
    *,
    release_height: float = 0.015,
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
    t_max: float = 5.0,
    edge: float | None = None,
    mass: float | None = None,
    load_face: int = 6,
    load_fraction: float = 0.0,
    load_depth: float = 0.8,
    stiffness: float | None = None,
    damping: float | None = None,
    friction: float | None = None,
    tilt_deg: float = 0.0,
    contact_law: str | None = None,
    gravity: float | None = None,
    dt: float | None = None,
    safety: float | None = None,
    rest_speed: float | None = None,
    rest_hold: float | None = None,
    energy_tol: float | None = None,
    scheme: str | None = None,
    friction_law: str | None = None,
    friction_vmin: float | None = None,
) -> ThrowTask:
    """A validated :class:`ThrowTask` from flat keywords (the env's ``gym.make`` keywords).

    Physical keywords left at None keep the defaults of :class:`~dice_env.scene.Scene` (or of
    ``scene`` when one is given), so changes to the default scene flow through. ``load_fraction``
    > 0 builds :meth:`Die.loaded` toward ``load_face``; ``tilt_deg`` tilts the table about y;
    ``contact_law`` is "gated" or "paper"; ``scheme`` is "paper" or "midpoint" (see
    :class:`~dice_env.scene.Scheme`); ``friction_law`` is "stick_slip" or "regularized" (the
    listing's, whose ``friction_vmin`` is its umin; see :class:`~dice_env.scene.FrictionLaw`).
    """
    base = Scene() if scene is None else scene
    if not isinstance(base, Scene):
        raise ValueError(f"scene must be a Scene or None, got {type(base).__name__}")
    check_range("load_fraction", load_fraction, 0.0, 1.0, high_open=True)
    die = base.die
    if edge is not None or mass is not None:
        die = Die(**_given(edge=edge, mass=mass, default=base.die))
    if load_fraction > 0:
        die = Die.loaded(check_face("load_face", load_face), load_fraction, load_depth,
                         edge=die.edge, mass=die.mass)
    ground_kw = _given(stiffness=stiffness, damping=damping, friction=friction,
                       contact_law=contact_law, default=base.ground)
    ground_kw["contact_law"] = _choice("contact_law", contact_law, ContactLaw,
                                       base.ground.contact_law)
    check_range("tilt_deg", tilt_deg, 0.0, 90.0, high_open=True)
    ground = Ground.tilted(tilt_deg, **ground_kw) if tilt_deg else Ground(
        normal=base.ground.normal, **ground_kw)
    rest = Rest(**_given(speed=rest_speed, hold=rest_hold, default=base.rest))
    scene_kw = _given(gravity=gravity, safety=safety, energy_tol=energy_tol,
                      friction_vmin=friction_vmin, default=base)
    scene_kw["scheme"] = _choice("scheme", scheme, Scheme, base.scheme)
    scene_kw["friction_law"] = _choice("friction_law", friction_law, FrictionLaw,
                                       base.friction_law)
    scene = base.with_(die=die, ground=ground, rest=rest, t_max=t_max,
                       dt=base.dt if dt is None else dt, **scene_kw)
    return ThrowTask(scene, release_height, max_speed, max_spin, hand_noise, orientation_noise,
                     min_speed, min_spin, shaping, num_threads, until)


def _choice(name: str, value: str | None, kind: type[IntEnum], default: IntEnum) -> IntEnum:
    """The member of ``kind`` named ``value`` in lower case (``default`` for None)."""
    members = {member.name.lower(): member for member in kind}
    if value is not None and value not in members:
        raise ValueError(f"{name} must be one of {sorted(members)}, got {value!r}")
    return default if value is None else members[value]


def check_face(name: str, value: object) -> int:
    """``value`` as a face number 1–6, or ``ValueError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an int in [1, 6], got {value!r}")
    check_range(name, int(value), 1, 6)
    return int(value)


def check_task_keywords(keywords: dict[str, object]) -> dict[str, object]:
    """``keywords`` unchanged if :func:`make_task` takes them all, else ``ValueError``."""
    known = inspect.signature(make_task).parameters
    unknown = sorted(set(keywords) - set(known))
    if unknown:
        raise ValueError(f"unknown keyword(s) {unknown}; DiceThrow-v0 takes {sorted(known)} "
                         "plus target_face, orientation_mode, render_mode, render_width, "
                         "render_height")
    return keywords


def _given(default: object, **values: object) -> dict[str, object]:
    """The keywords that were given, others taken from the dataclass ``default``."""
    return {k: getattr(default, k) if v is None else v for k, v in values.items()}


def _rotation_vector_quaternion(vectors: np.ndarray) -> np.ndarray:
    """Unit quaternions (n, 4), (w, x, y, z), of rotations by rotation vectors (n, 3)."""
    angle = np.linalg.norm(vectors, axis=1, keepdims=True)
    safe = np.where(angle > 0, angle, 1.0)
    return np.hstack([np.cos(angle / 2), np.sin(angle / 2) * vectors / safe])


def _z_turn(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _face_up_rotation(face_normal: np.ndarray) -> np.ndarray:
    """A rotation taking the body vector ``face_normal`` to world +z (axes permuted/flipped)."""
    z = face_normal
    x = np.roll(np.abs(z), 1)
    y = np.cross(z, x)
    return np.stack([x, y, z])


# Rotations putting face k+1 up (rows: the body axes that map to world x, y, z).
_FACE_UP = np.stack([_face_up_rotation(n) for n in FACE_NORMALS])

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
from functools import cached_property
from typing import Any

import numpy as np

from dice_env.checks import as_floats, check_nonnegative, check_positive, check_range
from dice_env.die import Die
from dice_env.envs.keywords import ENV_MAX_STEPS, build_scene, check_face, check_scene
from dice_env.group import GroupResult, GroupState, group_step, simulate_group
from dice_env.rotations import (
    orthonormality_error,
    quaternion_to_matrix,
    uniform_rotations,
    up_rotation,
)
from dice_env.scene import Scene
from dice_env.simulate import Result, State, lock_energy, simulate, thread_count

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
# Several dice: how many, what the target names, how the hand holds them.
MAX_NUM_DICE = 12
TARGETS = ("faces", "sum")
HAND_ROW = 4  # dice per row in the hand
HAND_GAP = 0.002  # m: the least gap between neighbours in the hand, in any orientations
SET_ANGLE = math.pi  # rad: a dice-setting action of 1 turns its die by this much


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
        clearance = max(die.reach for die in self.dice)
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
        if self.until == "decided" and not all(np.isfinite(lock_energy(s)).all()
                                               for s in self.die_scenes):
            raise ValueError("until='decided' needs a horizontal table with gravity (no energy "
                             "bound decides the face on a slope); use until='rest'")
        thread_count(self.num_threads)  # refuses a count numba does not have
        for scene in self.die_scenes:
            check_scene(scene, self.release_height)
        self._check_walls()

    @property
    def dice(self) -> tuple[Die, ...]:
        """The dice in the hand: the scene's die."""
        return (self.scene.die,)

    @property
    def step(self) -> float:
        """The integration step of a throw (s)."""
        return self.scene.step

    @property
    def die_scenes(self) -> tuple[Scene, ...]:
        """The scene with each die of :attr:`dice`."""
        return (self.scene,)

    @property
    def release_positions(self) -> np.ndarray:
        """Each die's centre at release, (N, 3) m: the release point."""
        return self.release_position[None]

    def _check_walls(self) -> None:
        """Every die in the hand must clear every wall by its reach."""
        for i, (centre, die) in enumerate(zip(self.release_positions, self.dice, strict=True)):
            for wall in self.scene.walls:
                gap = float(np.asarray(wall.normal) @ centre - wall.offset)
                if gap <= die.reach:
                    raise ValueError(
                        f"die {i} in the hand (centre {centre.round(4)} m) would reach through "
                        f"a wall (walls) by {die.reach - gap:.3g} m; use fewer or smaller "
                        "dice (num_dice, size) or other walls")

    @property
    def n_dice(self) -> int:
        """Dice per throw: 1."""
        return 1

    @property
    def target(self) -> str:
        """What the target names: "faces", the face to land up."""
        return "faces"

    @property
    def target_dim(self) -> int:
        """Length of the target's encoding at the start of the observation: ``n_faces``."""
        return self.n_faces

    @property
    def action_dim(self) -> int:
        """Action size: :data:`ACTION_DIM`."""
        return ACTION_DIM

    @property
    def noise_dim(self) -> int:
        """Hand noise per throw: :data:`NOISE_DIM` standard normals."""
        return NOISE_DIM

    @property
    def n_faces(self) -> int:
        """Number of faces of the die: targets are 1 … ``n_faces``."""
        return self.scene.die.n_faces

    @property
    def obs_dim(self) -> int:
        """Observation size: the target's encoding and each die's orientation (9 per die)."""
        return self.target_dim + ORIENTATION_DIM * self.n_dice

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
            draws[i] = _orientation_draw(rng, orientation_mode, self.n_faces)
        return targets, _orientations(orientation_mode, draws, self.scene.die)

    def fixed_target(self, target_face: object = None, target_sum: object = None) -> Any:
        """The episode keywords ``target_face``/``target_sum`` as a fixed target (None: drawn).

        One die: ``target_face`` (1 … ``n_faces``); ``target_sum`` is refused.
        """
        if target_sum is not None:
            raise ValueError(f"target_sum fixes the total of several dice (num_dice >= 2, "
                             f"target='sum'); this throw has one die, got {target_sum!r}")
        return None if target_face is None else check_face("target_face", target_face,
                                                           self.n_faces)

    def sample_noise(self, rng: np.random.Generator, n: int = 1) -> np.ndarray:
        """Hand noise for ``n`` throws: standard normals (n, :attr:`noise_dim`).

        Scaled by :meth:`release`.
        """
        return rng.standard_normal((n, self.noise_dim))

    def decode(self, observations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Targets and hands from observations (n, :attr:`obs_dim`), as :meth:`observe` took.

        The float32 matrices are projected back onto rotations (nearest in Frobenius norm), so
        they can be thrown again with :meth:`throw`.
        """
        observations = np.atleast_2d(np.asarray(observations, dtype=np.float64))
        if observations.shape[1] != self.obs_dim:
            raise ValueError(f"observations must have {self.obs_dim} columns, got "
                             f"{observations.shape[1]}")
        u, _, vt = np.linalg.svd(observations[:, self.target_dim:].reshape(-1, 3, 3))
        hands = (u @ vt).reshape(len(observations), *self._hand_shape)
        return self._decode_target(observations[:, :self.target_dim]), hands

    @property
    def _hand_shape(self) -> tuple[int, ...]:
        return (3, 3)

    def _decode_target(self, encoding: np.ndarray) -> np.ndarray:
        return encoding.argmax(axis=1) + 1

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
        actions = check_actions(actions, self.action_dim)
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
        void = void_reasons(fair, result.unstable, result.sunk, ended, self.until)
        counts = void == ""
        success = counts & (result.face == targets)
        alignment = target_alignment(result.final.orientation, self.scene.die, targets, normal)
        shaping = np.where(counts, self.shaping * alignment, 0.0)
        outcome = {"face": result.face, "settled": result.settled, "unstable": result.unstable,
                   "sunk": result.sunk, "max_sink": result.max_penetration}
        return self._scored(("target_face", targets), outcome, success, fair, void, shaping,
                            state, clipped, result)

    def _scored(self, target: tuple[str, np.ndarray], outcome: dict[str, np.ndarray],
                success: np.ndarray, fair: np.ndarray, void: np.ndarray, shaping: np.ndarray,
                state: State | GroupState, clipped: np.ndarray,
                result: Result | GroupResult) -> Throw:
        """The :class:`Throw` of a scored batch: rewards, info arrays, observations.

        ``target``: the info key of the targets and the targets; ``outcome``: the info arrays
        of what landed (``face``, ``settled``, ``unstable``, ``sunk``, ``max_sink``, ...).
        """
        name, targets = target
        reward_success = success.astype(np.float64)
        info = {
            "is_success": success,
            name: targets,
            **outcome,
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
    result: Result | GroupResult
    observation: np.ndarray


@dataclass(frozen=True)
class GroupThrowTask(ThrowTask):
    """A throw of several dice from one hand: they fly, collide and land together.

    ``dice``: 2 … :data:`MAX_NUM_DICE` dice, mixed shapes allowed, simulated together with
    :func:`dice_env.group.simulate_group` (die against die, the planes of ``scene``; the
    scene's own die is not used). Every other field as :class:`ThrowTask`; ``release_height``
    must clear the reach of every die.

    **The hand** holds the dice in rows of up to :data:`HAND_ROW` along the table's y axis, the
    rows one behind the other along its x axis, die ``i`` in row ``i // 4``; neighbours' centres
    are :attr:`hand_spacing` apart (the largest die's diameter across corners plus
    :data:`HAND_GAP`), each row centred on y = 0 and the rows on x = 0, so the hand's centre is
    the release point, all at ``release_height`` (:attr:`hand_offsets`). The hand is rigid:
    one action gives the hand's velocity ``v`` and spin ``w``, and die ``i`` leaves it with
    velocity ``v + w x r_i`` and spin ``w`` (``r_i`` its offset); each die has its own hand noise
    (9 standard normals per die, as one die's, added to the action before that product) and
    its own orientation in the hand, drawn per die.

    **Targets.** ``target="sum"`` (the default): a total N … sum of the faces is drawn uniformly
    and the throw succeeds when the faces read add up to it ("roll a seven" with two d6); the
    observation starts with one one-hot over the totals. Games with several dice score their
    total (craps, backgammon's moves aside, most board games), so it is the task people throw
    for; the dense shaping term is 0 (no single face needs to be up). ``target="faces"``: a face
    per die, each drawn uniformly, success when every die shows its own; the observation starts
    with one one-hot per die, and the shaping term is the mean over dice of each target's
    alignment with the table normal. Then every die's orientation (9 numbers per die).

    **Void throws** as one die's (foul: a die released slower than ``min_speed`` or
    ``min_spin``; unstable; sunk: any die; not settled or not decided), then "leaning": a die
    ended leaning on another die (not read).

    ``set_dice``: the agent also sets each die in the hand, as craps "dice setters" do: the
    action grows by 3 per die, a rotation vector ``SET_ANGLE * a`` (rad, world frame) applied
    to that die's drawn orientation before the orientation noise.
    """

    dice: tuple[Die, ...] = ()
    target: str = "sum"
    set_dice: bool = False

    def __post_init__(self) -> None:
        if not (isinstance(self.dice, tuple) and all(isinstance(d, Die) for d in self.dice)
                and 2 <= len(self.dice) <= MAX_NUM_DICE):
            raise ValueError(f"dice must be a tuple of 2 to {MAX_NUM_DICE} Die, "
                             f"got {self.dice!r}")
        if not (isinstance(self.target, str) and self.target in TARGETS):
            raise ValueError(f"target must be one of {TARGETS}, got {self.target!r}")
        if not isinstance(self.set_dice, bool):
            raise ValueError(f"set_dice must be True or False, got {self.set_dice!r}")
        super().__post_init__()
        step = self.step
        if self.scene.t_max / step > ENV_MAX_STEPS:
            raise ValueError(
                f"t_max must be at most {ENV_MAX_STEPS:.0e} steps: t_max={self.scene.t_max:g} s "
                f"over the {self.n_dice} dice's step of {step:.3g} s (die against die included) is "
                f"{self.scene.t_max / step:.3g} steps; lower t_max or num_dice")

    @cached_property
    def die_scenes(self) -> tuple[Scene, ...]:
        """The scene with each die of :attr:`dice`."""
        return tuple(self.scene.with_(die=die) for die in self.dice)

    @cached_property
    def step(self) -> float:
        """The integration step of a throw (s): the dice's, die against die included."""
        return group_step(self.scene, self.dice)

    @property
    def n_dice(self) -> int:
        """Dice per throw."""
        return len(self.dice)

    @property
    def n_faces(self) -> int:
        """Refused: several dice have :attr:`faces`, one count per die."""
        raise ValueError("n_faces is one die's; a throw of several dice has faces (one count "
                         "per die)")

    @property
    def faces(self) -> tuple[int, ...]:
        """Faces of each die."""
        return tuple(die.n_faces for die in self.dice)

    @property
    def totals(self) -> range:
        """The totals the faces can add up to: N … the sum of the faces."""
        return range(self.n_dice, sum(self.faces) + 1)

    @property
    def target_dim(self) -> int:
        """One one-hot per die ("faces") or one over :attr:`totals` ("sum")."""
        return sum(self.faces) if self.target == "faces" else len(self.totals)

    @property
    def action_dim(self) -> int:
        """The hand's velocity and spin (6), and 3 per die with ``set_dice``."""
        return ACTION_DIM + (3 * self.n_dice if self.set_dice else 0)

    @property
    def noise_dim(self) -> int:
        """Hand noise per throw: :data:`NOISE_DIM` standard normals per die."""
        return NOISE_DIM * self.n_dice

    @property
    def hand_spacing(self) -> float:
        """Distance (m) between neighbours' centres in the hand.

        The largest die's diameter across corners plus :data:`HAND_GAP`.
        """
        return 2.0 * max(die.reach for die in self.dice) + HAND_GAP

    @property
    def hand_offsets(self) -> np.ndarray:
        """Each die's centre in the hand relative to :attr:`release_position`, (N, 3) m."""
        normal = np.asarray(self.scene.ground.normal)
        x_axis = np.cross([0.0, 1.0, 0.0], normal)
        x_axis /= np.linalg.norm(x_axis)
        y_axis = np.cross(normal, x_axis)
        n, rows = self.n_dice, -(-self.n_dice // HAND_ROW)
        offsets = np.zeros((n, 3))
        for i in range(n):
            row, column = divmod(i, HAND_ROW)
            in_row = min(HAND_ROW, n - row * HAND_ROW)
            offsets[i] = self.hand_spacing * ((row - (rows - 1) / 2) * x_axis
                                              + (column - (in_row - 1) / 2) * y_axis)
        return offsets

    @property
    def release_positions(self) -> np.ndarray:
        """Each die's centre at release, (N, 3) m."""
        return self.release_position + self.hand_offsets

    def fixed_target(self, target_face: object = None, target_sum: object = None) -> Any:
        """The episode keywords as a fixed target (None: drawn).

        "faces": ``target_face``, one face per die (a sequence of N labels); "sum":
        ``target_sum``, an int in :attr:`totals`. The other is refused.
        """
        if self.target == "faces":
            if target_sum is not None:
                raise ValueError(f"target_sum fixes the total with target='sum'; target is "
                                 f"'faces' (fix each die's face with target_face), got "
                                 f"{target_sum!r}")
            return None if target_face is None else self._check_faces(target_face)
        if target_face is not None:
            raise ValueError(f"target_face fixes each die's face with target='faces'; target "
                             f"is 'sum' (fix the total with target_sum), got {target_face!r}")
        if target_sum is None:
            return None
        if isinstance(target_sum, bool) or not isinstance(target_sum, (int, np.integer)):
            raise ValueError(f"target_sum must be an int in [{self.totals[0]}, "
                             f"{self.totals[-1]}], got {target_sum!r}")
        check_range("target_sum", int(target_sum), self.totals[0], self.totals[-1])
        return int(target_sum)

    def _check_faces(self, value: object) -> tuple[int, ...]:
        if isinstance(value, (str, bytes)) or not isinstance(value, Sequence | np.ndarray) \
                or len(value) != self.n_dice:
            raise ValueError(f"target_face must be a sequence of {self.n_dice} faces, one per "
                             f"die (faces {self.faces}), got {value!r}")
        return tuple(check_face("target_face", f, n) for f, n in zip(value, self.faces,
                                                                       strict=True))

    def sample_hand(
        self,
        rng: np.random.Generator,
        target: Any = None,
        orientation_mode: str = "uniform",
    ) -> tuple[Any, np.ndarray]:
        """One episode's context: the target (N faces, or a total) and the hands (N, 3, 3)."""
        targets, hands = self.sample_hands([rng], target, orientation_mode)
        return targets[0], hands[0]

    def sample_hands(
        self,
        rngs: Sequence[np.random.Generator],
        target: Any = None,
        orientation_mode: str = "uniform",
    ) -> tuple[np.ndarray, np.ndarray]:
        """One context per generator: targets ((n, N) faces or (n,) totals), hands (n, N, 3, 3).

        ``target``: a fixed target as :meth:`fixed_target` returns it (None: drawn uniformly:
        each die's face, or the total over :attr:`totals`). Each generator draws the target,
        then each die's orientation in turn, as one die's.
        """
        check_orientation_mode(orientation_mode)
        n, faces = len(rngs), np.array(self.faces)
        by_face = self.target == "faces"
        targets = np.zeros((n, self.n_dice) if by_face else n, np.int64)
        draws = np.zeros((self.n_dice, n, 3))
        for i, rng in enumerate(rngs):
            if target is not None:
                targets[i] = target
            elif by_face:
                targets[i] = rng.integers(1, faces + 1)
            else:
                targets[i] = rng.integers(self.totals[0], self.totals[-1] + 1)
            for j in range(self.n_dice):
                draws[j, i] = _orientation_draw(rng, orientation_mode, self.faces[j])
        hands = np.stack([_orientations(orientation_mode, draws[j], die)
                          for j, die in enumerate(self.dice)], axis=1)
        return targets, hands

    def observe(self, targets: np.ndarray, orientations: np.ndarray) -> np.ndarray:
        """Observations (n, :attr:`obs_dim`) float32: the target's one-hot(s), orientations."""
        orientations = np.asarray(orientations).reshape(-1, ORIENTATION_DIM * self.n_dice)
        n = len(orientations)
        obs = np.zeros((n, self.obs_dim), np.float32)
        if self.target == "faces":
            starts = np.cumsum([0, *self.faces[:-1]])
            obs[np.arange(n)[:, None], starts + np.asarray(targets).reshape(n, -1) - 1] = 1.0
        else:
            obs[np.arange(n), np.asarray(targets).reshape(n) - self.totals[0]] = 1.0
        obs[:, self.target_dim:] = np.clip(orientations, -1.0, 1.0)
        return obs

    @property
    def _hand_shape(self) -> tuple[int, ...]:
        return (self.n_dice, 3, 3)

    def _decode_target(self, encoding: np.ndarray) -> np.ndarray:
        if self.target == "sum":
            return encoding.argmax(axis=1) + self.totals[0]
        ends = np.cumsum(self.faces)
        return np.stack([encoding[:, end - f:end].argmax(axis=1) + 1
                         for f, end in zip(self.faces, ends, strict=True)], axis=1)

    def release(
        self, actions: np.ndarray, hands: np.ndarray, noise: np.ndarray
    ) -> tuple[GroupState, np.ndarray]:
        """Releases for ``actions`` (n, :attr:`action_dim`), ``hands`` (n, N, 3, 3), ``noise``.

        ``noise`` (n, 9 N). Returns the group's state and which actions were clipped (n,).
        """
        actions = check_actions(actions, self.action_dim)
        clipped = np.any(np.abs(actions) > 1.0, axis=1)
        actions = np.clip(actions, -1.0, 1.0)
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
        return GroupState.of([
            State.release(scene, positions[i], velocity[:, i], spin[:, i], orientation[:, i])
            for i, scene in enumerate(self.die_scenes)]), clipped

    def throw(
        self,
        actions: np.ndarray,
        targets: np.ndarray,
        hands: np.ndarray,
        noise: np.ndarray,
        *,
        record_every: int = 0,
    ) -> Throw:
        """Simulate ``n`` throws of the dice in one kernel call and score them.

        ``targets``: (n, N) faces or (n,) totals; ``hands`` (n, N, 3, 3); ``noise`` (n, 9 N).
        Info as one die's, per throw, except per die (n, N): ``face`` (0: not read),
        ``leaning``, ``impacts``, ``release_velocity`` (n, N, 3), ``release_spin`` (n, N, 3),
        ``release_orientation`` (n, N, 3, 3); ``total`` (n,) the faces' sum; ``target_face``
        (n, N) or ``target_sum`` (n,).
        """
        by_face = self.target == "faces"
        targets = np.array(targets, dtype=np.int64).reshape((-1, self.n_dice) if by_face
                                                             else (-1,))
        state, clipped = self.release(actions, hands, noise)
        decided = self.until == "decided"
        result = simulate_group(self.scene, self.dice, state, stop_when_decided=decided,
                                record_every=record_every, orientations=bool(record_every),
                                num_threads=self.num_threads)
        speed = np.linalg.norm(state.velocity, axis=2)
        spin = np.linalg.norm(state.angular_velocity, axis=2)
        fair = np.all((speed >= self.min_speed) & (spin >= self.min_spin), axis=1)
        ended = result.decided if decided else result.settled
        leaning = ~result.read
        void = void_reasons(fair, result.unstable, result.sunk.any(axis=1), ended, self.until,
                            leaning.any(axis=1))
        counts = void == ""
        total = result.face.sum(axis=1)
        if by_face:
            hit = np.all(result.face == targets, axis=1)
            normal = np.asarray(self.scene.ground.normal)
            alignment = np.mean([target_alignment(result.final.orientation[:, i], die,
                                                  targets[:, i], normal)
                                 for i, die in enumerate(self.dice)], axis=0)
        else:
            hit, alignment = total == targets, np.zeros(len(targets))
        success = counts & hit
        shaping = np.where(counts, self.shaping * alignment, 0.0)
        outcome = {"face": result.face, "total": total, "leaning": leaning,
                   "settled": result.settled, "unstable": result.unstable,
                   "sunk": result.sunk.any(axis=1),
                   "max_sink": result.max_penetration.max(axis=1)}
        return self._scored(("target_face" if by_face else "target_sum", targets), outcome,
                            success, fair, void, shaping, state, clipped, result)


def void_reasons(fair: np.ndarray, unstable: np.ndarray, sunk: np.ndarray, ended: np.ndarray,
                 until: str, leaning: np.ndarray | None = None) -> np.ndarray:
    """Why each throw does not count, (n,) strings, ``""`` where it counts.

    The first that applies of "foul" (not ``fair``), "unstable", "sunk", not ended
    (:data:`UNTIL` of ``until``) and "leaning" (a die left leaning on another).
    """
    counted = np.where(leaning, "leaning", "") if leaning is not None else ""
    return np.where(~fair, "foul", np.where(unstable, "unstable", np.where(
        sunk, "sunk", np.where(~ended, UNTIL[until], counted))))


def target_alignment(orientation: np.ndarray, die: Die, targets: np.ndarray,
                     normal: np.ndarray) -> np.ndarray:
    """``n_target . n_table`` of each throw, (n,): 1 with the target up, -1 with it down.

    ``orientation`` (n, 3, 3) the die's at the end, ``targets`` (n,) its target faces.
    """
    return np.einsum("bij,bj,i->b", orientation, die.reading[np.asarray(targets) - 1], normal)


def check_actions(actions: np.ndarray, dim: int = ACTION_DIM) -> np.ndarray:
    """Actions as a float64 (n, dim) array; NaN/inf or a wrong shape raise ``ValueError``."""
    try:
        array = np.asarray(actions, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"action must be an array of numbers, shape ({dim},) or (n, {dim}), "
                         f"got {actions!r}") from error
    if array.shape == (dim,):
        array = array[None]
    if array.ndim != 2 or array.shape[1] != dim:
        raise ValueError(f"action must have shape ({dim},) or (n, {dim}), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"action must be finite (no NaN or inf), got {actions!r}")
    return array


def check_orientation_mode(value: object) -> None:
    """``ValueError`` unless ``value`` is one of :data:`ORIENTATION_MODES`."""
    if not (isinstance(value, str) and value in ORIENTATION_MODES):
        raise ValueError(f"orientation_mode must be one of {ORIENTATION_MODES}, got {value!r}")


def check_rotation(name: str, value: object) -> np.ndarray:
    """``value`` as a (3, 3) rotation matrix, or ``ValueError`` naming ``name``."""
    rot = as_floats(name, value)
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
    num_dice: int | None = None,
    target: str | None = None,
    set_dice: bool = False,
    scene: Scene | None = None,
    **physics: Any,
) -> ThrowTask:
    """A validated :class:`ThrowTask` from flat keywords (the env's ``gym.make`` keywords).

    ``physics`` are :func:`~dice_env.envs.keywords.build_scene`'s keywords (``t_max``, ``mass``,
    ``stiffness``, ...): each one given modifies ``scene`` (default: ``Scene()`` with ``t_max``
    5 s), whose other fields are kept, so changes to the default scene flow through.

    Several dice (:class:`GroupThrowTask`): ``num_dice`` (1 … :data:`MAX_NUM_DICE`; None: 1, or
    the length of a ``die`` tuple) repeats the die; ``die`` may also be a tuple of names or
    :class:`Die`, one per die (the die keywords ``size``, ``mass``, ``load_*`` apply to each).
    ``target`` "sum" (the default for several dice) or "faces" (one die's only target);
    ``set_dice`` lets the agent set the dice in the hand. One die is today's :class:`ThrowTask`.
    """
    check_task_keywords(physics)
    dice = check_num_dice(num_dice, physics.pop("die", None))
    common = {"release_height": release_height, "max_speed": max_speed, "max_spin": max_spin,
              "hand_noise": hand_noise, "orientation_noise": orientation_noise,
              "min_speed": min_speed, "min_spin": min_spin, "shaping": shaping,
              "num_threads": num_threads, "until": until}
    if len(dice) == 1:
        if target not in (None, "faces"):
            raise ValueError(f"target must be 'faces' for one die (target='sum' needs "
                             f"num_dice >= 2), got {target!r}")
        if set_dice is not False:
            raise ValueError(f"set_dice needs num_dice >= 2, got set_dice={set_dice!r}")
        return ThrowTask(build_scene(scene, die=dice[0], **physics), **common)
    scenes = [build_scene(scene, die=die, **physics) for die in dice]
    return GroupThrowTask(scenes[0], **common, dice=tuple(s.die for s in scenes),
                          target="sum" if target is None else target, set_dice=set_dice)


def check_num_dice(num_dice: object, die: object) -> tuple[Any, ...]:
    """The ``die`` keyword per die: ``num_dice`` copies of it, or its entries if a tuple.

    ``ValueError`` naming ``num_dice`` or ``die`` for a count outside 1 … :data:`MAX_NUM_DICE`
    or a tuple whose length is not ``num_dice``.
    """
    if num_dice is not None and (isinstance(num_dice, bool) or not isinstance(
            num_dice, (int, np.integer)) or not 1 <= num_dice <= MAX_NUM_DICE):
        raise ValueError(f"num_dice must be an int in [1, {MAX_NUM_DICE}], got {num_dice!r}")
    if not isinstance(die, (tuple, list)):
        return (die,) * (1 if num_dice is None else int(num_dice))
    if not 1 <= len(die) <= MAX_NUM_DICE:
        raise ValueError(f"die must be a name, a Die, or a tuple of 1 to {MAX_NUM_DICE} of "
                         f"them, got {len(die)} entries")
    if num_dice is not None and len(die) != num_dice:
        raise ValueError(f"die must hold num_dice={num_dice} dice, got {len(die)}: {die!r}")
    return tuple(die)


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


def _rotation_matrices(vectors: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of rotation vectors (..., 3)."""
    shape = np.shape(vectors)[:-1]
    quaternions = _rotation_vector_quaternion(np.reshape(vectors, (-1, 3)))
    return quaternion_to_matrix(quaternions).reshape(*shape, 3, 3)


def _rotation_vector_quaternion(vectors: np.ndarray) -> np.ndarray:
    """Unit quaternions (n, 4), (w, x, y, z), of rotations by rotation vectors (n, 3)."""
    angle = np.linalg.norm(vectors, axis=1, keepdims=True)
    safe = np.where(angle > 0, angle, 1.0)
    return np.hstack([np.cos(angle / 2), np.sin(angle / 2) * vectors / safe])


def _orientation_draw(rng: np.random.Generator, mode: str, n_faces: int) -> np.ndarray:
    """The draws (3,) of one hand orientation: three uniforms, a face and a turn, or none."""
    draw = np.zeros(3)
    if mode == "uniform":
        draw[:] = rng.random(3)
    elif mode == "flat":
        draw[0] = rng.integers(0, n_faces)
        draw[1] = rng.uniform(0, 2 * np.pi)
    return draw


def _orientations(mode: str, draws: np.ndarray, die: Die) -> np.ndarray:
    """Hand orientations (n, 3, 3) of ``die`` from :func:`_orientation_draw`'s draws (n, 3)."""
    if mode == "uniform":
        return uniform_rotations(draws.T)
    if mode == "flat":
        return np.stack([_z_turn(turn) @ face_up_rotation(die, int(f) + 1)
                         for f, turn, _ in draws])
    return np.tile(np.eye(3), (len(draws), 1, 1))


def _z_turn(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def face_up_rotation(die: Die, face: int) -> np.ndarray:
    """An orientation (body to world, 3x3) in which ``die`` reads ``face`` (a label).

    The face's reading direction (:attr:`Die.reading`) points to world +z
    (:func:`dice_env.rotations.up_rotation`).
    """
    return up_rotation(die.reading[check_face("face", face, die.n_faces) - 1])

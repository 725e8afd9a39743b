"""The DiceThrow task over a batch: a hand, a target, a judged landing, a reward.

The :class:`~dice_env.envs.hand.TaskHand` turns actions into releases, the kernel runs them,
:func:`judge` says which throws count and the :class:`~dice_env.envs.targets.Target` scores them.
Every env and the oracle share this path (:meth:`ThrowTask.sample_hand`, then
:meth:`ThrowTask.throw`). World frame, z up.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from functools import cached_property
from typing import Any

import numpy as np

from dice_env.envs.hand import ORIENTATION_MODES, TaskHand, default_release_height
from dice_env.envs.keywords import ENV_MAX_STEPS, SceneKeywords, check_scene
from dice_env.envs.targets import TARGETS, Target
from dice_env.model.checks import as_floats, check_choice, check_int, check_nonnegative
from dice_env.model.die import Die
from dice_env.model.rotations import orthonormality_error
from dice_env.model.scene import Scene
from dice_env.simulation.group import (
    GroupResult,
    GroupState,
    group_step,
    pair_step,
    simulate_group,
)
from dice_env.simulation.simulate import (
    LOCK_MARGIN,
    UP,
    Result,
    State,
    lock_energy,
    simulate,
)

ORIENTATION_DIM = 9  # the observation's orientation, row-major 3x3, after the target's one-hot
# How far a throw is simulated -> the void reason of one that does not get there in t_max.
UNTIL = {"rest": "not_settled", "decided": "not_decided"}
MAX_NUM_DICE = 12


@dataclass(frozen=True)
class ThrowTask:
    """A throw of N dice from the hand: how actions become releases and how a landing is scored.

    ``dice``: 1 … :data:`MAX_NUM_DICE` dice (default: the scene's die; the scene takes the
    first). Per-die arrays have a die axis only for several dice. ``release_height=None`` is
    :func:`~dice_env.envs.hand.default_release_height`. The hand's fields make :attr:`hand`,
    ``target`` names :attr:`goal`'s kind. Every field, the hand, the targets and void throws:
    ``docs/environment.md``.
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
    until: str = "rest"
    dice: tuple[Die, ...] = ()
    target: str | None = None
    set_dice: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.scene, Scene):
            raise ValueError(f"scene must be a Scene, got {type(self.scene).__name__}")
        self._check_dice()
        if self.release_height is None:
            object.__setattr__(self, "release_height", default_release_height(self.dice))
        hand = self.hand  # checks the hand's fields
        for name in ("min_speed", "min_spin", "shaping"):
            check_nonnegative(name, getattr(self, name))
        check_choice("until", self.until, UNTIL)
        if self.until == "decided" and not all(np.isfinite(lock_energy(s)).all()
                                               for s in self.die_scenes):
            raise ValueError("until='decided' needs a horizontal table with gravity (no energy "
                             "bound decides the face on a slope); use until='rest'")
        for scene in self.die_scenes:
            check_scene(scene, self.release_height)
        near = pair_step(self.scene, self.dice)  # a move with dice within reach: the shortest
        if self.scene.t_max / near > ENV_MAX_STEPS:
            raise ValueError(
                f"t_max must be at most {ENV_MAX_STEPS:.0e} steps: t_max={self.scene.t_max:g} s "
                f"over the {self.n_dice} dice's step of {near:.3g} s is "
                f"{self.scene.t_max / near:.3g} steps; lower t_max or num_dice")
        hand.check_walls()

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
    def hand(self) -> TaskHand:
        """The hand: actions to releases, from the task's hand fields."""
        return TaskHand(self.die_scenes, self.release_height, max_speed=self.max_speed,
                        max_spin=self.max_spin, hand_noise=self.hand_noise,
                        orientation_noise=self.orientation_noise, set_dice=self.set_dice)

    @cached_property
    def goal(self) -> Target:
        """The target of the ``target`` kind over the dice's faces."""
        return TARGETS[self.target](self.faces)

    @cached_property
    def die_scenes(self) -> tuple[Scene, ...]:
        """The scene with each die of :attr:`dice` (the first is :attr:`scene`)."""
        return (self.scene, *(self.scene.with_(die=die) for die in self.dice[1:]))

    @cached_property
    def step(self) -> float:
        """The unit of a throw's steps (s): one die's step; for several, :func:`group_step`."""
        return group_step(self.scene, self.dice)

    @property
    def n_dice(self) -> int:
        """Dice per throw."""
        return len(self.dice)

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
        """One throw's target: a face per die (the hand's ``die_shape``) or a total (())."""
        return self.goal.shape

    @property
    def action_dim(self) -> int:
        """The hand's velocity and spin, and 3 per die with ``set_dice``."""
        return self.hand.action_dim

    @property
    def obs_dim(self) -> int:
        """Observation size: the target's encoding and each die's orientation (9 per die)."""
        return self.goal.dim + ORIENTATION_DIM * self.n_dice

    @property
    def hand_position(self) -> np.ndarray:
        """The dice's centres in the hand as a pose's position: (3,) for one die, (N, 3)."""
        return self.hand.positions.reshape(*self.hand.die_shape, 3)

    def sample_hand(self, rng: np.random.Generator, target: Any = None,
                    orientation_mode: str = "uniform") -> tuple[Any, np.ndarray]:
        """One episode's target and hand (3, 3), or hands (N, 3, 3), as :meth:`sample_hands`."""
        targets, hands = self.sample_hands([rng], target, orientation_mode)
        return targets[0].tolist() if targets.ndim == 1 else targets[0], hands[0]

    def sample_hands(self, rngs: Sequence[np.random.Generator], target: Any = None,
                     orientation_mode: str = "uniform") -> tuple[np.ndarray, np.ndarray]:
        """One context per generator: targets (n, :attr:`target_shape`), hands (n, N, 3, 3).

        ``target``: fixed (as :attr:`goal`'s ``fix`` returns it) or None (drawn uniformly);
        ``orientation_mode``: "uniform" (all rotations), "flat" (a uniform face up and turn) or
        "identity". Each generator draws the target, then each die's orientation in turn.
        """
        check_choice("orientation_mode", orientation_mode, ORIENTATION_MODES)
        n = len(rngs)
        targets = np.zeros((n, math.prod(self.target_shape)), np.int64)
        draws = np.zeros((n, self.n_dice, 3))
        for i, rng in enumerate(rngs):
            targets[i] = self.goal.draw(rng) if target is None else target
            draws[i] = self.hand.draw(rng, orientation_mode)
        hands = self.hand.orientations(orientation_mode, draws)
        return (targets.reshape(n, *self.target_shape),
                hands.reshape(n, *self.hand.die_shape, 3, 3))

    def sample_noise(self, rng: np.random.Generator, n: int = 1) -> np.ndarray:
        """Hand noise for ``n`` throws: standard normals (n, the hand's ``noise_dim``)."""
        return self.hand.sample_noise(rng, n)

    def observe(self, targets: np.ndarray, orientations: np.ndarray) -> np.ndarray:
        """Observations (n, :attr:`obs_dim`) float32: the target's one-hot(s), orientations."""
        orientations = np.asarray(orientations).reshape(-1, ORIENTATION_DIM * self.n_dice)
        n = len(orientations)
        obs = np.zeros((n, self.obs_dim), np.float32)
        obs[np.arange(n)[:, None], self.goal.columns(targets)] = 1.0
        obs[:, self.goal.dim:] = np.clip(orientations, -1.0, 1.0)
        return obs

    def decode(self, observations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Targets and hands (the nearest rotations) from :meth:`observe`'s observations."""
        observations = np.atleast_2d(np.asarray(observations, dtype=np.float64))
        if observations.shape[1] != self.obs_dim:
            raise ValueError(f"observations must have {self.obs_dim} columns, got "
                             f"{observations.shape[1]}")
        u, _, vt = np.linalg.svd(observations[:, self.goal.dim:].reshape(-1, 3, 3))
        return (self.goal.decode(observations[:, :self.goal.dim]),
                (u @ vt).reshape(len(observations), *self.hand.die_shape, 3, 3))

    def release(self, actions: np.ndarray, hands: np.ndarray,
                noise: np.ndarray | Sequence[np.random.Generator], *,
                action_shape: tuple[int, ...] | None = None,
                ) -> tuple[State | GroupState, np.ndarray]:
        """The hand's releases: :meth:`TaskHand.release <dice_env.envs.hand.TaskHand.release>`."""
        return self.hand.release(actions, hands, noise, action_shape=action_shape)

    def fair(self, state: State | GroupState) -> np.ndarray:
        """Whether each release (n,) is within ``min_speed`` and ``min_spin``, every die's."""
        n = np.size(state.velocity) // (3 * self.n_dice)
        speed = np.linalg.norm(state.velocity, axis=-1).reshape(n, -1)
        spin = np.linalg.norm(state.angular_velocity, axis=-1).reshape(n, -1)
        return np.all((speed >= self.min_speed) & (spin >= self.min_spin), axis=1)

    def land(self, state: State | GroupState, targets: np.ndarray, *, record_every: int = 0,
             num_threads: int | None = None, device: str = "cpu") -> Landing:
        """Simulate the released dice (:attr:`run_until`) and judge each throw (:func:`judge`).

        ``targets`` (n, :attr:`target_shape`); ``num_threads``: the kernel's threads (None:
        all); ``device``: ``simulate``'s (one die only); ``record_every`` > 0 records the centres
        and orientations every that many steps.
        """
        fair = self.fair(state)
        targets = np.array(targets, dtype=np.int64).reshape(len(fair), *self.target_shape)
        run = self._simulate(state, record_every, num_threads, device)
        result, void = judge(self.scene, self.dice, run, self.run_until, fair=fair)
        return Landing(targets, result, void, fair)

    def success(self, landing: Landing) -> np.ndarray:
        """Whether each throw (n,) counts and hits its target."""
        return (landing.void == "") & self.goal.hit(landing.faces, landing.targets)

    def reward(self, landing: Landing) -> Reward:
        """Each throw's reward, in its terms: success (1 or 0) and shaping at rest."""
        alignment = self.goal.alignment(self.dice, np.asarray(self.scene.ground.normal),
                                        landing.orientation, landing.targets)
        return Reward(self.success(landing).astype(np.float64),
                      np.where(landing.void == "", self.shaping * alignment, 0.0))

    def info(self, landing: Landing, reward: Reward, state: State | GroupState,
             clipped: np.ndarray) -> dict[str, np.ndarray]:
        """The env's info over n throws (``docs/environment.md``); per-die keys with a die axis."""
        result, n = landing.result, len(landing.void)
        several = ({"total": landing.faces.sum(axis=1), "leaning": ~result.read}
                   if self.n_dice > 1 else {})
        return {"is_success": self.success(landing), self.goal.info_key: landing.targets,
                "face": result.face, **several, "settled": result.settled,
                "unstable": result.unstable, "sunk": result.sunk.reshape(n, -1).any(axis=1),
                "max_sink": result.max_penetration.reshape(n, -1).max(axis=1),
                "fair": landing.fair, "void_reason": landing.void, "rest_time": result.rest_time,
                "impacts": result.impacts, "reward_success": reward.success,
                "reward_shaping": reward.shaping, "release_velocity": state.velocity,
                "release_spin": state.angular_velocity, "release_orientation": state.orientation,
                "action_clipped": clipped}

    def throw(self, actions: np.ndarray, targets: np.ndarray, hands: np.ndarray,
              noise: np.ndarray | Sequence[np.random.Generator], *, record_every: int = 0,
              action_shape: tuple[int, ...] | None = None,
              num_threads: int | None = None, device: str = "cpu") -> Throw:
        """Release, simulate in one kernel call, judge and score ``n`` throws of the dice.

        ``targets`` (n, :attr:`target_shape`), the rest as :meth:`release`'s and :meth:`land`'s.
        """
        state, clipped = self.release(actions, hands, noise, action_shape=action_shape)
        landing = self.land(state, targets, record_every=record_every, num_threads=num_threads,
                            device=device)
        reward = self.reward(landing)
        return Throw(reward=reward.total, info=self.info(landing, reward, state, clipped),
                     result=landing.result,
                     observation=self.observe(landing.targets, landing.result.final.orientation))

    @property
    def run_until(self) -> str:
        """The kernel's ``until``: ``"early_rest"`` for one die to rest (the same face, faster)."""
        return "early_rest" if self.until == "rest" and self.n_dice == 1 else self.until

    def _simulate(self, state: State | GroupState, record_every: int,
                  num_threads: int | None, device: str) -> Result | GroupResult:
        """The kernel's run of the released dice (:attr:`run_until`): one die's, or the group's."""
        if isinstance(state, GroupState):
            check_choice("device", device, ("cpu",))  # several dice: the CPU's kernel only
            return simulate_group(self.scene, self.dice, state, until=self.run_until,
                                  record_every=record_every, orientations=bool(record_every),
                                  num_threads=num_threads)
        return simulate(self.scene, state, until=self.run_until, record_every=record_every,
                        record=("orientations",) if record_every else ("energy",),
                        num_threads=num_threads, device=device)


@dataclass(frozen=True)
class Landing:
    """n throws judged: their targets, the kernel's result and why each does not count.

    ``targets`` (n, target shape); ``void`` (n,): :func:`judge`'s reasons, ``""`` where the
    throw counts; ``fair`` (n,): releases within the task's speed and spin.
    """

    targets: np.ndarray
    result: Result | GroupResult
    void: np.ndarray
    fair: np.ndarray

    @property
    def faces(self) -> np.ndarray:
        """The face each die reads, (n, N)."""
        return self.result.face.reshape(len(self.void), -1)

    @property
    def orientation(self) -> np.ndarray:
        """Each die's orientation at the end, (n, N, 3, 3)."""
        return self.result.final.orientation.reshape(len(self.void), -1, 3, 3)


@dataclass(frozen=True)
class Reward:
    """n throws' reward terms, (n,) each: ``success`` (1.0 or 0.0) and ``shaping``."""

    success: np.ndarray
    shaping: np.ndarray

    @property
    def total(self) -> np.ndarray:
        """The reward: success + shaping."""
        return self.success + self.shaping


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
    rest's ``settled`` as if the hold were waited out) and why each throw does not count, (n,):
    ``""`` or the first of "foul", "unstable", "sunk", :data:`UNTIL`'s reason, "leaning" and
    "not_decided" (a face :func:`decided_reads` does not read).
    """
    if until == "early_rest":  # not settled where the hold (its quiet steps) ends after t_max
        dt = scene.step
        n_steps = max(1, round((scene.t_max if t_max is None else t_max) / dt))
        late = result.settled & (np.rint(result.rest_time / dt) + 1
                                 + math.ceil(scene.rest.hold / dt) > n_steps)
        if late.any():
            result = replace(result, settled=result.settled & ~late,
                             rest_time=np.where(late, n_steps * dt, result.rest_time))
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

    Its reading direction must beat every other face's along up by
    :data:`~dice_env.simulation.simulate.LOCK_MARGIN` of what it beats its nearest neighbour's by
    when read straight up (a die on a steep table or cocked against a wall may fall short).
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
    die = keywords.pop("die", None)
    if num_dice is not None:
        check_int("num_dice", num_dice, 1, MAX_NUM_DICE)
    if not isinstance(die, (tuple, list)):
        die = (die,) * (1 if num_dice is None else int(num_dice))
    elif not 1 <= len(die) <= MAX_NUM_DICE:
        raise ValueError(f"die must be a name, a Die, or a tuple of 1 to {MAX_NUM_DICE} of "
                         f"them, got {len(die)} entries")
    elif num_dice is not None and len(die) != num_dice:
        raise ValueError(f"die must hold num_dice={num_dice} dice, got {len(die)}: {die!r}")
    scenes = [SceneKeywords(die=one, **keywords).build(scene) for one in die]
    return ThrowTask(scene=scenes[0], dice=tuple(s.die for s in scenes), **fields_given)


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
                         "orientation_mode, render_mode, render_width, render_height, "
                         "num_threads, device")
    return keywords

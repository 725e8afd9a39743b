"""A recorded throw: its scene, dice, release state and frames, as data that replays exactly."""

from __future__ import annotations

import importlib.metadata
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from dice_env.envs.throw_task import judge
from dice_env.model.checks import check_choice, check_type
from dice_env.model.die import Die
from dice_env.model.rotations import (
    matrix_to_quaternion,
    orthonormality_error,
    quaternion_to_matrix,
)
from dice_env.model.scene import Scene
from dice_env.simulation.codec import from_data, to_data
from dice_env.simulation.group import (
    GROUP_UNTIL,
    DieContact,
    GroupState,
    group_steps,
    simulate_group,
)
from dice_env.simulation.simulate import (
    ENDINGS,
    MAX_RECORD_BYTES,
    ROTATION_TOL,
    State,
    ending,
    simulate,
)

FORMAT = "dice_env.throw"  # what a file holding recordings says it holds
FPS = 60.0  # frames per simulated second, by default
FPS_RANGE = (1.0, 1000.0)  # frames per simulated second a recording may have
MAX_FRAMES = 100_000  # frames of one throw (all dice), against a page or an export too large
STATE_FIELDS = ("position", "velocity", "angular_momentum", "orientation", "angular_velocity")
DATA_FIELDS = ("format", "version", "title", "scene", "dice", "contact", "run", "fps", "release",
               "t", "position", "quaternion", "outcome")  # what Recording.to_data writes
RECORD_FLOATS = 12  # floats recorded a die a frame: its centre (3) and orientation (9)


def library_version() -> str:
    """The installed dice_env's version."""
    return importlib.metadata.version("dice_env")


@dataclass(frozen=True)
class Recording:
    """One throw of one or more dice, as recorded.

    ``release``: a :class:`GroupState` of one throw; ``run``: its keywords (``t_max``,
    ``until``). Frames from the release to the end: ``t`` (n,), ``position`` (n, N, 3),
    ``orientation`` (n, N, 3, 3) body to world. ``outcome``: ``faces``, ``read`` (False: a die
    leaning on another), ``settled``, ``decided``, ``unstable``, ``sunk``, ``time`` (s) and
    ``void`` (``""`` where the throw counts, else why not, as the env's ``void_reason``).
    Built only of consistent parts: frames one a time (time from 0, strictly increasing), one
    position and rotation a die, finite numbers, ``fps`` in :data:`FPS_RANGE`.
    """

    scene: Scene
    dice: tuple[Die, ...]
    contact: DieContact
    release: GroupState
    run: dict[str, Any]
    fps: float
    t: np.ndarray
    position: np.ndarray
    orientation: np.ndarray
    outcome: dict[str, Any]
    title: str = ""
    version: str = field(default_factory=library_version)

    def __post_init__(self) -> None:
        """Refuse (``ValueError``, ``TypeError``) what no throw records, naming what is wrong."""
        check_type("scene", self.scene, Scene)
        check_type("contact", self.contact, DieContact)
        if (not isinstance(self.dice, tuple) or not self.dice
                or not all(isinstance(die, Die) for die in self.dice)):
            raise TypeError(f"dice must be a non-empty tuple of Die, got {self.dice!r:.80}")
        for name in ("title", "version"):
            check_type(name, getattr(self, name), str)
        n, run, outcome = self.n_dice, self.run, self.outcome
        if not isinstance(run, dict) or set(run) != {"t_max", "until"}:
            raise ValueError(f"run must be {{'t_max': ..., 'until': ...}}, got {run!r:.80}")
        t_max = run["t_max"]
        if t_max is not None and (not isinstance(t_max, (int, float)) or isinstance(t_max, bool)
                                  or not 0 < t_max < math.inf):
            raise ValueError(f"run's t_max must be None or a finite time > 0 (s), got {t_max!r}")
        check_choice("run's until", run["until"], tuple(ENDINGS) if n == 1 else GROUP_UNTIL)
        object.__setattr__(self, "fps", check_fps(self.fps))
        check_type("release", self.release, GroupState)
        for name in STATE_FIELDS:
            array = getattr(self.release, name)
            tail = (3, 3) if name == "orientation" else (3,)
            if array.shape != (1, n, *tail) or not np.all(np.isfinite(array)):
                raise ValueError(f"release {name} must be finite, shape {(1, n, *tail)} for "
                                 f"{n} dice, got shape {array.shape}")
        check_frames(self.t, self.position, self.orientation, n)
        check_type("outcome", outcome, dict)
        faces = outcome.get("faces")
        if (not isinstance(faces, list) or len(faces) != n
                or not all(type(face) is int for face in faces)):
            raise ValueError(f"outcome's faces must be a list of {n} ints (one a die), got "
                             f"{faces!r:.80}")
        check_type("outcome's void", outcome.get("void"), str)

    @property
    def n_dice(self) -> int:
        """Dice in the throw."""
        return len(self.dice)

    def to_data(self) -> dict[str, Any]:
        """JSON data of the recording: the frames as quaternions (w, x, y, z), the rest exact."""
        return {
            "format": FORMAT, "version": self.version, "title": self.title,
            "scene": to_data(self.scene), "dice": to_data(self.dice),
            "contact": to_data(self.contact), "run": dict(self.run), "fps": self.fps,
            "release": {name: getattr(self.release, name)[0].tolist() for name in STATE_FIELDS},
            "t": self.t.tolist(), "position": self.position.tolist(),
            "quaternion": matrix_to_quaternion(self.orientation).tolist(),
            "outcome": self.outcome,
        }

    @classmethod
    def from_data(cls, data: dict[str, Any]) -> Recording:
        """The recording :meth:`to_data` wrote (its orientations from the quaternions).

        Data that is no such recording is refused with a ``ValueError`` or ``TypeError`` naming
        what is wrong, before anything is built of it.
        """
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            raise ValueError(f"data must be a recording ({{'format': {FORMAT!r}, ...}}), got "
                             f"{str(data)[:80]!r}")
        _check_keys("a recording", data, DATA_FIELDS)
        _check_keys("a recording's release", data["release"], STATE_FIELDS)
        release = GroupState(*(_floats(f"release {name}", data["release"][name])[None]
                               for name in STATE_FIELDS))
        quaternion = _floats("quaternion", data["quaternion"])
        with np.errstate(over="ignore"):  # beyond 1e154, |q| is inf: refused below
            norm = np.linalg.norm(quaternion, axis=-1) if quaternion.ndim else np.nan
        if quaternion.shape[-1:] != (4,) or np.max(np.abs(norm - 1), initial=0) > 1e-9 \
                or not np.all(np.isfinite(norm)):
            raise ValueError("quaternion must hold finite unit quaternions (..., 4), got shape "
                             f"{quaternion.shape}")
        return cls(scene=from_data(data["scene"]), dice=from_data(data["dice"]),
                   contact=from_data(data["contact"]), release=release,
                   run=_run_keywords(data["run"]), fps=data["fps"],
                   t=_floats("t", data["t"]), position=_floats("position", data["position"]),
                   orientation=quaternion_to_matrix(quaternion),
                   outcome=dict(data["outcome"]) if isinstance(data["outcome"], dict)
                   else data["outcome"], title=data["title"], version=data["version"])


def check_fps(fps: object, limit: float | None = None) -> float:
    """``fps`` in :data:`FPS_RANGE` and, given a time ``limit`` (s), at least ``1 / limit``.

    Returns it as a float; ``ValueError`` naming ``fps`` and its range otherwise.
    """
    low, high = FPS_RANGE
    short = limit is not None and 1.0 / limit > low  # a time limit shorter than a frame
    low = 1.0 / limit if short else low
    if (not isinstance(fps, (int, float, np.integer, np.floating)) or isinstance(fps, bool)
            or not low <= fps <= high):
        also = f" (at least one frame by t_max = {limit:g} s)" if short else ""
        raise ValueError(f"fps must be in [{low:g}, {high:g}] frames per simulated second"
                         f"{also}, got {fps!r:.80}")
    return float(fps)


def check_frames(t: np.ndarray, position: np.ndarray, orientation: np.ndarray,
                 n_dice: int) -> None:
    """Refuse (``ValueError``) frames that are no throw's, naming what is wrong.

    ``t`` (n,) from 0, strictly increasing; every die's centre ``position`` (n, n_dice, 3) and
    rotation ``orientation`` (n, n_dice, 3, 3); all finite float64.
    """
    arrays = {"t": t, "position": position, "orientation": orientation}
    for name, array in arrays.items():
        if not isinstance(array, np.ndarray) or array.dtype != np.float64:
            raise TypeError(f"{name} must be a float64 array, got {type(array).__name__}")
    if t.ndim != 1 or len(t) < 1:
        raise ValueError(f"t must hold one time or more (shape (n,)), got shape {t.shape}")
    for name, tail in (("position", (n_dice, 3)), ("orientation", (n_dice, 3, 3))):
        if arrays[name].shape != (len(t), *tail):
            raise ValueError(f"{name} must have shape {(len(t), *tail)} ({len(t)} times of t, "
                             f"{n_dice} dice), got {arrays[name].shape}")
    for name, array in arrays.items():
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{name} must be finite (no NaN or inf)")
    if t[0] != 0 or np.any(np.diff(t) <= 0):
        raise ValueError("t must start at 0 and increase strictly, frame after frame")
    worst = float(np.max(orthonormality_error(orientation)))
    if worst > ROTATION_TOL:
        raise ValueError(f"orientation must hold rotation matrices (R R^T = I, det R = +1, to "
                         f"{ROTATION_TOL:g}), got an error of {worst:.3g}")


def max_throws(scene: Scene, dice: Sequence[Die], *, fps: float = FPS,
               contact: DieContact = DieContact(), t_max: float | None = None) -> int:
    """The most throws :func:`record` records at once: their frames fit ``MAX_RECORD_BYTES``."""
    _, stride, n_steps = run_plan(scene, dice, contact, fps, t_max)
    return MAX_RECORD_BYTES // (8 * RECORD_FLOATS * len(dice) * max(1, n_steps // stride))


def record(scene: Scene, dice: Die | Sequence[Die], state: State | GroupState, *,
           fps: float = FPS, contact: DieContact = DieContact(), t_max: float | None = None,
           until: str = "rest", titles: Sequence[str] | None = None,
           voids: Sequence[str] | None = None) -> list[Recording]:
    """Simulate the throws of ``state`` and record each at ``fps`` frames per simulated second.

    ``dice``: one die (``state`` a :class:`State`; it replaces the scene's die) or several
    (``state`` a :class:`GroupState`, run by :func:`dice_env.simulation.group.simulate_group`
    with ``contact``). ``titles`` and ``voids`` (one per throw): captions and void reasons that
    override the simulation's (``""`` keeps it). ``fps``: in :data:`FPS_RANGE`, and at least
    one frame by the time limit. Returns one recording a throw.
    """
    single = isinstance(dice, Die)
    dice = (dice,) if single else tuple(dice)
    if not isinstance(state, State if single else GroupState):
        raise TypeError("state must be a State for one die and a GroupState for several, got "
                        f"a {type(state).__name__} for {len(dice)} dice")
    ending(until, tuple(ENDINGS) if single else GROUP_UNTIL)
    release = GroupState.of([state]) if single else state.copy()
    dt, stride, n_steps = run_plan(scene, dice, contact, fps, t_max)
    if n_steps // stride * len(dice) > MAX_FRAMES:
        raise ValueError(f"t_max={n_steps * dt:g} s at fps={fps:g} records more than "
                         f"{MAX_FRAMES} die frames a throw: lower fps or t_max")
    count = release.batch_size
    titles = [""] * count if titles is None else list(titles)
    voids = [""] * count if voids is None else list(voids)
    if len(titles) != count or len(voids) != count:
        raise ValueError(f"titles and voids must hold one entry per throw ({count}), got "
                         f"{len(titles)} and {len(voids)}")
    if len(dice) == 1:
        own = scene.with_(die=dice[0])  # the scene the run has
        result = simulate(own, release.die(0), t_max=t_max, until=until, record_every=stride,
                          record=("orientations",))
        faces, read = result.face[:, None], np.ones((len(result.face), 1), bool)
        sunk = result.sunk[:, None]
    else:
        own = scene
        result = simulate_group(scene, dice, release, contact=contact, t_max=t_max, until=until,
                                record_every=stride, orientations=True)
        faces, read, sunk = result.face, result.read, result.sunk
    result, own_voids = judge(own, dice, result, until, t_max=t_max)
    recordings = []
    for b in range(count):
        frames = min(result.x_cm.shape[1], -(-int(result.steps[b]) // stride))
        shape = (frames, len(dice), 3)  # one die's frames get their die axis
        outcome = {
            "faces": faces[b].tolist(), "read": read[b].tolist(),
            "settled": bool(result.settled[b]), "decided": bool(result.decided[b]),
            "unstable": bool(result.unstable[b]), "sunk": bool(sunk[b].any()),
            "time": float(result.steps[b] * (result.t[0] / stride)),
            "void": voids[b] or str(own_voids[b])}
        recordings.append(Recording(
            scene=own if single else scene, dice=dice, contact=contact,
            release=GroupState(*(getattr(release, name)[b:b + 1] for name in STATE_FIELDS)),
            run={"t_max": t_max, "until": until}, fps=fps,
            t=np.arange(frames + 1) * (stride * dt),
            position=np.concatenate([release.position[b:b + 1],
                                     result.x_cm[b, :frames].reshape(shape)]),
            orientation=np.concatenate([release.orientation[b:b + 1],
                                        result.orientations[b, :frames].reshape(*shape, 3)]),
            outcome=outcome, title=titles[b]))
    return recordings


def as_data(recordings: Recording | Sequence[Recording]) -> list[dict[str, Any]]:
    """JSON data of one recording or several (a list, in order)."""
    items = [recordings] if isinstance(recordings, Recording) else list(recordings)
    if not items or not all(isinstance(r, Recording) for r in items):
        raise TypeError("recordings must be a Recording or a non-empty sequence of them")
    return [r.to_data() for r in items]


def run_plan(scene: Scene, dice: Sequence[Die], contact: DieContact, fps: object,
             t_max: float | None) -> tuple[float, int, int]:
    """The step (s), the steps a frame and the steps to the time limit of a recorded run."""
    fps = check_fps(fps, scene.t_max if t_max is None else t_max)
    dt, n_steps = group_steps(scene, dice, t_max, contact)
    return dt, max(1, round(1.0 / (fps * dt))), n_steps


def _run_keywords(run: dict[str, Any]) -> dict[str, Any]:
    """A recording's run keywords, those of a file from before ``until`` converted to it."""
    if not isinstance(run, dict):
        raise TypeError(f"run must be a dict of keywords, got {type(run).__name__}")
    if "until" in run:
        return dict(run)
    _check_keys("an old recording's run", run, ("t_max", "stop_when_decided", "early_rest"))
    until = ("decided" if run["stop_when_decided"] else
             "early_rest" if run["early_rest"] else "rest")
    return {"t_max": run["t_max"], "until": until}


def _check_keys(what: str, data: object, keys: Sequence[str]) -> None:
    """Refuse ``data`` unless it is a dict holding every one of ``keys``."""
    if not isinstance(data, dict):
        raise TypeError(f"{what} must be a dict, got {type(data).__name__}")
    missing = [key for key in keys if key not in data]
    if missing:
        raise ValueError(f"{what} must hold {', '.join(keys)}; missing {', '.join(missing)}")


def _floats(name: str, value: object) -> np.ndarray:
    """``value`` as a float64 array, or ``ValueError`` naming ``name`` (without the value)."""
    try:
        return np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as error:
        raise ValueError(f"{name} must be an array of numbers ({error})") from None

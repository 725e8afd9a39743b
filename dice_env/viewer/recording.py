"""A recorded throw: its scene, dice, release state and frames, as data that replays exactly."""

from __future__ import annotations

import importlib.metadata
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from dice_env.envs.task import void_reasons
from dice_env.model.die import Die
from dice_env.model.rotations import matrix_to_quaternion, quaternion_to_matrix
from dice_env.model.scene import Scene
from dice_env.simulation.codec import from_data, to_data
from dice_env.simulation.group import (
    GROUP_UNTIL,
    DieContact,
    GroupState,
    group_step,
    simulate_group,
)
from dice_env.simulation.simulate import ENDINGS, State, ending, simulate

FORMAT = "dice_env.throw"  # what a file holding recordings says it holds
FPS = 60.0  # frames per simulated second, by default
MAX_FRAMES = 100_000  # frames of one throw (all dice), against a page or an export too large
STATE_FIELDS = ("position", "velocity", "angular_momentum", "orientation", "angular_velocity")


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
        """The recording :meth:`to_data` wrote (its orientations from the quaternions)."""
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            raise ValueError(f"data must be a recording ({{'format': {FORMAT!r}, ...}}), got "
                             f"{str(data)[:80]!r}")
        release = GroupState(*(np.array(data["release"][name], dtype=np.float64)[None]
                               for name in STATE_FIELDS))
        return cls(scene=from_data(data["scene"]), dice=from_data(data["dice"]),
                   contact=from_data(data["contact"]), release=release,
                   run=_run_keywords(data["run"]),
                   fps=float(data["fps"]), t=np.array(data["t"], dtype=np.float64),
                   position=np.array(data["position"], dtype=np.float64),
                   orientation=quaternion_to_matrix(np.array(data["quaternion"])),
                   outcome=dict(data["outcome"]), title=str(data["title"]),
                   version=str(data["version"]))


def record(scene: Scene, dice: Die | Sequence[Die], state: State | GroupState, *,
           fps: float = FPS, contact: DieContact = DieContact(), t_max: float | None = None,
           until: str = "rest", titles: Sequence[str] | None = None,
           voids: Sequence[str] | None = None) -> list[Recording]:
    """Simulate the throws of ``state`` and record each at ``fps`` frames per simulated second.

    ``dice``: one die (``state`` a :class:`State`; it replaces the scene's die) or several
    (``state`` a :class:`GroupState`, run by :func:`dice_env.simulation.group.simulate_group`
    with ``contact``). ``titles`` and ``voids`` (one per throw): captions and void reasons that
    override the simulation's (``""`` keeps it). Returns one recording a throw.
    """
    single = isinstance(dice, Die)
    dice = (dice,) if single else tuple(dice)
    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a finite number > 0, got {fps!r}")
    if not isinstance(state, State if single else GroupState):
        raise TypeError("state must be a State for one die and a GroupState for several, got "
                        f"a {type(state).__name__} for {len(dice)} dice")
    ending(until, tuple(ENDINGS) if single else GROUP_UNTIL)
    release = GroupState.of([state]) if single else state.copy()
    dt = group_step(scene, dice, contact)
    stride = max(1, round(1.0 / (fps * dt)))
    limit = scene.t_max if t_max is None else t_max
    if limit / (stride * dt) * len(dice) > MAX_FRAMES:
        raise ValueError(f"t_max={limit:g} s at fps={fps:g} records more than {MAX_FRAMES} "
                         "die frames a throw: lower fps or t_max")
    run = {"t_max": t_max, "until": until}
    result, outcomes = _simulate(scene, dice, release, contact, stride, run)
    count = release.batch_size
    titles = [""] * count if titles is None else list(titles)
    voids = [""] * count if voids is None else list(voids)
    if len(titles) != count or len(voids) != count:
        raise ValueError(f"titles and voids must hold one entry per throw ({count}), got "
                         f"{len(titles)} and {len(voids)}")
    recordings = []
    for b in range(count):
        frames = min(result.x_cm.shape[1], -(-int(result.steps[b]) // stride))
        shape = (frames, len(dice), 3)  # one die's frames get their die axis
        outcome = outcomes[b] | ({"void": voids[b]} if voids[b] else {})
        recordings.append(Recording(
            scene=scene.with_(die=dice[0]) if single else scene, dice=dice, contact=contact,
            release=GroupState(*(getattr(release, name)[b:b + 1] for name in STATE_FIELDS)),
            run=run, fps=float(fps), t=np.arange(frames + 1) * (stride * dt),
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


def _simulate(scene: Scene, dice: tuple[Die, ...], release: GroupState, contact: DieContact,
              stride: int, run: dict[str, Any]) -> tuple[Any, list[dict[str, Any]]]:
    """The recorded run and each throw's outcome."""
    decided = run["until"] == "decided"
    if len(dice) == 1:
        result = simulate(scene.with_(die=dice[0]), release.die(0), t_max=run["t_max"],
                          until=run["until"], record_every=stride, record=("orientations",))
        faces, read, sunk = result.face[:, None], np.ones((len(result.face), 1), bool), \
            result.sunk[:, None]
    else:
        result = simulate_group(scene, dice, release, contact=contact, t_max=run["t_max"],
                                until=run["until"], record_every=stride, orientations=True)
        faces, read, sunk = result.face, result.read, result.sunk
    voids = void_reasons(np.ones(len(faces), bool), result.unstable, sunk.any(axis=1),
                         result.decided if decided else result.settled,
                         "decided" if decided else "rest", ~read.all(axis=1))
    return result, [{
        "faces": faces[b].tolist(), "read": read[b].tolist(),
        "settled": bool(result.settled[b]), "decided": bool(result.decided[b]),
        "unstable": bool(result.unstable[b]), "sunk": bool(sunk[b].any()),
        "time": float(result.steps[b] * (result.t[0] / stride)), "void": str(voids[b]),
    } for b in range(len(faces))]


def _run_keywords(run: dict[str, Any]) -> dict[str, Any]:
    """A recording's run keywords, those of a file from before ``until`` converted to it."""
    if "until" in run:
        return dict(run)
    until = ("decided" if run["stop_when_decided"] else
             "early_rest" if run["early_rest"] else "rest")
    return {"t_max": run["t_max"], "until": until}

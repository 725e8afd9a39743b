"""Recordings kept and thrown again: :func:`save`, :func:`load` and :func:`replay`.

A file is data: :func:`load` refuses (:class:`RecordingError`, one line) anything that is not a
whole, consistent recording before any work, and :func:`replay` simulates a recording no
further than its frames and the rest hold after them.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import math
from collections.abc import Sequence
from pathlib import Path

from dice_env.disk import parse_json, write_atomically
from dice_env.envs.keywords import ENV_MAX_STEPS
from dice_env.envs.throw_task import UNTIL
from dice_env.viewer.html import read_html
from dice_env.viewer.recording import Recording, as_data, record, run_plan

# Void reasons a replay makes itself (the rest, e.g. a task's "foul", are carried over).
_OWN_VOIDS = ("", "unstable", "sunk", "leaning", *UNTIL.values())
# What building a recording of foreign data may raise: each means the data is no recording.
_DATA_ERRORS = (ValueError, TypeError, KeyError, IndexError, AttributeError, OverflowError,
                RecursionError)


class ReplayError(ValueError):
    """A replayed throw that did not land as recorded (another version, another machine)."""


class RecordingError(ValueError):
    """A file or recording that cannot be replayed: unreadable, inconsistent or out of bounds."""


def load(path: str | Path) -> list[Recording]:
    """The recordings in a page, a ``.glb`` export or a ``.json`` at ``path``.

    :class:`RecordingError` names the file and what is wrong with it (unreadable, truncated,
    no recordings, inconsistent frames or settings).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".html", ".htm", ".glb", ".json"):
        raise RecordingError(f"path must end in .html, .glb or .json, got {path.name!r}")
    if suffix == ".glb" and importlib.util.find_spec("pygltflib") is None:
        raise RecordingError(f"{path}: reading a .glb needs pygltflib (pip install "
                             "'dice_env[gltf]')")
    try:
        if suffix == ".glb":
            from dice_env.viewer.gltf import read_glb

            data = read_glb(path)
        else:
            data = (parse_json(path.read_text(encoding="utf-8")) if suffix == ".json"
                    else read_html(path))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as error:
        raise RecordingError(f"{path}: {_line(error)}") from None
    if not isinstance(data, list) or not data:
        raise RecordingError(f"{path}: holds no recordings (a non-empty list of them), got "
                             f"{_line(repr(data))[:80]}")
    recordings = []
    for k, item in enumerate(data):
        try:
            recordings.append(Recording.from_data(item))
        except _DATA_ERRORS as error:
            raise RecordingError(f"{path}: recording {k}: {_line(error)}") from None
    return recordings


def save(recordings: Recording | Sequence[Recording], path: str | Path) -> Path:
    """Write ``recordings`` to ``path`` as JSON (a list of :meth:`Recording.to_data`)."""
    path = Path(path)
    write_atomically(path, json.dumps(as_data(recordings)).encode())
    return path


def replay(source: Recording | Sequence[Recording] | str | Path) -> list[Recording]:
    """Throw ``source`` (recordings or a file :func:`load` reads) again; the new recordings.

    Each throw is simulated no further than its frames and the rest hold after them, at most
    ``ENV_MAX_STEPS`` steps. :class:`RecordingError` names a throw that cannot be thrown again;
    :class:`ReplayError` each throw whose faces differ.
    """
    recorded = (load(source) if isinstance(source, (str, Path))
                else [source] if isinstance(source, Recording) else list(source))
    again, wrong = [], []
    for k, old in enumerate(recorded):
        try:
            new = _throw_again(old)
        except (ValueError, TypeError) as error:
            raise RecordingError(f"throw {k} cannot be thrown again: {_line(error)}") from None
        if new.outcome["faces"] != old.outcome["faces"]:
            wrong.append(f"throw {k}: faces {old.outcome['faces']} recorded (dice_env "
                         f"{old.version}), {new.outcome['faces']} now (dice_env {new.version})")
        again.append(new)
    if wrong:
        raise ReplayError("the replay landed other faces: " + "; ".join(wrong))
    return again


def _throw_again(old: Recording) -> Recording:
    """``old`` thrown again, to its time limit or the end of its frames and rest hold."""
    dice = old.dice[0] if old.n_dice == 1 else old.dice
    state = old.release.die(0) if old.n_dice == 1 else old.release
    voids = [old.outcome["void"]] if old.outcome["void"] not in _OWN_VOIDS else None
    dt, stride, n_steps = run_plan(old.scene, old.dice, old.contact, old.fps, old.run["t_max"])
    # its frames, one more against round-off, and the rest hold that ends the last
    needed = (len(old.t) + 1) * stride + math.ceil(old.scene.rest.hold / dt)
    steps = min(n_steps, needed)
    if steps > ENV_MAX_STEPS:
        raise ValueError(f"its replay takes {steps:.3g} steps of {dt:.3g} s, more than the "
                         f"{ENV_MAX_STEPS:.0e} a throw may take")
    t_max = old.run["t_max"] if n_steps <= needed else steps * dt
    new = record(old.scene, dice, state, fps=old.fps, contact=old.contact, t_max=t_max,
                 until=old.run["until"], titles=[old.title], voids=voids)[0]
    return dataclasses.replace(new, run=dict(old.run))


def _line(error: object) -> str:
    """An error's message on one line."""
    if isinstance(error, RecursionError):
        return "data nested too deeply to be a recording"
    return " ".join((str(error) or type(error).__name__).split())

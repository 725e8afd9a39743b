"""Recordings kept and thrown again: :func:`save`, :func:`load` and :func:`replay`."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from dice_env.envs.task import UNTIL
from dice_env.viewer.html import read_html
from dice_env.viewer.recording import Recording, as_data, record

# Void reasons a replay makes itself (the rest, e.g. a task's "foul", are carried over).
_OWN_VOIDS = ("", "unstable", "sunk", "leaning", *UNTIL.values())


class ReplayError(ValueError):
    """A replayed throw that did not land as recorded (another version, another machine)."""


def load(path: str | Path) -> list[Recording]:
    """The recordings in a page, a ``.glb`` export (needs pygltflib) or a ``.json`` at ``path``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".html", ".htm"):
        data = read_html(path)
    elif suffix == ".glb":
        from dice_env.viewer.gltf import read_glb

        data = read_glb(path)
    elif suffix == ".json":
        data = json.loads(path.read_text())
    else:
        raise ValueError(f"path must end in .html, .glb or .json, got {path.name!r}")
    return [Recording.from_data(item) for item in data]


def save(recordings: Recording | Sequence[Recording], path: str | Path) -> Path:
    """Write ``recordings`` to ``path`` as JSON (a list of :meth:`Recording.to_data`)."""
    path = Path(path)
    path.write_text(json.dumps(as_data(recordings)))
    return path


def replay(source: Recording | Sequence[Recording] | str | Path) -> list[Recording]:
    """Throw ``source`` (recordings or a file :func:`load` reads) again; the new recordings.

    :class:`ReplayError` names each throw whose faces differ.
    """
    if isinstance(source, (str, Path)):
        recorded = load(source)
    elif isinstance(source, Recording):
        recorded = [source]
    else:
        recorded = list(source)
    again, wrong = [], []
    for k, old in enumerate(recorded):
        dice = old.dice[0] if old.n_dice == 1 else old.dice
        state = old.release.die(0) if old.n_dice == 1 else old.release
        voids = [old.outcome["void"]] if old.outcome["void"] not in _OWN_VOIDS else None
        new = record(old.scene, dice, state, fps=old.fps, contact=old.contact,
                     t_max=old.run["t_max"], until=old.run["until"], titles=[old.title],
                     voids=voids)[0]
        if new.outcome["faces"] != old.outcome["faces"]:
            wrong.append(f"throw {k}: faces {old.outcome['faces']} recorded (dice_env "
                         f"{old.version}), {new.outcome['faces']} now (dice_env {new.version})")
        again.append(new)
    if wrong:
        raise ReplayError("the replay landed other faces: " + "; ".join(wrong))
    return again

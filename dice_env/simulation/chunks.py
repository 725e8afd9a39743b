"""Long runs in chunks kept on disk, so that a run stopped part-way continues where it stopped.

A run folder holds ``spec.json`` (what the run throws) and one ``.npz`` per finished chunk,
each written atomically. Another spec's folder, chunks without a spec or a corrupt file are
refused by name (:class:`FolderError`).
"""

from __future__ import annotations

import hashlib
import json
import zipfile
import zlib
from pathlib import Path

import numpy as np

from dice_env.disk import write_atomically

SPEC_FILE = "spec.json"

Arrays = dict[str, np.ndarray]


class FolderError(ValueError):
    """A run folder that cannot be used as it is: another spec's, or a foreign or corrupt file."""


def identity(record: dict) -> str:
    """A hash of ``record``'s JSON data: the spec a chunk records it belongs to."""
    return hashlib.sha256(json.dumps(record, sort_keys=True).encode()).hexdigest()[:16]


def prepare(folder: Path, record: dict, name: str = "keep") -> Path:
    """``folder`` made ready for a run of ``record``: created with its spec, or checked against it.

    ``name``: the parameter that passed ``folder``, for the :class:`FolderError`.
    """
    record = json.loads(json.dumps(record))
    path = folder / SPEC_FILE
    if folder.exists() and not folder.is_dir():
        raise FolderError(f"{name}={str(folder)!r} is a file, not a folder: pass a folder")
    if path.exists():
        try:
            saved = json.loads(path.read_text())
            if not isinstance(saved, dict):
                raise ValueError(f"JSON {type(saved).__name__}, not an object")
        except ValueError as error:  # not JSON, not text or not an object
            raise FolderError(f"{str(path)!r} is corrupt ({error}): delete {name}="
                              f"{str(folder)!r}, or pass another folder") from error
        differ = [key for key in record | saved if saved.get(key) != record.get(key)]
        if differ:
            shown = "; ".join("another scene" if k == "scene" else
                              f"{k} {saved.get(k)!r} there, {record.get(k)!r} asked"
                              for k in differ)
            raise FolderError(f"{name}={str(folder)!r} holds a run of another spec ({shown}): "
                              "pass the same set-up, or another folder")
    else:
        orphans = sorted(p.name for p in folder.glob("*.npz"))
        if orphans:
            shown = ", ".join(orphans[:3]) + (", ..." if len(orphans) > 3 else "")
            raise FolderError(f"{name}={str(folder)!r} holds {len(orphans)} chunks ({shown}) but "
                              f"no {SPEC_FILE}: they are not known to be this run's; delete "
                              "them, or pass another folder")
        folder.mkdir(parents=True, exist_ok=True)
        write_atomically(path, lambda f: f.write(json.dumps(record, indent=1).encode()))
    return folder


def load(path: Path) -> Arrays:
    """All the arrays of the ``.npz`` at ``path``; :class:`FolderError` naming it if corrupt."""
    try:
        saved = np.load(path)
        if not isinstance(saved, np.lib.npyio.NpzFile):
            raise ValueError("an array, not an .npz archive")
        with saved:
            return {name: saved[name] for name in saved.files}
    except (OSError, EOFError, ValueError, KeyError, NotImplementedError, MemoryError,
            zipfile.BadZipFile, zlib.error) as error:  # what zipfile and numpy raise on bad data
        raise FolderError(f"{str(path)!r} is corrupt (not a readable .npz archive): delete it "
                          "to throw its chunk again") from error


"""Long runs in chunks kept on disk, so that a run stopped part-way continues where it stopped.

A run folder holds ``spec.json`` (what the run throws, as JSON data) and one ``.npz`` of arrays
per finished chunk, each written atomically (never half a file). A folder holding another
spec is refused rather than mixed in. The caller seeds each chunk from its index alone, so a
run's result does not depend on which chunks were read back and which were thrown.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

SPEC_FILE = "spec.json"

Arrays = dict[str, np.ndarray]


def prepare(folder: Path, record: dict, name: str = "keep") -> Path:
    """``folder`` made ready for a run of ``record``: created with its spec, or checked against it.

    ``name``: the parameter that passed ``folder``, for the error.
    """
    record = json.loads(json.dumps(record))
    path = folder / SPEC_FILE
    if path.exists():
        saved = json.loads(path.read_text())
        differ = [key for key in record | saved if saved.get(key) != record.get(key)]
        if differ:
            shown = "; ".join("another scene" if k == "scene" else
                              f"{k} {saved.get(k)!r} there, {record.get(k)!r} asked"
                              for k in differ)
            raise ValueError(f"{name}={str(folder)!r} holds a run of another spec ({shown}): "
                             "pass the same set-up, or another folder")
    else:
        folder.mkdir(parents=True, exist_ok=True)
        write_atomically(path, lambda f: f.write(json.dumps(record, indent=1).encode()))
    return folder


def write_atomically(path: Path, write: Callable) -> None:
    """``write(file)`` to a temporary file renamed to ``path``: never a half-written file."""
    partial = path.with_name(path.name + ".partial")
    with open(partial, "wb") as f:
        write(f)
    os.replace(partial, path)


def kept_chunks(throw: Callable[[int, int], Arrays], throws: int, chunk: int,
                folder: Path | None, prefix: str, bar: object = None,
                unit: int = 1) -> list[Arrays]:
    """``throws`` split into chunks of ``chunk`` (the last takes the rest), each ``throw(i, size)``.

    With ``folder`` (made ready by :func:`prepare`), chunk ``i`` of ``size`` throws is kept as
    ``<prefix>-<i>-<size>.npz`` there and read back instead of thrown when present. ``bar``
    (a progress bar) advances by ``size * unit`` per chunk.
    """
    parts = []
    for i, start in enumerate(range(0, throws, chunk)):
        size = min(chunk, throws - start)
        path = None if folder is None else folder / f"{prefix}-{i:05d}-{size}.npz"
        if path is not None and path.exists():
            with np.load(path) as saved:
                part = dict(saved)
        else:
            part = throw(i, size)
            if path is not None:
                write_atomically(path, lambda f, arrays=part: np.savez(f, **arrays))
        parts.append(part)
        if bar is not None:
            bar.update(size * unit)
    return parts

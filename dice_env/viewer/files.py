"""Recordings in files: JSON of their data, read back from a page, an export or JSON alike."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from dice_env.viewer.html import read_html
from dice_env.viewer.recording import Recording, as_data


def load(path: str | Path) -> list[Recording]:
    """The recordings in ``path``: a page, a ``.glb`` export or a ``.json`` of :func:`save`.

    Pages are those of :func:`dice_env.viewer.html.write_html`, exports those of
    :func:`dice_env.viewer.gltf.write_glb` (reading one needs pygltflib: the ``viewer`` extra).
    """
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

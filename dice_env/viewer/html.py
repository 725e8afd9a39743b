"""A self-contained HTML page of recorded throws, drawn in 3D by three.js.

It opens offline: the bundle ``viewer.bundle.js`` (built from ``js/``) inlined, the recordings as
JSON and what the viewer draws (meshes, textures, walls, floor), which :func:`read_html` reads.
"""

from __future__ import annotations

import base64
import html
import json
import re
from collections.abc import Sequence
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np

from dice_env.disk import parse_json, write_atomically
from dice_env.model.checks import check_choice
from dice_env.model.die import Die
from dice_env.viewer.recording import Recording
from dice_env.viewer.scenery import scenery
from dice_env.viewer.textures import face_atlas, png_bytes

LAYOUTS = ("sequence", "side")  # several throws one after another, or side by side on a grid
DATA_ID = "dice-env-throws"  # the id of the page's script of JSON data
TEXTURE_PIXELS = 128  # texture pixels a side of one face

_DATA = re.compile(rf'<script type="application/json" id="{DATA_ID}">(.*?)</script>', re.S)


def write_html(recordings: Recording | Sequence[Recording], path: str | Path, *,
               layout: str = "sequence", title: str | None = None) -> Path:
    """Write a page of ``recordings`` to ``path`` (``.html``) and return the path.

    ``layout``: ``"sequence"`` (one throw after another) or ``"side"`` (side by side); the page
    can switch. ``title``: default a single recording's title, else ``"dice_env throws"``.
    """
    items = [recordings] if isinstance(recordings, Recording) else recordings
    if (not isinstance(items, Sequence) or isinstance(items, (str, bytes))
            or not all(isinstance(r, Recording) for r in items)):
        got = [type(r).__name__ for r in items] if isinstance(items, (list, tuple)) else items
        raise TypeError(f"recordings must be a Recording or a sequence of them, got {got!r:.80}")
    if not items:
        raise ValueError("recordings must not be empty: give at least one Recording")
    check_choice("layout", layout, LAYOUTS)
    path = Path(path)
    if path.suffix.lower() != ".html":
        raise ValueError(f"path must end in .html, got {path.name!r}")
    if title is not None and not isinstance(title, str):
        raise TypeError(f"title must be a str or None, got {type(title).__name__}")
    if title is None:
        title = items[0].title if len(items) == 1 and items[0].title else "dice_env throws"
    shapes: dict[Die, int] = {}
    data = {"title": title, "layout": layout, "recordings": [r.to_data() for r in items],
            "throws": [_throw_view(r, shapes) for r in items],  # fills shapes
            "shapes": [_shape(die) for die in shapes]}
    try:
        text = json.dumps(data, separators=(",", ":"), allow_nan=False)
    except ValueError as error:  # JSON.parse in the page reads no NaN nor infinity
        raise ValueError(f"recordings must hold finite numbers only: {error}") from None
    # JSON strings may hold "<" only as an escape: no "</script>" or "<!--" ends the script.
    text = text.replace("<", "\\u003c")
    bundle = files("dice_env.viewer").joinpath("viewer.bundle.js").read_text(encoding="utf-8")
    if re.search(r"</script|<!--", bundle, re.I):
        raise RuntimeError("viewer.bundle.js holds '</script' or '<!--', which would end or "
                           "break its script in the page")
    write_atomically(path, (
        "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        f"<title>{html.escape(title)}</title>\n</head>\n<body>\n"
        f"<script type=\"application/json\" id=\"{DATA_ID}\">{text}</script>\n"
        f"<script>\n{bundle}\n</script>\n</body>\n</html>\n").encode())
    return path


def read_html(path: str | Path) -> list[dict[str, Any]]:
    """The recordings' data embedded in a page of :func:`write_html` (a list, in order)."""
    path = Path(path)
    match = _DATA.search(path.read_text(encoding="utf-8"))
    if match is None:
        raise ValueError(f"path {str(path)!r} is not a page of dice_env.viewer.write_html "
                         f"(no whole script {DATA_ID!r})")
    data = parse_json(match.group(1))
    if not isinstance(data, dict) or "recordings" not in data:
        raise ValueError(f"path {str(path)!r}: its script {DATA_ID!r} holds no 'recordings'")
    return data["recordings"]


def _shape(die: Die) -> dict[str, Any]:
    """A die's triangles about its centre of mass, flat normals, texture coordinates, atlas."""
    image, uv = face_atlas(die, TEXTURE_PIXELS)
    fan = [(k, c) for k, face in enumerate(die.faces)  # a convex face as a fan of triangles
           for i in range(1, len(face) - 1) for c in (0, i, i + 1)]
    face, corner = np.array(fan).T
    position = die.vertices_body[[die.faces[k][c] for k, c in fan]]
    png = base64.b64encode(png_bytes(image)).decode("ascii")
    return {"position": _rounded(position), "normal": _rounded(np.asarray(die.face_normals)[face]),
            "uv": _rounded(uv[face, corner]), "texture": f"data:image/png;base64,{png}"}


def _throw_view(recording: Recording, shapes: dict[Die, int]) -> dict[str, Any]:
    """What the page draws of a throw besides its dice' frames: shapes, extent, floor, walls."""
    view = scenery(recording)
    u, w = view.axes
    return {"dice": [shapes.setdefault(die, len(shapes)) for die in recording.dice],
            "size": view.size, "centre": _rounded(view.centre), "radius": view.radius,
            "floor": {"point": _rounded(view.centre), "u": _rounded(u), "w": _rounded(w)},
            "walls": [[_rounded(p) for p in polygon] for polygon in view.walls.values()]}


def _rounded(values: Any) -> list[float]:
    """Floats to 7 significant digits (float32 precision, what the page draws with)."""
    return [float(f"{v:.7g}") for v in np.ravel(values)]

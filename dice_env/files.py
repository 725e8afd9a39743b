"""Files kept for later, written whole or not at all.

Each is written to a name unique to the process in its own folder and renamed into place, so a
crash, a Ctrl-C or a second process writing the same file never leaves a half-written one.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any


def write_atomically(path: str | Path, write: Callable[[IO[bytes]], Any]) -> Path:
    """``write(file)`` into a temporary file of ``path``'s folder, then renamed to ``path``."""
    path = Path(path)
    fd, partial = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".partial")
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.replace(partial, path)
    except BaseException:
        Path(partial).unlink(missing_ok=True)
        raise
    return path


def write_text(path: str | Path, text: str) -> Path:
    """``text`` (UTF-8) written atomically to ``path``."""
    return write_atomically(path, lambda f: f.write(text.encode()))


def write_json(path: str | Path, data: Any, indent: int | None = 1) -> Path:
    """``data`` as JSON (and a final newline) written atomically to ``path``."""
    return write_text(path, json.dumps(data, indent=indent) + "\n")


"""Files on disk: written whole or not at all, and JSON read back with a reason when it is not."""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path
from typing import Any


def write_atomically(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole or not at all.

    To a name unique to this process and thread in the same folder, then renamed into place.
    """
    partial = path.with_name(f".{path.name}.{os.getpid()}-{threading.get_ident()}.partial")
    try:
        partial.write_bytes(data)
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)


def parse_json(text: str | bytes) -> Any:
    """JSON ``text`` parsed, or ``ValueError`` saying it is not whole JSON."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise ValueError(f"not whole JSON (truncated or edited?): {error}") from None
    except RecursionError:
        raise ValueError("JSON nested too deeply to be a recording") from None

"""Files on disk: written whole or not at all, and JSON read back with a reason when it is not."""

from __future__ import annotations

import json
import os
import secrets
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO


def write_atomically(path: Path, data: bytes | Callable[[BinaryIO], object]) -> None:
    """Write ``data`` (bytes, or a function writing to the file) to ``path`` whole or not at all.

    To a temporary name of this process's alone (``<name>.<pid>-<random>.partial``, created
    exclusively) in the same folder, renamed into place: processes writing one folder never
    rename each other's files; removed if writing fails.
    """
    partial = path.with_name(f"{path.name}.{os.getpid()}-{secrets.token_hex(4)}.partial")
    try:
        with open(partial, "xb") as f:
            if callable(data):
                data(f)
            else:
                f.write(data)
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

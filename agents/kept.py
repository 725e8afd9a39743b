"""Files the agents keep for later: written whole, read back or refused by name.

Written through :func:`dice_env.disk.write_atomically` (a name unique to the process,
renamed into place); an unusable one is refused with what to do (:class:`RunError`).
"""

from __future__ import annotations

import io
import json
import sys
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from dice_env.disk import write_atomically

INTERRUPTED = 130  # exit status after Ctrl-C (128 + SIGINT), as shells report it


class RunError(ValueError):
    """A kept result or checkpoint that cannot be used as it is; the message says what to do."""


def differences(saved: dict[str, Any], wanted: dict[str, Any]) -> str:
    """How ``saved`` differs from ``wanted`` on ``wanted``'s keys ("" when it does not)."""
    return "; ".join("other hyperparameters" if key == "hyperparams" else
                     f"{key} {saved.get(key)!r} there, {value!r} here"
                     for key, value in wanted.items() if saved.get(key) != value)


def read_json(path: Path, hint: str) -> dict[str, Any]:
    """The JSON object of ``path``; :class:`RunError` naming it, with ``hint``, if not one."""
    try:
        data = json.loads(path.read_bytes())
        if not isinstance(data, dict):
            raise ValueError(f"JSON {type(data).__name__}, not an object")
    except (OSError, ValueError) as error:
        raise RunError(f"{path} is unreadable ({type(error).__name__}: {error}): {hint}") \
            from None
    return data


def readable_zip(path: Path, hint: str) -> None:
    """:class:`RunError` naming ``path``, with ``hint``, unless it is a whole zip archive."""
    try:
        with zipfile.ZipFile(path) as archive:
            bad = archive.testzip()
    except (OSError, EOFError, zipfile.BadZipFile) as error:
        raise RunError(f"{path} is not a readable zip archive ({error}): {hint}") from None
    if bad is not None:
        raise RunError(f"{path} is corrupt ({bad} fails its CRC check): {hint}")


def interrupted(what_is_kept: str) -> int:
    """Say after Ctrl-C what is kept and how to go on (``what_is_kept``); :data:`INTERRUPTED`."""
    print(f"\ninterrupted (Ctrl-C): {what_is_kept}", file=sys.stderr)
    return INTERRUPTED


def read_sessions(run: Path) -> list[dict[str, Any]]:
    """The training sessions a run keeps, one per line of ``training.jsonl`` (none if absent)."""
    path = Path(run) / "training.jsonl"
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def write_sessions(run: Path, sessions: list[dict[str, Any]]) -> Path:
    """``sessions`` written whole as the run's ``training.jsonl``."""
    return write_text(Path(run) / "training.jsonl", "".join(json.dumps(s) + "\n" for s in sessions))


def write_text(path: Path, text: str) -> Path:
    """``text`` (UTF-8) written whole to ``path``."""
    write_atomically(Path(path), text.encode())
    return path


def write_json(path: Path, data: Any, indent: int | None = 1) -> Path:
    """``data`` as JSON (and a final newline) written whole to ``path``."""
    return write_text(path, json.dumps(data, indent=indent) + "\n")


def write_saved(path: Path, save: Callable[[IO[bytes]], Any]) -> Path:
    """What ``save(file)`` writes (a model's ``save``, a figure's ``savefig``), written whole."""
    buffer = io.BytesIO()
    save(buffer)
    write_atomically(Path(path), buffer.getvalue())
    return path

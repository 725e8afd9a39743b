"""Where a result came from: the checkout's ``git describe``, else the installed version."""

from __future__ import annotations

import subprocess
from importlib import metadata
from pathlib import Path

CHECKOUT = Path(__file__).resolve().parents[1]  # the repository's root when run from a checkout


def code_version(tree: Path | str | None = None) -> str:
    """``git describe --always --dirty`` of the checkout at ``tree`` (default: this package's).

    Where ``tree`` is no git checkout (an installed package): ``dice_env VERSION`` of the
    installed distribution, or ``"unknown"``.
    """
    tree = CHECKOUT if tree is None else Path(tree)
    if (tree / ".git").exists():
        try:
            done = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=tree,
                                  capture_output=True, text=True, timeout=10)
        except (OSError, subprocess.TimeoutExpired):
            return "unknown"
        return done.stdout.strip() or "unknown"
    try:
        return f"dice_env {metadata.version('dice_env')}"
    except metadata.PackageNotFoundError:
        return "unknown"

"""One line on stderr before a kernel compiles: what is compiling and about how long it takes.

numba compiles each kernel at its first call and caches the machine code on disk
(``NUMBA_CACHE_DIR``, else ``__pycache__`` beside the sources), so only a process that finds
the cache empty or stale waits. :func:`announce` says so once per kernel and process, and
is quiet when the cache is warm or when :data:`QUIET` is set in the environment.
"""

from __future__ import annotations

import os
import pickle
import sys
from collections.abc import Sequence

QUIET = "DICE_ENV_QUIET_COMPILE"
_announced: set[str] = set()


def announce(dispatchers: Sequence[object], what: str, seconds: float) -> None:
    """Say on stderr that the kernel ``what`` compiles, unless its ``dispatchers`` need not.

    ``dispatchers`` are the kernel's costly numba ``@njit(cache=True)`` functions and
    ``seconds`` its cold compile time on two cores (``benchmarks/cold_start.py`` measures
    it). Nothing is said when each dispatcher is compiled in this process or found in
    numba's cache, when ``what`` was announced before, or when :data:`QUIET` is set to
    anything but ``""`` or ``"0"``.
    """
    if what in _announced or os.environ.get(QUIET, "") not in ("", "0"):
        return
    _announced.add(what)
    if all(ready(d) for d in dispatchers):
        return
    minutes = f"{seconds / 60:.0f} min" if seconds >= 90 else f"{seconds:.0f} s"
    print(f"dice_env: compiling {what} (first use with this numba cache: about {minutes} on "
          f"2 cores, then cached; {QUIET}=1 silences this)", file=sys.stderr, flush=True)


def ready(dispatcher: object) -> bool:
    """Whether ``dispatcher`` runs without compiling: compiled in this process or cached."""
    return bool(dispatcher.overloads) or _cached(dispatcher)


def _cached(dispatcher: object) -> bool:
    """Whether numba's on-disk cache holds a current compilation of ``dispatcher``.

    A cache index written for other sources or another numba reads as empty.
    """
    cache = getattr(dispatcher, "_cache", None)
    index = getattr(cache, "_cache_file", None)
    if index is None:  # not cached on disk: every process compiles it
        return False
    try:
        return bool(index._load_index())
    except (OSError, EOFError, pickle.UnpicklingError):  # numba recompiles: the notice is right
        return False

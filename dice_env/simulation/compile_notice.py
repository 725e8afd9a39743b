"""One line on stderr before a kernel compiles: what is compiling and about how long it takes.

numba compiles each kernel at its first call and caches the machine code on disk
(``NUMBA_CACHE_DIR``, else ``__pycache__`` beside the sources), so only a process that finds
the cache empty or stale waits. :func:`announce` says so for a kernel loop neither compiled
nor cached for the types of its arguments (a loop compiles once per signature: the
vectorised loop has two), and is quiet when :data:`QUIET` is set in the environment.
"""

from __future__ import annotations

import os
import pickle
import sys

QUIET = "DICE_ENV_QUIET_COMPILE"
# Per (kernel, its arguments' classes): numba's types of the arguments (a quarter of a
# millisecond to work out, so once per variant)
_types: dict[tuple[object, tuple[type, ...]], tuple] = {}


def announce(dispatcher: object, args: tuple, what: str, seconds: float) -> None:
    """Say on stderr that the kernel ``what`` compiles, unless ``dispatcher`` runs ``args`` now.

    ``dispatcher`` is the kernel's numba ``@njit(cache=True)`` loop and ``seconds`` its cold
    compile time on two cores (``benchmarks/cold_start.py`` measures it). Nothing is said
    when the loop is compiled in this process or found in numba's cache for the types of
    ``args``, or when :data:`QUIET` is set to anything but ``""`` or ``"0"``.
    """
    if os.environ.get(QUIET, "") not in ("", "0") or ready(dispatcher, args):
        return
    minutes = f"{seconds / 60:.0f} min" if seconds >= 90 else f"{seconds:.0f} s"
    print(f"dice_env: compiling {what} (first use with this numba cache: about {minutes} on "
          f"2 cores, then cached; {QUIET}=1 silences this)", file=sys.stderr, flush=True)


def ready(dispatcher: object, args: tuple) -> bool:
    """Whether ``dispatcher`` runs ``args`` without compiling: compiled or cached for them."""
    key = (dispatcher, tuple(type(a) for a in args))
    if key not in _types:
        _types[key] = tuple(dispatcher.typeof_pyval(a) for a in args)
    types = _types[key]  # a run compiles them, or loads them from the cache, into overloads
    return types in dispatcher.overloads or _cached(dispatcher, types)


def _cached(dispatcher: object, types: tuple) -> bool:
    """Whether numba's on-disk cache holds a current compilation of ``dispatcher`` for ``types``.

    A cache index written for other sources or another numba reads as empty.
    """
    cache = getattr(dispatcher, "_cache", None)
    index = getattr(cache, "_cache_file", None)
    if index is None:  # not cached on disk: every process compiles it
        return False
    try:
        return any(key[0] == types for key in index._load_index())
    except (OSError, EOFError, pickle.UnpicklingError):  # numba recompiles: the notice is right
        return False

"""One line on stderr before a kernel compiles: what is compiling and about how long it takes.

numba caches each kernel's machine code on disk (``NUMBA_CACHE_DIR``, else ``__pycache__``),
so only a process that finds the cache empty or stale for a signature waits. The notice says
about how long, from the cold compile times ``benchmarks/cold_start.py`` measured
(:data:`TIMES`). A cache file numba cannot read is named with the folder to delete
(:func:`cache_hint`).
"""

from __future__ import annotations

import contextlib
import functools
import os
import pickle
import sys
from collections.abc import Iterator
from pathlib import Path

from dice_env.disk import parse_json

QUIET = "DICE_ENV_QUIET_COMPILE"
TIMES = Path(__file__).with_name("compile_times.json")  # written by benchmarks/cold_start.py
# numba's types of the arguments per (kernel, their classes): 0.25 ms to work out
_types: dict[tuple[object, tuple[type, ...]], tuple] = {}


def announce(dispatcher: object, args: tuple, what: str, seconds: float | None = None) -> None:
    """Say on stderr that the kernel ``what`` compiles, unless :func:`ready`.

    The notice gives about how long: ``seconds``, else ``what``'s measured time in :data:`TIMES`
    (none if it has none). Quiet when :data:`QUIET` is set to anything but ``""`` or ``"0"``.
    """
    if os.environ.get(QUIET, "") not in ("", "0") or ready(dispatcher, args):
        return
    cores, measured = measured_times()
    seconds = measured.get(what) if seconds is None else seconds
    about = ""
    if seconds is not None:
        minutes = f"{seconds / 60:.0f} min" if seconds >= 90 else f"{seconds:.0f} s"
        about = f": about {minutes}" + (f" on {cores} cores" if cores else "")
    print(f"dice_env: compiling {what} (first use with this numba cache{about}, then cached; "
          f"{QUIET}=1 silences this)", file=sys.stderr, flush=True)


@functools.cache
def measured_times() -> tuple[int, dict[str, float]]:
    """The cores and each kernel's cold compile time (s) in :data:`TIMES`; none if it is absent."""
    try:
        times = parse_json(TIMES.read_bytes())
    except FileNotFoundError:
        return 0, {}
    return times["cores"], times["seconds"]


def ready(dispatcher: object, args: tuple) -> bool:
    """Whether ``dispatcher`` runs ``args`` without compiling: compiled or cached for them."""
    key = (dispatcher, tuple(type(a) for a in args))
    if key not in _types:
        _types[key] = tuple(dispatcher.typeof_pyval(a) for a in args)
    types = _types[key]  # a run compiles them, or loads them from the cache, into overloads
    if types in dispatcher.overloads:
        return True
    index = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if index is None:  # not cached on disk: every process compiles it
        return False
    try:  # numba's on-disk cache holds a current compilation for these types
        return any(entry[0] == types for entry in index._load_index())
    except (OSError, EOFError, pickle.UnpicklingError):  # numba recompiles: the notice is right
        return False


@contextlib.contextmanager
def cache_hint(dispatcher: object) -> Iterator[None]:
    """Run the block; ``RuntimeError`` naming the folder to delete if ``dispatcher``'s cache is cut.

    numba fails on a cache file it cannot unpickle (cut short, say) at every call until it goes.
    """
    try:
        yield
    except (pickle.UnpicklingError, EOFError) as error:
        folder = getattr(getattr(dispatcher, "_cache", None), "_cache_path", "numba's cache")
        name = getattr(getattr(dispatcher, "py_func", None), "__qualname__", "kernel")
        raise RuntimeError(f"numba could not read its cached {name} ({error}): a "
                           f"cache file is cut short or damaged; delete the folder {folder} "
                           "(or its files for this kernel) and run again to compile it "
                           "afresh") from error

"""No silent waits: progress bars that can be turned off, a notice before the kernel compiles."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

# The first simulation in a checkout compiles the kernel (numba caches it next to the source).
COMPILE_NOTICE = ("compiling the simulation kernel (first run in this checkout, cached "
                  "afterwards): about 30 s on a free machine, up to 3 min on a busy one")


class Bar:
    """A tqdm bar (``enabled``) or nothing, with the same ``update`` and ``close``."""

    def __init__(self, total: int, desc: str, unit: str, enabled: bool = True,
                 initial: int = 0) -> None:
        self.total = total
        self.n = initial
        self._bar: Any = None
        if enabled:
            from tqdm.auto import tqdm

            self._bar = tqdm(total=total, initial=initial, desc=desc, unit=unit,
                             dynamic_ncols=True, file=sys.stderr)

    def update(self, k: int) -> None:
        """Advance by ``k``."""
        self.n += k
        if self._bar is not None:
            self._bar.update(k)

    def close(self) -> None:
        """Close the bar (its line stays on the terminal)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None


@contextmanager
def bar(total: int, desc: str, unit: str, enabled: bool = True) -> Iterator[Bar]:
    """A :class:`Bar` closed on leaving the block."""
    b = Bar(total, desc, unit, enabled)
    try:
        yield b
    finally:
        b.close()


def kernel_cached() -> bool:
    """Whether numba's cache already holds the simulation kernel (index files next to it)."""
    from dice_env import kernel

    try:
        folder = Path(kernel.simulate_batch._cache.cache_path)
    except AttributeError:  # numba without a file cache: assume a compile
        return False
    return any(folder.glob("kernel.simulate_*.nbi"))


def announce_compile(log: Any = print) -> None:
    """Say that the kernel will compile (and how long it takes) when it is not cached yet."""
    if not kernel_cached():
        log(COMPILE_NOTICE)

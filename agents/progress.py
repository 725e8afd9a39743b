"""No silent waits: progress bars that can be turned off.

A kernel about to compile says so itself (:mod:`dice_env.simulation.compile_notice`).
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


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

"""Markdown for reports: a table, and a share with its interval."""

from __future__ import annotations

from collections.abc import Iterable


def bracket(interval: object, digits: int = 3) -> str:
    """An interval ``(low, high)`` as ``[low, high]`` to ``digits`` decimals."""
    low, high = interval
    return f"[{low:.{digits}f}, {high:.{digits}f}]"


def estimate(p: float, interval: object, digits: int = 3) -> str:
    """A share and its interval as ``p [low, high]`` to ``digits`` decimals."""
    return f"{p:.{digits}f} {bracket(interval, digits)}"


def markdown_table(header: str, rows: Iterable[Iterable[object]]) -> str:
    """A markdown table: ``header`` ("a | b"), its rule, then one line per row of cells."""
    lines = [f"| {header} |", "|" + "---|" * (header.count(" | ") + 1)]
    return "\n".join(lines + ["| " + " | ".join(map(str, row)) + " |" for row in rows])

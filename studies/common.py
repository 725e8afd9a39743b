"""What every study shares: docs folder, seed, figures, progress bar, throw count, chunks."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import fields
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # every study imports this module: its figures are written, not shown
import matplotlib.pyplot as plt
import numpy as np
from tqdm import tqdm

from dice_env.disk import write_atomically
from dice_env.model.checks import check_int
from dice_env.simulation.chunks import Arrays, load
from dice_env.simulation.simulate import DiceArrays
from studies import ROOT

DOCS = ROOT / "docs"  # where the full studies write their pages
SEED = 2026  # the studies' default seed


def save_figure(fig: plt.Figure, path: Path) -> None:
    """Write ``fig`` as a PNG, whole or not at all (creating the folder), and close it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomically(path, lambda f: fig.savefig(f, format="png", dpi=110, bbox_inches="tight"))
    plt.close(fig)


def draw_figures(figures: dict[str, Callable[[dict, Path], None]], data: dict,
                 out: Path) -> None:
    """Draw each of a study's ``figures`` (name: draw) from its page's numbers ``data``.

    Each lands as ``out/figures/<name>.png``; ``data`` is what the study keeps as its JSON.
    """
    for name, draw in figures.items():
        draw(data, out / "figures" / f"{name}.png")


def write_text(path: Path, text: str) -> None:
    """Write a page or JSON ``text`` to ``path``, whole or not at all."""
    write_atomically(path, text.encode())


def error_bars(p: np.ndarray, ci: np.ndarray) -> np.ndarray:
    """Matplotlib's (2, n) error bars of shares ``p`` from intervals ``ci`` (n, 2), clipped at 0."""
    return np.clip(np.stack([p - ci[:, 0], ci[:, 1] - p]), 0.0, None)


def progress(total: int, desc: str, unit: str = "run") -> tqdm:
    """The studies' progress bar, counting ``unit``."""
    return tqdm(total=total, desc=desc, unit=unit, dynamic_ncols=True)


def join(parts: list) -> object:
    """``parts`` (states, or results without records) as one: their arrays concatenated."""
    values = {f.name: [getattr(p, f.name) for p in parts] for f in fields(parts[0])}
    return type(parts[0])(**{k: join(v) if isinstance(v[0], DiceArrays) else np.concatenate(v)
                             for k, v in values.items() if v[0] is not None})


def checked_throws(throws: object, least: int, default: int | None = None) -> int | None:
    """A study's ``throws`` checked: an int >= ``least``, or ``default`` (its own size) for None."""
    return default if throws is None else check_int("throws", throws, least)


def kept_chunks(throw: Callable[[int, int], Arrays], throws: int, chunk: int,
                folder: Path | None, prefix: str, bar: object = None,
                unit: int = 1) -> list[Arrays]:
    """``throws`` split into chunks of ``chunk`` (the last takes the rest), each ``throw(i, size)``.

    With ``folder`` (see :func:`dice_env.simulation.chunks.prepare`), chunk ``i`` is kept as
    ``<prefix>-<i>-<size>.npz`` there and read back when present; ``bar`` advances by
    ``size * unit`` per chunk.
    """
    parts = []
    for i, start in enumerate(range(0, throws, chunk)):
        size = min(chunk, throws - start)
        path = None if folder is None else folder / f"{prefix}-{i:05d}-{size}.npz"
        if path is not None and path.exists():
            parts.append(load(path))
        else:
            parts.append(throw(i, size))
            if path is not None:
                write_atomically(path, lambda f, arrays=parts[-1]: np.savez(f, **arrays))
        if bar is not None:
            bar.update(size * unit)
    return parts

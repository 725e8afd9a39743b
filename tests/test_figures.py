"""Every figure of the docs is what its command draws, pixel for pixel (slow: CI runs them).

The studies' figures are redrawn from the JSON their pages keep (``python -m studies.figures``);
the README's figures are tested in ``test_render.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from studies.figures import figures

DOCS = Path(__file__).resolve().parents[1] / "docs"
STUDY_FIGURES = figures()


def differing_pixels(drawn: Path, committed: Path) -> float:
    """Share of the pixels whose RGB differs between two PNGs of the same size."""
    a, b = (np.asarray(Image.open(p).convert("RGB")) for p in (drawn, committed))
    assert a.shape == b.shape, f"{drawn.name}: size {a.shape[:2]}, committed {b.shape[:2]}"
    return float((a != b).any(axis=-1).mean())


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(STUDY_FIGURES))
def test_a_study_figure_is_what_its_json_draws(name, tmp_path):
    """``python -m studies.figures NAME`` redraws docs/figures/NAME.png pixel for pixel."""
    STUDY_FIGURES[name].redraw(tmp_path / f"{name}.png")
    differ = differing_pixels(tmp_path / f"{name}.png", DOCS / "figures" / f"{name}.png")
    assert differ == 0.0, f"{name}: {differ:.1%} of the pixels differ; redraw it with " \
        f"python -m studies.figures {name} --out docs/figures/{name}.png"

"""Every figure of the docs is what its command draws, pixel for pixel (slow: CI runs them).

Each figure is redrawn from the JSON it was drawn from: a study's from ``docs/<study>.json``
(``python -m studies.figures NAME``), the agents' from their results. The README's figures are
tested in ``test_render.py``.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from dice_env.viewer import browser
from dice_env.viewer.__main__ import main as viewer_main
from studies.figures import figures

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
STUDY_FIGURES = figures()


def _read(path: Path) -> dict:
    return json.loads(path.read_text())


def _baselines(path: Path) -> None:
    from agents import benchmark  # SB3 and torch: only where the slow test runs

    benchmark.figure(_read(benchmark.RESULTS / "baselines.json"), path)


def _controllability(path: Path) -> None:
    from agents import controllability

    controllability.figure(_read(DOCS / "controllability.json"), path)


# The agents' figures: (committed PNG, redraw into a path, the command that draws it).
AGENT_FIGURES: dict[str, tuple[Path, Callable[[Path], None], str]] = {
    "baselines": (DOCS / "figures" / "baselines.png", _baselines,
                  "python -m agents.benchmark --table"),
    "controllability": (DOCS / "controllability.png", _controllability,
                        "python -m agents.controllability --run RUN --out docs")}

# docs/figures/viewer.png: docs/viewer.md's command, its page and picture written elsewhere.
VIEWER = ["--num-dice", "2", "--walls", "tray", "--seed", "1", "--at", "0.12", "--force"]
# Chromium draws the viewer's page in software (SwiftShader), the same picture on one machine
# from run to run; another CPU may round an edge's shading otherwise: so much may differ.
VIEWER_SHADE, VIEWER_SHARE = 16, 0.005  # by more than 16/255 in a channel, in 0.5% of pixels


def differing_pixels(drawn: Path, committed: Path, by: int = 0) -> float:
    """Share of the pixels whose RGB differs by more than ``by`` between two same-size PNGs."""
    a, b = (np.asarray(Image.open(p).convert("RGB")).astype(int) for p in (drawn, committed))
    assert a.shape == b.shape, f"{drawn.name}: size {a.shape[:2]}, committed {b.shape[:2]}"
    return float((np.abs(a - b) > by).any(axis=-1).mean())


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(STUDY_FIGURES))
def test_a_study_figure_is_what_its_json_draws(name, tmp_path):
    """``python -m studies.figures NAME`` redraws docs/figures/NAME.png pixel for pixel."""
    STUDY_FIGURES[name].redraw(tmp_path / f"{name}.png")
    differ = differing_pixels(tmp_path / f"{name}.png", DOCS / "figures" / f"{name}.png")
    assert differ == 0.0, f"{name}: {differ:.1%} of the pixels differ; redraw it with " \
        f"python -m studies.figures {name} --out docs/figures/{name}.png"


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(AGENT_FIGURES))
def test_an_agents_figure_is_what_its_json_draws(name, tmp_path):
    """The agents' figures redrawn from their kept results, pixel for pixel."""
    committed, redraw, command = AGENT_FIGURES[name]
    redraw(tmp_path / committed.name)
    differ = differing_pixels(tmp_path / committed.name, committed)
    assert differ == 0.0, f"{name}: {differ:.1%} of the pixels differ ({command} draws it)"


@pytest.mark.slow
def test_the_viewer_figure_is_what_its_command_draws(tmp_path, monkeypatch):
    """docs/viewer.md's command redraws docs/figures/viewer.png, within the stated tolerance."""
    if browser.missing():
        pytest.skip(browser.missing())
    monkeypatch.chdir(tmp_path)
    assert viewer_main([*VIEWER, "--out", "tray.html", "--screenshot", "viewer.png"]) == 0
    differ = differing_pixels(tmp_path / "viewer.png", DOCS / "figures" / "viewer.png",
                              VIEWER_SHADE)
    assert differ <= VIEWER_SHARE, f"viewer: {differ:.1%} of the pixels differ by more than " \
        f"{VIEWER_SHADE}/255; redraw it with docs/viewer.md's command"


def test_every_figure_of_the_docs_is_redrawn_by_a_test():
    """Each PNG under docs/ is a study's, an agent's, the README's or the viewer's."""
    from studies.readme_figures import FIGURES as README_FIGURES

    covered = {*STUDY_FIGURES, *README_FIGURES, "viewer"}
    covered |= {path.stem for path, _, _ in AGENT_FIGURES.values()}
    assert {p.stem for p in DOCS.rglob("*.png")} <= covered


@pytest.mark.parametrize("page", [ROOT / "README.md", *sorted(DOCS.glob("*.md"))],
                         ids=lambda p: p.name)
def test_every_figure_names_its_command(page):
    """An image's alt text or the lines just below it give the command that draws it."""
    lines = page.read_text().splitlines()
    for i, line in enumerate(lines):
        for alt in re.findall(r"!\[([^\]]*)\]\([^)]+\.png\)", line):
            near = " ".join([alt, *lines[i + 1:i + 5]])
            assert "python -m " in near, f"{page.name}:{i + 1}: no command beside the figure"

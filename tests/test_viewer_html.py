"""The HTML page of recorded throws: its data round trip, its size, and the page itself.

The page is opened from ``file://`` in Debian's Chromium (headless, WebGL by SwiftShader)
through Playwright; those tests skip where either is missing. They check that the viewer
starts cleanly and draws, and that at the start, middle and end of a throw each die is where
the recording puts it: the viewer's own projection agrees with one computed here from the
camera's matrices, and the canvas shows something at that pixel that is not there once the
die has moved on.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dice_env import Die, Scene, State
from dice_env.envs import make_task
from dice_env.model.surroundings import walls
from dice_env.simulation.group import GroupState
from dice_env.viewer import Recording, browser, load, record
from dice_env.viewer.html import read_html, write_html
from dice_env.viewer.recording import as_data
from dice_env.viewer.throws import task_throws

VIEWPORT = {"width": 800, "height": 600}
# Points on a die (world offsets from its centre, within a quarter of its size): pips or edges.
PATCH = [np.array([x, y, 0.0]) * Die().size / 4 for x in (-1, 0, 1) for y in (-1, 0, 1)]
MAX_PAGE_BYTES = 2_000_000  # a 2 s throw of two dice


@pytest.fixture(scope="module")
def throw() -> Recording:
    """Two dice thrown into a tray: they fly, bounce and settle apart."""
    scene = Scene(walls=walls("tray"))
    release = GroupState.of([
        State.release(scene, np.array([-0.05, 0.0, 0.05]), np.array([0.8, 0.3, 0.0]),
                      np.array([10.0, 5.0, 3.0])),
        State.release(scene, np.array([0.03, 0.02, 0.06]), np.array([-0.5, 0.6, 0.0]),
                      np.array([-4.0, 8.0, 3.0]))])
    return record(scene, (Die(), Die()), release, titles=["two in a tray"])[0]


@pytest.fixture(scope="module")
def page(throw: Recording, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The page of ``throw``."""
    return write_html(throw, tmp_path_factory.mktemp("page") / "throw.html")


def test_read_html_gives_the_data_back(throw: Recording, page: Path) -> None:
    assert read_html(page) == json.loads(json.dumps(as_data(throw)))
    (again,) = load(page)
    assert again.title == throw.title and again.outcome == throw.outcome
    assert np.array_equal(again.t, throw.t) and np.array_equal(again.position, throw.position)
    np.testing.assert_allclose(again.orientation, throw.orientation, atol=1e-12)
    assert again.release.position.tobytes() == throw.release.position.tobytes()


def test_page_is_self_contained(page: Path) -> None:
    text = page.read_text()
    assert "<script src" not in text and "<link" not in text  # nothing fetched at view time
    assert "Three.js Authors" in text and "SPDX-License-Identifier: MIT" in text
    assert "data:image/png;base64," in text  # the face textures


def test_page_of_a_two_second_throw_of_two_dice_is_small(throw: Recording,
                                                         tmp_path: Path) -> None:
    frames = round(2.0 * throw.fps) + 1  # 2 s of frames: the throw's, the last held
    hold = np.minimum(np.arange(frames), len(throw.t) - 1)
    long = dataclasses.replace(throw, t=np.arange(frames) / throw.fps,
                               position=throw.position[hold],
                               orientation=throw.orientation[hold])
    size = write_html(long, tmp_path / "long.html").stat().st_size
    print(f"page of a 2 s throw of two dice: {size} bytes")
    assert size < MAX_PAGE_BYTES


def test_bad_arguments_are_named(throw: Recording, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="layout"):
        write_html(throw, tmp_path / "a.html", layout="grid")
    with pytest.raises(ValueError, match=r"path must end in \.html"):
        write_html(throw, tmp_path / "a.htm")
    with pytest.raises(ValueError, match="recordings must not be empty"):
        write_html([], tmp_path / "a.html")
    for bad in ([throw, "throw"], 3):
        with pytest.raises(TypeError, match="recordings must be"):
            write_html(bad, tmp_path / "a.html")
    with pytest.raises(ValueError, match="finite"):
        write_html(dataclasses.replace(throw, position=throw.position * np.nan),
                   tmp_path / "a.html")
    (tmp_path / "other.html").write_text("<html></html>")
    with pytest.raises(ValueError, match="not a page"):
        read_html(tmp_path / "other.html")


@pytest.fixture(scope="module")
def browser_page(page: Path) -> Iterator[tuple[Any, list[str]]]:
    """The page open in headless Chromium, ready; and the errors it logged."""
    if browser.chromium() is None:
        pytest.skip("no Chromium (Debian: apt-get install chromium; .ci/setup installs it)")
    pytest.importorskip("playwright.sync_api", reason="no playwright (pip install playwright)")
    errors: list[str] = []
    with browser.opened(page, (VIEWPORT["width"], VIEWPORT["height"]), errors) as tab:
        yield tab, errors


def _goto(tab: Any, page: Path) -> None:
    tab.goto(page.resolve().as_uri())
    tab.wait_for_function(browser.READY, timeout=15_000)


@pytest.fixture(scope="module")
def aimed() -> list[Recording]:
    """Two still drops of a d6 held face 1 up, without hand noise: at target 1 and 6."""
    task = make_task(hand_noise=0.0, orientation_noise=0.0)
    _, hands = task.sample_hands([np.random.default_rng(0)] * 2, orientation_mode="identity")
    recordings = task_throws(task, np.zeros((2, 6)), np.array([1, 6]), hands,
                             task.sample_noise(np.random.default_rng(0), 2))
    assert [r.outcome["success"] for r in recordings] == [True, False]
    return recordings


def _heading(tab: Any, t: float) -> str:
    tab.evaluate(f"diceViewer.setTime({t!r})")
    return tab.evaluate("document.getElementById('dice-title').textContent")


# The canvas's pixels (RGBA) at CSS pixel points, read through a 2D canvas copy of it.
PIXELS = """points => {
  const gl = document.querySelector("canvas");
  const copy = Object.assign(document.createElement("canvas"),
                             {width: gl.width, height: gl.height}).getContext("2d");
  copy.drawImage(gl, 0, 0);
  const scale = gl.width / gl.clientWidth;
  return points.map(([x, y]) => Array.from(
    copy.getImageData(Math.round(x * scale), Math.round(y * scale), 1, 1).data));
}"""


def _pixels(tab: Any, points: list[tuple[float, float]]) -> np.ndarray:
    """The canvas's RGB at ``points`` (CSS pixels), as ints."""
    return np.array(tab.evaluate(PIXELS, [list(p) for p in points]))[:, :3].astype(int)


def _projected(camera: dict[str, Any], point: np.ndarray) -> np.ndarray:
    """``point`` (world) in canvas pixels through the page camera's matrices."""
    view = np.array(camera["view"]).reshape(4, 4).T  # three.js keeps them column-major
    projection = np.array(camera["projection"]).reshape(4, 4).T
    clip = projection @ view @ np.append(point, 1.0)
    x, y = clip[:2] / clip[3]
    return np.array([(x + 1) / 2 * camera["width"], (1 - y) / 2 * camera["height"]])


def test_page_draws_without_errors(browser_page: tuple[Any, list[str]]) -> None:
    tab, errors = browser_page
    assert errors == []
    assert tab.evaluate("diceViewer.frames.length") == 1
    grid = [(x, y) for x in range(20, VIEWPORT["width"], 40)
            for y in range(20, VIEWPORT["height"], 40)]
    colours = {tuple(c) for c in _pixels(tab, grid)}
    assert len(colours) >= 5, f"the canvas looks blank: colours {colours}"


def test_dice_are_drawn_where_recorded(browser_page: tuple[Any, list[str]],
                                       throw: Recording) -> None:
    tab, errors = browser_page
    n = len(throw.t)
    times = [0, n // 2, n - 1]  # frames: released, moving, at rest
    assert np.linalg.norm(throw.position[n // 2, 0] - throw.position[0, 0]) > 3 * Die().size
    seen: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # frame: (die 0's pixel, its colour)
    dice: dict[int, list[np.ndarray]] = {}  # frame: every die's pixel
    for i in times:
        tab.evaluate(f"diceViewer.setTime({float(throw.t[i])!r})")
        camera = tab.evaluate("diceViewer.camera()")
        dice[i] = [_projected(camera, throw.position[i, j]) for j in range(throw.n_dice)]
        for j in range(throw.n_dice):
            shown = np.array(tab.evaluate(f"diceViewer.project(0, {j})"))
            np.testing.assert_allclose(shown, dice[i][j], atol=0.5)
        patch = [tuple(_projected(camera, throw.position[i, 0] + offset)) for offset in PATCH]
        seen[i] = dice[i][0], patch, _pixels(tab, patch)
    # Die 0's patch of pixels looks different at the frame (of those) where every die is
    # farthest off: the die, not the floor, was there.
    for i, (centre, patch, colours) in seen.items():
        other = max(times, key=lambda k: min(np.linalg.norm(p - centre) for p in dice[k]))
        assert min(np.linalg.norm(p - centre) for p in dice[other]) > 20, \
            "the dice hardly moved on screen"
        tab.evaluate(f"diceViewer.setTime({float(throw.t[other])!r})")
        behind = _pixels(tab, patch)
        assert np.abs(colours - behind).max() > 24, \
            f"frame {i}: die 0's pixels {colours.tolist()} are what shows without it " \
            f"({behind.tolist()})"
    assert errors == []


def test_the_heading_gives_the_faces_and_total_when_the_dice_stop(
        browser_page: tuple[Any, list[str]], throw: Recording) -> None:
    tab, errors = browser_page
    faces = throw.outcome["faces"]
    assert all(throw.outcome["read"])
    assert _heading(tab, 0.0) == _heading(tab, float(throw.t[-1]) / 2) == "two in a tray"
    assert _heading(tab, 1e9) == \
        f"two in a tray: faces {faces[0]}, {faces[1]} (total {sum(faces)})"
    assert errors == []


def test_the_heading_gives_a_target_and_its_verdict_only_where_there_is_one(
        browser_page: tuple[Any, list[str]], page: Path, aimed: list[Recording],
        tmp_path: Path) -> None:
    tab, errors = browser_page
    try:
        for rec, verdict in zip(aimed, ("success", "failure"), strict=True):
            target, (face,) = rec.outcome["target"], rec.outcome["faces"]
            _goto(tab, write_html(rec, tmp_path / f"{verdict}.html"))
            assert _heading(tab, 0.0) == f"dice_env throws · target {target}"
            assert _heading(tab, 1e9) == \
                f"dice_env throws: faces {face} · target {target}: {verdict}"
    finally:
        _goto(tab, page)
    assert errors == []

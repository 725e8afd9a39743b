"""The renderer: every die with its labels, the walls, the shadow, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from dice_env.envs.render import WALL_ALPHA, has_pips, render_die, resting
from dice_env.model.die import STANDARD_SIZES, Die
from dice_env.model.scene import Scene
from dice_env.model.surroundings import walls
from studies.readme_figures import FIGURES, main

FIGURES_DIR = Path(__file__).resolve().parents[1] / "docs" / "figures"
CUBOID = Die.cuboid((0.012, 0.016, 0.02))
DICE = [Die.standard(name) for name in STANDARD_SIZES] + [CUBOID]


def is_floor(image: np.ndarray) -> np.ndarray:
    """Felt (green), with or without grid and shadow."""
    r, g, _ = np.moveaxis(image.astype(int), -1, 0)
    return g > r + 20


def is_ink(image: np.ndarray) -> np.ndarray:
    """Pips and numerals."""
    return image.max(axis=-1) < 80


def is_wood(image: np.ndarray) -> np.ndarray:
    """The walls' colour."""
    r, g, b = np.moveaxis(image.astype(int), -1, 0)
    return (r > 40) & (r > 1.4 * g) & (r > 2 * b)


def top_face_disc(die: Die, label: int, size: int, view_edges: float) -> np.ndarray:
    """Pixels within the inscribed circle of the regular top face, seen from straight above."""
    corners = np.asarray(die.vertices)[list(die.faces[label - 1])]
    centre = corners.mean(axis=0)
    sides = np.roll(corners, -1, axis=0) - corners
    inradius = min(np.linalg.norm(np.cross(s, centre - c)) / np.linalg.norm(s)
                   for s, c in zip(sides, corners, strict=True))
    radius = 0.95 * inradius * size / (view_edges * die.size)
    rows, cols = np.mgrid[:size, :size] - (size - 1) / 2
    return rows**2 + cols**2 < radius**2


@pytest.mark.parametrize("die", DICE, ids=lambda die: die.name)
def test_every_die_renders_over_the_image_centre(die):
    scene = Scene(die=die)
    for label in (1, die.n_faces):
        position, orientation = resting(die, label, turn=0.4)
        image = render_die(scene, position, orientation, size=(48, 64))
        assert image.shape == (48, 64, 3) and image.dtype == np.uint8
        assert not is_floor(image[22:26, 30:34]).any()  # the die covers the centre
        assert is_floor(image[:4, :4]).all()


@pytest.mark.parametrize("die", DICE, ids=lambda die: die.name)
def test_resting_reads_the_label_with_the_lowest_corner_on_the_floor(die):
    for label in range(1, die.n_faces + 1):
        position, orientation = resting(die, label, at=(0.1, -0.2), turn=1.0)
        assert die.face_read(orientation, np.array([0.0, 0.0, 1.0])) == label
        lowest = (position + die.vertices_body @ orientation.T).min(axis=0)
        assert lowest[2] == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(position[:2], (0.1, -0.2))


@pytest.mark.parametrize("die", [Die(), CUBOID], ids=["d6", "cuboid"])
def test_pips_on_the_top_face_count_its_label(die):
    scene = Scene(die=die)
    for label in range(1, 7):
        position, orientation = resting(die, label, turn=0.3)
        image = render_die(scene, position, orientation, size=(96, 96), elevation=90.0)
        assert ndimage.label(is_ink(image))[1] == label


def test_numerals_on_the_top_face_of_the_d20():
    # Straight above, inside the top face: one component per digit, plus 6's and 9's underline.
    die = Die.standard("d20")
    for label in range(1, 21):
        position, orientation = resting(die, label, turn=0.2)
        image = render_die(Scene(die=die), position, orientation, size=(160, 160),
                           elevation=90.0, view_edges=1.5)
        ink = is_ink(image) & top_face_disc(die, label, 160, 1.5)
        assert ndimage.label(ink)[1] == len(str(label)) + (label in (6, 9)), label


def test_only_the_d6_and_cuboids_have_pips():
    assert has_pips(Die()) and has_pips(CUBOID) and has_pips(Die.loaded(3))
    assert not any(has_pips(Die.standard(name)) for name in ("d4", "d8", "d10", "d12", "d20"))
    cube = Die.from_vertices(np.asarray(Die().vertices), labels=[2, 1, 3, 4, 5, 6])
    assert not has_pips(cube)  # a cube numbered otherwise shows numerals
    assert is_ink(render_die(Scene(die=cube), *resting(cube, 1), elevation=90.0)).any()


def test_the_tray_shows_its_walls_in_a_wide_view_only():
    scene = Scene(walls=walls("tray"))
    position, orientation = resting(scene.die, 1, at=(0.02, 0.01))
    wide = render_die(scene, position, orientation, elevation=90.0, view_edges=25.0)
    narrow = render_die(scene, position, orientation, elevation=90.0)
    assert is_wood(wide).any() and not is_wood(narrow).any()
    assert not is_wood(render_die(Scene(), position, orientation, view_edges=25.0)).any()


def test_a_wall_in_front_of_the_die_is_translucent():
    scene = Scene(walls=walls("tray"))
    position, orientation = resting(scene.die, 3, at=(0.14, 0.0))  # 1 cm inside the +x wall
    image = render_die(scene, position, orientation, elevation=20.0, azimuth=0.0,
                       view_edges=4.0).astype(int)
    row = image[120]
    assert is_wood(row[[5, -5]]).all() and np.array_equal(row[5], row[-5])  # the board alone
    alone = render_die(Scene(), position, orientation, elevation=20.0, azimuth=0.0,
                       view_edges=4.0).astype(int)[120, 160]
    np.testing.assert_allclose(row[160], WALL_ALPHA * row[5] + (1 - WALL_ALPHA) * alone,
                               atol=2)  # the die seen through the board


def test_the_shadow_lies_below_the_die():
    die = Die.standard("d12")
    position, orientation = resting(die, 1)
    lifted = position + np.array([0.0, 0.0, 0.02])  # the shadow straight below, lower in the image
    image = render_die(Scene(die=die), lifted, orientation, elevation=45.0, azimuth=-90.0)
    felt = is_floor(image)
    shadow = felt & (image[..., 1] < 0.7 * image[..., 1][felt].max())
    rows = np.arange(240)[:, None] + np.zeros((1, 320))
    assert shadow.sum() > 200
    assert rows[shadow].mean() > rows[~felt].mean() + 20
    assert not (shadow & (rows < 120)).any()


@pytest.mark.parametrize(("keyword", "value"), [
    ("orientation", np.eye(2)), ("position", np.zeros(2)), ("size", (0, 10)),
    ("elevation", 0.0), ("elevation", 91.0), ("azimuth", np.nan), ("view_edges", -1.0),
])
def test_bad_input_names_the_parameter(keyword, value):
    args = {"position": np.zeros(3), "orientation": np.eye(3)}
    kwargs = {}
    (args if keyword in args else kwargs)[keyword] = value
    with pytest.raises(ValueError, match=keyword):
        render_die(Scene(), args["position"], args["orientation"], **kwargs)


def test_resting_refuses_a_label_the_die_lacks():
    for label in (0, 7, 2.0, True):
        with pytest.raises(ValueError, match=r"label must be an int in \[1, 6\]"):
            resting(Die(), label)


@pytest.mark.slow
def test_the_committed_figures_are_what_their_command_draws(tmp_path):
    """``python -m studies.readme_figures NAME`` redraws docs/figures/NAME.png pixel for pixel."""
    for name in FIGURES:
        main([name, "--out", str(tmp_path / f"{name}.png")])
        drawn = np.asarray(Image.open(tmp_path / f"{name}.png").convert("RGB"))
        committed = np.asarray(Image.open(FIGURES_DIR / f"{name}.png").convert("RGB"))
        assert drawn.shape == committed.shape, name
        differ = (drawn != committed).any(axis=-1).mean()
        assert differ == 0.0, f"{name}: {differ:.1%} of the pixels differ; redraw it with " \
            f"python -m studies.readme_figures {name} --out docs/figures/{name}.png"

"""A headless numpy renderer of convex dice with their labels, the walls and the floor.

An orthographic camera looks down at the dice; each pixel casts a ray against the dice (face
half-spaces) and the walls (boards :data:`WALL_HEIGHT` high, translucent in front of a die).
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from dice_env.envs.throw_task import ThrowTask
from dice_env.model.checks import as_shaped, check_int, check_positive, check_range
from dice_env.model.die import Die
from dice_env.model.rotations import axis_angle
from dice_env.model.scene import Plane, Scene

# In-face axes (u, v) of the d6's pip faces, body frame, so that u x v is the outward normal.
FACE_U = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 1, 0]], float)
_D6_NORMALS = Die().face_normals
FACE_V = np.cross(_D6_NORMALS, FACE_U)
# Pip centres in face coordinates (u, v in [-1, 1], units of half the face's shorter side).
PIPS = (
    ((0, 0),),
    ((-0.5, -0.5), (0.5, 0.5)),
    ((-0.5, -0.5), (0, 0), (0.5, 0.5)),
    ((-0.5, -0.5), (-0.5, 0.5), (0.5, -0.5), (0.5, 0.5)),
    ((-0.5, -0.5), (-0.5, 0.5), (0.5, -0.5), (0.5, 0.5), (0, 0)),
    ((-0.5, -0.5), (-0.5, 0), (-0.5, 0.5), (0.5, -0.5), (0.5, 0), (0.5, 0.5)),
)
PIP_RADIUS = 0.19  # in units of half the face's shorter side
RIM_WIDTH = 0.035  # faces are darkened this close to their edges, in die sizes
FACE_COLOUR = np.array([245, 240, 225], float)
PIP_COLOUR = np.array([25, 25, 35], float)  # pips and numerals
TABLE_COLOUR = np.array([40, 110, 60], float)  # felt green
BEYOND_COLOUR = np.array([95, 90, 85], float)  # the floor outside the walls
WALL_COLOUR = np.array([120, 75, 40], float)  # dark wood
WALL_HEIGHT = 0.025  # m: drawn height of a wall above the floor (drawing only)
WALL_THICKNESS = 0.006  # m: drawn thickness behind the wall's plane (drawing only)
WALL_ALPHA = 0.35  # opacity of a wall in front of the die
# Numerals: glyph box 0.6 wide by 1 high, strokes of half-width STROKE, digits ADVANCE apart,
# the underline UNDERLINE below the baseline.
STROKE = 0.08
ADVANCE = 0.85
UNDERLINE = -0.25
NUMERAL_FILL = 0.9  # the diagonal of the widest label's box over the inscribed diameter
D4_PLACE, D4_HEIGHT = 0.5, 0.38  # d4 numerals: centre and height in centre-to-corner distances
# Digits that read as a digit upside down (turned by 180 degrees).
UPSIDE_DOWN = {"0": "0", "1": "1", "6": "9", "8": "8", "9": "6"}


def _arc(cx: float, cy: float, rx: float, ry: float, start: float, stop: float,
         n: int) -> np.ndarray:
    """Points (n, 2) on an elliptic arc from ``start`` to ``stop`` degrees."""
    angle = np.radians(np.linspace(start, stop, n))
    return np.stack([cx + rx * np.cos(angle), cy + ry * np.sin(angle)], axis=1)


_SIX = (np.vstack([_arc(0.62, 0.32, 0.62, 0.68, 100, 180, 6),
                   _arc(0.3, 0.3, 0.3, 0.3, 180, -180, 20)]),)
# The digits as polylines in their box (x in [0, 0.6], y in [0, 1], y up).
GLYPHS = {
    "0": (_arc(0.3, 0.5, 0.3, 0.5, 0, 360, 24),),
    "1": (np.array([(0.1, 0.78), (0.32, 1.0), (0.32, 0.0)]),),
    "2": (np.vstack([_arc(0.3, 0.7, 0.28, 0.3, 165, -30, 10), [(0, 0), (0.6, 0)]]),),
    "3": (np.vstack([_arc(0.3, 0.76, 0.26, 0.24, 150, -90, 10),
                     _arc(0.3, 0.27, 0.3, 0.27, 90, -150, 12)]),),
    "4": (np.array([(0.45, 0.0), (0.45, 1.0), (0.0, 0.32), (0.6, 0.32)]),),
    "5": (np.vstack([[(0.55, 1.0), (0.1, 1.0), (0.06, 0.56)],
                     _arc(0.3, 0.32, 0.3, 0.32, 135, -140, 12)]),),
    "6": _SIX,
    "7": (np.array([(0.0, 1.0), (0.6, 1.0), (0.18, 0.0)]),),
    "8": (_arc(0.3, 0.76, 0.24, 0.24, 0, 360, 16), _arc(0.3, 0.27, 0.3, 0.27, 0, 360, 20)),
    "9": tuple((0.6, 1.0) - line for line in _SIX),
}


@dataclass(frozen=True)
class FaceArt:
    """What is drawn on one face, in its own frame (metres).

    ``centre`` (3,) body frame; ``axes`` (2, 3): the in-face unit axes u, v (u x v outward);
    ``edges`` (P, 3): inward edge lines ``(n_u, n_v, c)``, distance ``n . (u, v) - c``;
    ``pips`` (Q, 2); ``strokes`` (S, 2, 2) the numerals' segments, ``widths`` (S,) their
    half-widths, all within ``reach`` of the face's origin.
    """

    centre: np.ndarray
    axes: np.ndarray
    edges: np.ndarray
    pips: np.ndarray
    pip_radius: float
    strokes: np.ndarray
    widths: np.ndarray
    reach: float


@dataclass(frozen=True)
class View:
    """The camera of :func:`render_die` and :func:`render_dice`, given as their keywords.

    ``size`` (height, width) in pixels; ``elevation`` (degrees, (0, 90]); ``azimuth`` (degrees,
    [-360, 360]); ``view_edges``: the image width in die sizes.
    """

    size: tuple[int, int] = (240, 320)
    elevation: float = 55.0
    azimuth: float = -60.0
    view_edges: float = 5.0

    def __post_init__(self) -> None:
        if (not isinstance(self.size, (tuple, list)) or len(self.size) != 2 or not all(
                isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 1
                for n in self.size)):
            raise ValueError(f"size must be (height, width), two ints >= 1, got {self.size!r}")
        check_range("elevation", self.elevation, 0.0, 90.0, low_open=True)
        check_range("azimuth", self.azimuth, -360.0, 360.0)
        check_positive("view_edges", self.view_edges)


def render_die(scene: Scene, position: np.ndarray, orientation: np.ndarray,
               **view: Any) -> np.ndarray:
    """An RGB image (height, width, 3) uint8 of the die in the scene: floor, walls, shadow.

    ``position`` (3,) centre of mass, ``orientation`` (3, 3) body to world; ``view``: the
    camera's keywords (:class:`View`).
    """
    camera = View(**view)
    position = as_shaped("position", position, (3,))
    orientation = as_shaped("orientation", orientation, (3, 3))
    die = scene.die
    centre = position - orientation @ np.asarray(die.com)  # geometric centre, camera target
    return _render(scene, [(die, np.zeros(3), orientation)], centre,
                   camera.view_edges * die.size, camera)


def render_dice(scene: Scene, dice: tuple[Die, ...], positions: np.ndarray,
                orientations: np.ndarray, **view: Any) -> np.ndarray:
    """An RGB image (height, width, 3) uint8 of several dice in the scene, as :func:`render_die`.

    ``positions`` (N, 3) centres of mass, ``orientations`` (N, 3, 3). The camera looks at the
    middle of the dice; the image is ``view_edges`` largest dice wide, or wider to show all.
    """
    camera = View(**view)
    positions = as_shaped("positions", positions, (len(dice), 3))  # a row per die
    orientations = as_shaped("orientations", orientations, (len(dice), 3, 3))
    centres = positions - np.einsum("nij,nj->ni", orientations, [d.com for d in dice])
    centre = (centres.min(axis=0) + centres.max(axis=0)) / 2
    largest = max(d.size for d in dice)
    spread = float(np.ptp(centres, axis=0).max()) + 2 * largest
    return _render(scene, list(zip(dice, centres - centre, orientations, strict=True)), centre,
                   max(camera.view_edges * largest, spread), camera)


# The dice to draw: each die, its geometric centre from the camera's target (m), its orientation.
_Dice = list[tuple[Die, np.ndarray, np.ndarray]]


def _render(scene: Scene, dice: _Dice, centre: np.ndarray, view: float,
            camera_view: View) -> np.ndarray:
    """The image of ``dice`` about ``centre`` (the camera's target), ``view`` m wide."""
    height, width = camera_view.size
    normal = np.asarray(scene.ground.normal)
    forward, right, up = _camera(normal, math.radians(camera_view.elevation),
                                 math.radians(camera_view.azimuth))
    scale = view / width  # metres per pixel
    xs = (np.arange(width) - (width - 1) / 2) * scale
    ys = ((height - 1) / 2 - np.arange(height)) * scale
    camera = _Lines(np.zeros(3), forward, right, up)
    light = _unit(normal + 0.4 * right + 0.3 * up)

    floor = _floor_lines(scene, centre, camera)
    image = _floor(scene, centre, floor, dice, xs, ys, scale)
    depth = np.full((height, width), np.inf)
    for planes in _boards(scene, centre):
        if not _in_view(planes, floor, xs, ys):
            continue
        t, face = _clip(planes, camera, xs, ys)
        near = t < depth
        depth[near] = t[near]
        shade = 0.45 + 0.55 * np.maximum(0.0, planes[:, :3] @ light)
        image[near] = WALL_COLOUR * shade[face[near], None]
    nearest = np.full((height, width), np.inf)  # the nearest die drawn so far
    for pose in dice:
        _draw_die(image, depth, nearest, pose, camera, xs, ys, scale, light)
    return np.clip(image, 0, 255).astype(np.uint8)


def render_task(task: ThrowTask, position: np.ndarray, orientation: np.ndarray,
                **view: object) -> np.ndarray:
    """The frame of a task's die ((3,), (3, 3)) or dice ((N, 3), (N, 3, 3)); ``view`` as there."""
    if task.n_dice == 1:
        return render_die(task.scene, position, orientation, **view)
    return render_dice(task.scene, task.dice, position, orientation, **view)


# --- geometry -----------------------------------------------------------------------------

@dataclass(frozen=True)
class _Lines:
    """A family of lines ``base + x dx + y dy + t direction`` (relative to the die's centre)."""

    base: np.ndarray
    direction: np.ndarray
    dx: np.ndarray
    dy: np.ndarray

    def at(self, vector: np.ndarray, xs: np.ndarray, ys: np.ndarray, constant: float) -> np.ndarray:
        """``vector . (base + x dx + y dy) - constant`` on the grid (len(ys), len(xs))."""
        row = xs * (vector @ self.dx) + (vector @ self.base - constant)
        return (ys * (vector @ self.dy))[:, None] + row[None, :]


def _clip(planes: np.ndarray, lines: _Lines, xs: np.ndarray,
          ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each line enters the convex set ``n . x <= c`` of ``planes`` (K, 4) rows (n, c).

    Returns the entry parameter t along ``lines.direction`` (inf: a miss) and the entry plane.
    """
    shape = (len(ys), len(xs))
    low, high = np.full(shape, -np.inf), np.full(shape, np.inf)
    entry = np.zeros(shape, dtype=np.intp)
    for k, (n, c) in enumerate(zip(planes[:, :3], planes[:, 3], strict=True)):
        rate = n @ lines.direction
        if rate == 0.0:  # parallel: inside the half-space or not at all
            np.maximum(low, np.where(lines.at(n, xs, ys, c) > 0, np.inf, -np.inf), out=low)
            continue
        t = lines.at(n, xs, ys, c) * (-1.0 / rate)
        if rate < 0:
            entry[t > low] = k
            np.maximum(low, t, out=low)
        else:
            np.minimum(high, t, out=high)
    return np.where(low <= high, low, np.inf), entry


def _camera(normal: np.ndarray, elevation: float, azimuth: float) -> tuple[np.ndarray, ...]:
    """Unit vectors (forward, right, up) of a camera looking down at the table."""
    tangent, bitangent = _plane_axes(normal)
    horizontal = math.cos(azimuth) * tangent + math.sin(azimuth) * bitangent
    forward = -(math.sin(elevation) * normal + math.cos(elevation) * horizontal)
    right = _unit(np.cross(forward, normal))
    return forward, right, np.cross(right, forward)


def _plane_axes(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors spanning the table (x and y for a level table)."""
    bitangent = _unit(np.cross(normal, [1.0, 0.0, 0.0]))
    return np.cross(bitangent, normal), bitangent


def _unit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def _die_planes(die: Die, orientation: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """The die's face half-spaces (F, 4) rows (n, c) about the camera's target, ``offset`` off."""
    normals = die.face_normals @ orientation.T
    return np.column_stack([normals, _face_offsets(die) + normals @ offset])


def _boards(scene: Scene, centre: np.ndarray) -> list[np.ndarray]:
    """Each wall's board (to the other walls' outer faces) as rows (n, c) about ``centre``."""
    floor, *rows = (_plane_row(plane, centre) for plane in scene.planes)
    thick, high = np.array([0, 0, 0, WALL_THICKNESS]), np.array([0, 0, 0, WALL_HEIGHT])
    return [np.array([wall, thick - wall, floor + high, -floor,  # then the other walls' ends
                      *(thick - row for j, row in enumerate(rows) if j != i)])
            for i, wall in enumerate(rows)]


def _in_view(planes: np.ndarray, floor: _Lines, xs: np.ndarray, ys: np.ndarray) -> bool:
    """Whether the board (K, 4) may be in view: not all of the view's box outside one plane."""
    corners = np.array([floor.base + x * floor.dx + y * floor.dy + h * floor.direction
                        for x in xs[[0, -1]] for y in ys[[0, -1]] for h in (0.0, WALL_HEIGHT)])
    return not np.any(np.all(corners @ planes[:, :3].T > planes[:, 3], axis=0))


def _plane_row(plane: Plane, centre: np.ndarray) -> np.ndarray:
    """The half-space ``normal . x <= offset`` of ``plane`` about ``centre``, as a row (n, c)."""
    n = np.asarray(plane.normal)
    return np.append(n, plane.offset - n @ centre)


# --- the floor ----------------------------------------------------------------------------

def _floor_lines(scene: Scene, centre: np.ndarray, camera: _Lines) -> _Lines:
    """The vertical lines through the points where the camera rays meet the floor."""
    normal, offset = np.asarray(scene.ground.normal), scene.ground.offset
    rate = camera.direction @ normal
    base = camera.direction * (offset - normal @ centre) / rate
    dx, dy = (d - camera.direction * (normal @ d) / rate for d in (camera.dx, camera.dy))
    return _Lines(base, normal, dx, dy)


def _floor(scene: Scene, centre: np.ndarray, floor: _Lines, dice: _Dice,
           xs: np.ndarray, ys: np.ndarray, scale: float) -> np.ndarray:
    """Floor colour per pixel: felt inside the walls, a grid of one die size, the shadows."""
    size = max(die.size for die, _, _ in dice)  # the grid's cell
    width = max(0.02, 0.6 * scale / size)  # grid line half-width, in sizes
    grid = np.zeros((len(ys), len(xs)), dtype=bool)
    for axis in _plane_axes(floor.direction):
        cells = floor.at(axis, xs, ys, -axis @ centre) / size
        grid |= np.abs((cells + 0.5) % 1.0 - 0.5) < width
    beyond = np.zeros_like(grid)
    for wall in scene.walls:
        row = _plane_row(wall, centre)
        beyond |= floor.at(row[:3], xs, ys, row[3]) < 0
    colour = np.where(beyond[..., None], BEYOND_COLOUR, TABLE_COLOUR)
    image = np.where(grid[..., None], colour * 1.25, colour)
    shadow, normal = np.zeros_like(grid), np.asarray(scene.ground.normal)
    for die, offset, orientation in dice:
        corners = np.asarray(die.vertices) @ orientation.T + offset
        lift = corners @ normal + normal @ centre - scene.ground.offset  # above the floor
        rows, cols = _box(corners - np.outer(lift, normal), floor, xs, ys)  # the shadow's box
        t, _ = _clip(_die_planes(die, orientation, offset), floor, xs[cols], ys[rows])
        shadow[rows, cols] |= np.isfinite(t)
    image *= np.where(shadow, 0.55, 1.0)[..., None]
    return image


def _box(points: np.ndarray, lines: _Lines, xs: np.ndarray,
         ys: np.ndarray) -> tuple[slice, slice]:
    """The pixel rows and columns whose lines pass near ``points`` (N, 3), about the centre."""
    basis = np.array([lines.dx, lines.dy])
    screen = np.linalg.solve(basis @ basis.T, basis @ (points - lines.base).T)
    step = xs[1] - xs[0] if len(xs) > 1 else 1.0
    cols = np.searchsorted(xs, [screen[0].min() - step, screen[0].max() + step])
    rows = np.searchsorted(-ys, [-screen[1].max() - step, -screen[1].min() + step])
    return slice(*rows), slice(*cols)


# --- the die ------------------------------------------------------------------------------

def _draw_die(image: np.ndarray, depth: np.ndarray, nearest: np.ndarray,
              pose: tuple[Die, np.ndarray, np.ndarray], camera: _Lines, xs: np.ndarray,
              ys: np.ndarray, scale: float, light: np.ndarray) -> None:
    """Draw ``pose`` (die, offset, orientation) where no die in ``nearest`` (depths) is nearer.

    A nearer board (``depth``) stays in front, translucent.
    """
    die, offset, orientation = pose
    rows, cols = _box(np.asarray(die.vertices) @ orientation.T + offset, camera, xs, ys)
    planes = _die_planes(die, orientation, offset)
    t, entry = _clip(planes, camera, xs[cols], ys[rows])
    crop, behind, front = image[rows, cols], depth[rows, cols], nearest[rows, cols]
    t = np.where(t < front, t, np.inf)  # behind a die drawn before: hidden
    np.minimum(front, t, out=front)
    px, py = np.meshgrid(xs[cols], ys[rows])
    for k, art in enumerate(face_art(die)):
        hit = np.isfinite(t) & (entry == k)
        if not hit.any():
            continue
        axes = art.axes @ orientation.T  # world frame
        origin = orientation @ art.centre + offset
        screen = np.array([camera.dx, camera.dy])
        uv = np.linalg.solve(screen @ axes.T, np.stack([px[hit], py[hit]]) -
                             (screen @ origin)[:, None]).T
        shade = 0.45 + 0.55 * max(0.0, float(planes[k, :3] @ light))
        colour = face_colour(art, uv, shade, RIM_WIDTH * die.size, scale)
        ahead = (t[hit] < behind[hit])[:, None]
        crop[hit] = np.where(ahead, colour, WALL_ALPHA * crop[hit] + (1 - WALL_ALPHA) * colour)
    image[rows, cols] = crop
    nearest[rows, cols] = front


def face_colour(art: FaceArt, uv: np.ndarray, shade: float, rim: float,
                scale: float) -> np.ndarray:
    """Colour (M, 3) of the face at points ``uv`` (M, 2): shaded, darker near the rim, inked."""
    edge = (uv @ art.edges[:, :2].T - art.edges[:, 2]).min(axis=1)
    face = FACE_COLOUR * np.where(edge < rim, 0.8 * shade, shade)[:, None]
    ink = np.zeros(len(uv))
    if len(art.pips):
        gaps = ((uv[:, None, :] - art.pips[None]) ** 2).sum(axis=-1)
        ink = (gaps.min(axis=1) < art.pip_radius**2).astype(float)
    if len(art.strokes):
        near = np.einsum("mi,mi->m", uv, uv) < (art.reach + scale) ** 2
        depth = (art.widths - _segment_distance(uv[near], art.strokes)).max(axis=1)
        ink[near] = np.clip(depth / scale + 0.5, 0.0, 1.0)  # about one pixel of antialiasing
    return face + ink[:, None] * (PIP_COLOUR - face)


def _segment_distance(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Distance (M, S) from each point (M, 2) to each segment (S, 2, 2)."""
    start, step = segments[:, 0], segments[:, 1] - segments[:, 0]
    rel = points[:, None, :] - start[None]
    length2 = np.maximum(np.einsum("si,si->s", step, step), 1e-300)
    along = np.clip(np.einsum("msi,si->ms", rel, step) / length2, 0.0, 1.0)
    gap = rel - along[..., None] * step
    return np.sqrt(np.einsum("msi,msi->ms", gap, gap))


# --- what each face carries ---------------------------------------------------------------

@lru_cache(maxsize=64)
def _face_offsets(die: Die) -> np.ndarray:
    """Distance (m) of each face plane from the geometric centre, (F,)."""
    vertices = np.asarray(die.vertices)
    return np.einsum("fi,fi->f", die.face_normals, vertices[[f[0] for f in die.faces]])


def has_pips(die: Die) -> bool:
    """True for a die drawn with pips: six faces numbered like the d6 (the d6, the cuboids)."""
    return (die.n_faces == 6 and not die.reads_down
            and bool(np.allclose(die.face_normals, _D6_NORMALS, atol=1e-9)))


@lru_cache(maxsize=64)
def face_art(die: Die) -> tuple[FaceArt, ...]:
    """What each face of ``die`` carries, in label order (computed once per die)."""
    vertices = np.asarray(die.vertices)
    polygons = [vertices[list(face)] for face in die.faces]
    if has_pips(die):
        return tuple(_pip_face(polygon, k) for k, polygon in enumerate(polygons))
    shift = 1 if die.name == "d10" else 0  # the d10 prints digits 0-9
    texts = [str(label - shift) for label in die.labels]
    fit = max(_text_radius(text, texts) for text in texts)
    art = []
    for text, polygon, normal in zip(texts, polygons, die.face_normals, strict=True):
        centre, axes = _numeral_frame(polygon, normal)
        flat = (polygon - centre) @ axes.T
        if die.reads_down:  # a d4: near each corner, upright towards it, read with that corner up
            placed = []
            for corner, spot in zip(polygon, flat, strict=True):
                reach = float(np.linalg.norm(spot))
                label = int(np.argmax(die.reading @ _unit(corner)))
                placed.append((texts[label], D4_PLACE * spot, spot / reach, D4_HEIGHT * reach))
        else:
            inradius = float(-_edge_lines(flat)[:, 2].max())  # about the face's origin
            placed = [(text, np.zeros(2), np.array([0.0, 1.0]), NUMERAL_FILL * inradius / fit)]
        art.append(_numeral_face(centre, axes, flat, placed, texts))
    return tuple(art)


def _pip_face(polygon: np.ndarray, k: int) -> FaceArt:
    """Face ``k`` of a d6-like die: pips of face ``k + 1`` on its own axes FACE_U, FACE_V."""
    centre, axes = polygon.mean(axis=0), np.array([FACE_U[k], FACE_V[k]])
    flat = (polygon - centre) @ axes.T
    half = float(np.ptp(flat, axis=0).min()) / 2
    return FaceArt(centre, axes, _edge_lines(flat), np.array(PIPS[k], float) * half,
                    PIP_RADIUS * half, np.zeros((0, 2, 2)), np.zeros(0), 0.0)


def _numeral_frame(polygon: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The face's area centroid and axes (u, v), v (up) towards the corner nearest +z (or +y)."""
    fan = np.cross(polygon[1:-1] - polygon[0], polygon[2:] - polygon[0]) @ normal
    centre = (fan @ (polygon[0] + polygon[1:-1] + polygon[2:]) / 3) / fan.sum()
    reference = np.eye(3)[2] - normal[2] * normal
    if np.linalg.norm(reference) < 0.3:
        reference = np.eye(3)[1] - normal[1] * normal
    corners = polygon - centre
    up = _unit(corners[np.argmax(corners @ reference / np.linalg.norm(corners, axis=1))])
    return centre, np.array([np.cross(up, normal), up])


def _edge_lines(flat: np.ndarray) -> np.ndarray:
    """Inward edge lines (P, 3) ``(n_u, n_v, c)`` of a counter-clockwise polygon (P, 2)."""
    step = np.roll(flat, -1, axis=0) - flat
    inward = np.stack([-step[:, 1], step[:, 0]], axis=1) / np.linalg.norm(step, axis=1)[:, None]
    return np.column_stack([inward, (inward * flat).sum(axis=1)])


def _underlined(text: str, texts: list[str]) -> bool:
    """6 and 9, and any text that reads as another of ``texts`` upside down."""
    turned = "".join(UPSIDE_DOWN.get(digit, "?") for digit in reversed(text))
    return text in ("6", "9") or (turned != text and turned in texts)


def _text_radius(text: str, texts: list[str]) -> float:
    """Half the diagonal of ``text``'s box (strokes and underline included), glyph units."""
    width = ADVANCE * (len(text) - 1) + 0.6 + 2 * STROKE
    height = 1 + 2 * STROKE - (UNDERLINE if _underlined(text, texts) else 0.0)
    return math.hypot(width, height) / 2


def _numeral_face(centre: np.ndarray, axes: np.ndarray, flat: np.ndarray,
                  placed: list[tuple[str, np.ndarray, np.ndarray, float]],
                  texts: list[str]) -> FaceArt:
    """A face with numerals: ``placed`` (text, centre, up, height) in face coordinates."""
    strokes, widths = [], []
    for text, middle, up, height in placed:
        glyph = _text_strokes(text, _underlined(text, texts))
        turn = np.array([[up[1], -up[0]], [up[0], up[1]]])  # glyph x, y to face u, v
        strokes.append(middle + height * glyph @ turn)
        widths.append(np.full(len(glyph), STROKE * height))
    strokes, widths = np.concatenate(strokes), np.concatenate(widths)
    reach = float(np.linalg.norm(strokes, axis=-1).max() + widths.max())
    return FaceArt(centre, axes, _edge_lines(flat), np.zeros((0, 2)), 0.0, strokes, widths, reach)


@lru_cache(maxsize=256)
def _text_strokes(text: str, underline: bool) -> np.ndarray:
    """Segments (S, 2, 2) of ``text`` in glyph units, its box centred on the origin."""
    lines = [line + np.array([ADVANCE * i, 0.0])
             for i, digit in enumerate(text) for line in GLYPHS[digit]]
    width = ADVANCE * (len(text) - 1) + 0.6
    if underline:
        lines.append(np.array([(0.0, UNDERLINE), (width, UNDERLINE)]))
    segments = np.concatenate([np.stack([line[:-1], line[1:]], axis=1) for line in lines])
    low = UNDERLINE if underline else 0.0
    return segments - (width / 2, (1 + low) / 2)


# --- poses and the window -----------------------------------------------------------------

def resting(die: Die, label: int, at: tuple[float, float] = (0.0, 0.0),
            turn: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Centre of mass and orientation of ``die`` reading ``label`` on a level floor at z = 0.

    ``at``: (x, y) (m); ``turn``: rad about the vertical.
    """
    check_int("label", label, 1, die.n_faces)
    reading = die.reading[label - 1]
    axis = np.cross(reading, [0.0, 0.0, 1.0])
    if np.linalg.norm(axis) > 1e-12:
        tilt = axis_angle(axis, math.acos(np.clip(reading[2], -1.0, 1.0)))
    else:  # already vertical: upright, or half a turn about x
        flip = float(np.sign(reading[2]))
        tilt = np.diag([1.0, flip, flip])
    orientation = axis_angle([0.0, 0.0, 1.0], turn) @ tilt
    return np.array([*at, die.resting_heights[label - 1]]), orientation


class Viewer:
    """A matplotlib window showing frames at ``fps``; does nothing where there is no display."""

    def __init__(self, fps: float) -> None:
        self.fps, self._figure, self._image = fps, None, None

    def show(self, frame: np.ndarray) -> None:
        """Show ``frame`` (H, W, 3) uint8 and wait one frame interval."""
        if not (sys.platform.startswith(("darwin", "win")) or os.environ.get("DISPLAY")
                or os.environ.get("WAYLAND_DISPLAY")):  # no window can open
            return
        try:
            import matplotlib.pyplot as plt
        except ImportError as error:
            raise ImportError("render_mode='human' draws in a matplotlib window: pip install "
                              "matplotlib, or use render_mode='rgb_array'") from error
        if self._figure is None:
            plt.ion()
            self._figure, axes = plt.subplots()
            axes.set_axis_off()
            self._image = axes.imshow(frame)
        else:
            self._image.set_data(frame)
        plt.pause(1.0 / self.fps)

    def close(self) -> None:
        """Close the window."""
        if self._figure is not None:
            import matplotlib.pyplot as plt

            plt.close(self._figure)
            self._figure = None

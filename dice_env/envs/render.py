"""A headless software renderer of the die with its pips (numpy only), and a window for "human".

Orthographic camera looking down at the die from ``elevation`` degrees above the table, centred
on the die so a rolling die stays in view; the table carries a grid of one edge
length (to show motion) and the die's shadow straight below it. Faces are shaded by a fixed
light; pips are drawn as discs on the faces in the standard layout.
"""

from __future__ import annotations

import math
import os
import sys

import numpy as np

from dice_env.die import FACE_NORMALS
from dice_env.scene import Scene

# In-face axes (u, v) per face, body frame, so that u x v is the outward normal.
FACE_U = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 1, 0]], float)
FACE_V = np.cross(FACE_NORMALS, FACE_U)
# Pip centres in face coordinates (u, v in [-1, 1]) for faces 1-6.
PIPS = (
    ((0, 0),),
    ((-0.5, -0.5), (0.5, 0.5)),
    ((-0.5, -0.5), (0, 0), (0.5, 0.5)),
    ((-0.5, -0.5), (-0.5, 0.5), (0.5, -0.5), (0.5, 0.5)),
    ((-0.5, -0.5), (-0.5, 0.5), (0.5, -0.5), (0.5, 0.5), (0, 0)),
    ((-0.5, -0.5), (-0.5, 0), (-0.5, 0.5), (0.5, -0.5), (0.5, 0), (0.5, 0.5)),
)
PIP_RADIUS = 0.19  # in units of the half edge
FACE_COLOUR = np.array([245, 240, 225], float)
PIP_COLOUR = np.array([25, 25, 35], float)
TABLE_COLOUR = np.array([40, 110, 60], float)  # felt green
SKY_COLOUR = np.array([200, 210, 225], float)


def render_die(
    scene: Scene,
    position: np.ndarray,
    orientation: np.ndarray,
    *,
    size: tuple[int, int] = (240, 320),
    elevation: float = 55.0,
    azimuth: float = -60.0,
    view_edges: float = 5.0,
) -> np.ndarray:
    """An RGB image (height, width, 3) uint8 of the die over the scene's table.

    ``position`` (3,) centre of mass, ``orientation`` (3, 3) body to world.
    ``elevation``/``azimuth`` (degrees) place the camera; ``view_edges`` is the image width in
    die edges.
    """
    height, width = size
    die = scene.die
    half = die.half_edge
    normal = np.asarray(scene.ground.normal)
    forward, right, up = _camera(normal, math.radians(elevation), math.radians(azimuth))
    scale = view_edges * die.edge / width  # metres per pixel
    centre = position - orientation @ np.asarray(die.com)  # geometric centre, camera target
    xs = (np.arange(width) - (width - 1) / 2) * scale
    ys = ((height - 1) / 2 - np.arange(height)) * scale
    px, py = np.meshgrid(xs, ys)
    origin = centre + px[..., None] * right + py[..., None] * up  # (H, W, 3) ray origins

    image = _table(origin, forward, normal, die.edge, centre, orientation, half)
    light = _unit(normal + 0.4 * right + 0.3 * up)
    for k in range(6):
        n = orientation @ FACE_NORMALS[k]
        if n @ forward >= 0:  # faces away from the camera
            continue
        a, b = orientation @ FACE_U[k], orientation @ FACE_V[k]
        offset = half * n
        m = np.array([[right @ a, right @ b], [up @ a, up @ b]]) * half
        u, v = np.einsum("ij,hwj->ihw", np.linalg.inv(m),
                         np.stack([px - right @ offset, py - up @ offset], -1))
        inside = (np.abs(u) <= 1) & (np.abs(v) <= 1)
        shade = 0.45 + 0.55 * max(0.0, float(n @ light))
        rim = np.maximum(np.abs(u), np.abs(v)) > 0.93
        pip = np.zeros_like(inside)
        for cu, cv in PIPS[k]:
            pip |= (u - cu) ** 2 + (v - cv) ** 2 < PIP_RADIUS**2
        colour = np.where(pip[..., None], PIP_COLOUR, FACE_COLOUR * shade)
        colour = np.where((rim & ~pip)[..., None], colour * 0.8, colour)
        image = np.where(inside[..., None], colour, image)
    return np.clip(image, 0, 255).astype(np.uint8)


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


def _table(
    origin: np.ndarray, forward: np.ndarray, normal: np.ndarray, edge: float,
    centre: np.ndarray, orientation: np.ndarray, half: float,
) -> np.ndarray:
    """Colour where each ray meets the table: felt, a grid of one edge, the die's shadow."""
    t = -(origin @ normal) / (forward @ normal)
    hit = origin + t[..., None] * forward
    in_plane = hit @ np.stack(_plane_axes(normal), axis=1) / edge
    grid = np.any(np.abs((in_plane + 0.5) % 1.0 - 0.5) < 0.02, axis=-1)
    # Shadow: the vertical line through the hit point crosses the die (slab test, body frame).
    rel = (hit - centre) @ orientation
    direction = orientation.T @ normal
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-half - rel) / direction
        t2 = (half - rel) / direction
    lo = np.where(direction == 0, np.where(np.abs(rel) <= half, -np.inf, np.inf),
                  np.minimum(t1, t2)).max(axis=-1)
    hi = np.where(direction == 0, np.where(np.abs(rel) <= half, np.inf, -np.inf),
                  np.maximum(t1, t2)).min(axis=-1)
    shadow = lo <= hi
    colour = np.where(grid[..., None], TABLE_COLOUR * 1.25, TABLE_COLOUR)
    return np.where(shadow[..., None], colour * 0.55, colour)


def _unit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def has_display() -> bool:
    """True when a window can be opened (a display on Linux; always on macOS and Windows)."""
    if sys.platform.startswith(("darwin", "win")):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class Viewer:
    """A matplotlib window showing frames at ``fps``; does nothing where there is no display."""

    def __init__(self, fps: float) -> None:
        self.fps = fps
        self._figure = None
        self._image = None

    def show(self, frame: np.ndarray) -> None:
        """Show ``frame`` (H, W, 3) uint8 and wait one frame interval."""
        if not has_display():
            return
        import matplotlib.pyplot as plt

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

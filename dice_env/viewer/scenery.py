"""What a view of a recorded throw draws around the dice: the floor and the walls, once.

The page (:mod:`~dice_env.viewer.html`) and the glb (:mod:`~dice_env.viewer.gltf`) both draw
from :func:`scenery`: a box ``radius`` about the floor's ``centre`` in x and y, and each wall as
its polygon ``height`` up, cut by the floor, the other walls and the box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dice_env.model.scene import Plane
from dice_env.viewer.recording import Recording

_Cut = tuple[np.ndarray, float]  # (normal, offset): keep the side normal . p >= offset


@dataclass(frozen=True)
class Scenery:
    """A recording's view: its extent, the floor's point and axes, the floor and walls drawn."""

    size: float  # m: the largest die's size
    centre: np.ndarray  # (3,) the floor's point below the middle of the dice' path
    radius: float  # m: the view's box reaches this far from centre in x and in y
    axes: tuple[np.ndarray, np.ndarray]  # the floor's (u, w), u horizontal if it can be
    floor: np.ndarray  # (K, 3) the floor's corners in order: its part in the box, a quad
    walls: dict[int, np.ndarray]  # a wall's index in scene.walls -> its corners (K, 3) in order


def scenery(recording: Recording) -> Scenery:
    """The view of ``recording``: a box about where the dice go, wide enough for the walls near."""
    size = max(die.size for die in recording.dice)
    points = recording.position.reshape(-1, 3)
    low, high = points.min(axis=0), points.max(axis=0)
    floor, *walls = recording.scene.planes
    centre = _onto(floor, (low + high) / 2)
    reach = float(np.linalg.norm(points[:, :2] - centre[:2], axis=1).max()) + 2 * size
    near = [abs(float(np.dot(w.normal, centre)) - w.offset) for w in walls]
    radius = max([reach, 6 * size] + [d + size for d in near if d < 4 * reach])
    height = max(3 * size, min(float(high[2]) + size, radius / 2))
    box = [(np.array(axis), float(np.dot(axis, centre)) - radius)
           for axis in ((1.0, 0, 0), (-1.0, 0, 0), (0, 1.0, 0), (0, -1.0, 0))]
    drawn: dict[int, np.ndarray] = {}
    for k, wall in enumerate(walls):  # cut where it passes behind the floor or another wall
        others = [(np.asarray(p.normal, dtype=np.float64), p.offset)
                  for p in (floor, *walls[:k], *walls[k + 1:])]
        polygon = _polygon(wall, centre, 4 * radius, height, others + box)
        if len(polygon) >= 3:
            drawn[k] = np.array(polygon)
    return Scenery(size, centre, radius, _basis(np.asarray(floor.normal, dtype=np.float64)),
                   np.array(_polygon(floor, centre, 4 * radius, 4 * radius, box)), drawn)


def _polygon(plane: Plane, centre: np.ndarray, across: float, up: float,
             cuts: list[_Cut]) -> list[np.ndarray]:
    """The rectangle of ``plane`` about its point nearest ``centre``, cut by each of ``cuts``.

    Its half sides: ``across`` along the plane's first axis, ``up`` along its second.
    """
    foot = _onto(plane, centre)
    u, w = _basis(np.asarray(plane.normal, dtype=np.float64))
    polygon = [foot + a * across * u + b * up * w for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    for normal, offset in cuts:
        polygon = _clip(polygon, normal, offset)
    return polygon


def _onto(plane: Plane, point: np.ndarray) -> np.ndarray:
    """The point of ``plane`` nearest ``point``."""
    normal = np.asarray(plane.normal, dtype=np.float64)
    return point + (plane.offset - normal @ point) * normal


def _basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors spanning the plane of ``normal``: the first horizontal if it can be."""
    u = np.cross(normal, (0.0, 0.0, 1.0))
    u = u if np.linalg.norm(u) > 1e-9 else np.cross(normal, (0.0, 1.0, 0.0))
    u /= np.linalg.norm(u)
    w = np.cross(normal, u)
    return u, (w if w[2] >= 0 else -w)


def _clip(polygon: list[np.ndarray], normal: np.ndarray, offset: float) -> list[np.ndarray]:
    """The part of a convex polygon on the side of ``normal . p >= offset`` (Sutherland-Hodgman)."""
    kept = []
    for a, b in zip(polygon, polygon[1:] + polygon[:1], strict=True):
        da, db = normal @ a - offset, normal @ b - offset
        if da >= 0:
            kept.append(a)
        if (da >= 0) != (db >= 0):
            kept.append(a + da / (da - db) * (b - a))
    return kept

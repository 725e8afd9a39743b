"""The die: eight corner nodes, a mass distribution and numbered faces.

Body frame: origin at the geometric centre, axes along the edges. Faces follow a standard
(right-handed, "Western") die: opposite faces sum to 7 and the faces 1, 2, 3 meet at the
corner (+, +, +) and run counter-clockwise seen from outside that corner.

======  ==========  ======  ==========
face    outward     face    outward
======  ==========  ======  ==========
1       +z          6       -z
2       +x          5       -x
3       +y          4       -y
======  ==========  ======  ==========
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from dice_env.table import DIE_EDGE, DIE_MASS
from dice_env.validation import check_finite, check_positive, check_range

# Corner signs in the order of the paper's cube.m (node k = row k).
CORNER_SIGNS = np.array(
    [
        [1, 1, 1], [1, -1, 1], [-1, -1, 1], [-1, 1, 1],
        [1, 1, -1], [1, -1, -1], [-1, -1, -1], [-1, 1, -1],
    ],
    dtype=np.float64,
)
# The 12 edges as node-index pairs (cube.m's links, 0-based), for drawing.
EDGES = np.array(
    [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4],
     [0, 4], [1, 5], [2, 6], [3, 7]],
)
# Outward body-frame normal of face k+1.
FACE_NORMALS = np.array(
    [[0, 0, 1], [1, 0, 0], [0, 1, 0], [0, -1, 0], [-1, 0, 0], [0, 0, -1]], dtype=np.float64
)


def paper_side_length(r: float) -> float:
    """The paper's side length for corner distance ``r``: ``s = -sqrt(2) + 2*sqrt(0.5 + r^2)``.

    A quirk kept for paper mode only: a cube whose corners lie at distance ``r`` from its centre
    has ``s = 2r/sqrt(3)`` (1.1547 for r = 1); this formula gives 1.0353, and the resulting
    corners lie at ``s*sqrt(3)/2`` = 0.8966 from the centre, not at ``r``.
    """
    return -math.sqrt(2.0) + 2.0 * math.sqrt(0.5 + r * r)


def solid_cube_inertia(mass: float, edge: float) -> np.ndarray:
    """Inertia tensor of a uniform solid cube about its centre: ``(1/6) m s^2`` times identity."""
    return np.eye(3) * (mass * edge * edge / 6.0)


@dataclass(frozen=True)
class Die:
    """A cubic die of edge ``edge`` and mass ``mass``; corners are the contact nodes.

    The default is a uniform solid die (the paper's inertia, ``(1/6) m s^2``). A loaded die
    carries its centre of mass ``com`` (body frame, from the geometric centre) and its inertia
    tensor ``inertia`` about that centre of mass; build one with :meth:`loaded` or
    :meth:`from_node_masses`.
    """

    edge: float = DIE_EDGE
    mass: float = DIE_MASS
    com: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: tuple[tuple[float, ...], ...] | None = field(default=None)

    def __post_init__(self) -> None:
        check_positive("edge", self.edge)
        check_positive("mass", self.mass)
        com = np.asarray(self.com, dtype=np.float64)
        if com.shape != (3,):
            raise ValueError(f"com must have shape (3,), got {com.shape}")
        check_finite("com", com)
        if np.any(np.abs(com) >= self.edge / 2):
            raise ValueError(f"com must lie inside the die, |com_i| < edge/2 = {self.edge / 2}")
        if self.inertia is not None:
            inertia = np.asarray(self.inertia, dtype=np.float64)
            if inertia.shape != (3, 3):
                raise ValueError(f"inertia must have shape (3, 3), got {inertia.shape}")
            check_finite("inertia", inertia)
            if not np.allclose(inertia, inertia.T, rtol=1e-12, atol=0.0):
                raise ValueError("inertia must be symmetric")
            principal = np.linalg.eigvalsh(inertia)
            if principal[0] <= 0 or principal[2] > principal[0] + principal[1] * (1 + 1e-12):
                raise ValueError(
                    "inertia must be positive definite with principal moments obeying the "
                    f"triangle inequality, got principal moments {principal}"
                )

    @classmethod
    def paper(cls, r: float = 1.0, mass: float = 1.0) -> Die:
        """The paper's cube: side from :func:`paper_side_length`, solid-cube inertia."""
        check_positive("r", r)
        return cls(edge=paper_side_length(r), mass=mass)

    @classmethod
    def loaded(
        cls,
        face: int = 6,
        fraction: float = 0.1,
        depth: float = 0.8,
        edge: float = DIE_EDGE,
        mass: float = DIE_MASS,
    ) -> Die:
        """A die with ``fraction`` of its mass moved into a point weight toward ``face``.

        The weight sits on the axis of ``face`` at ``depth`` times the half edge from the centre;
        the rest of the mass stays a uniform solid cube. The heavy face tends to land down, so
        its opposite (``7 - face``) shows up more often.
        """
        if not isinstance(face, (int, np.integer)) or isinstance(face, bool) or not 1 <= face <= 6:
            raise ValueError(f"face must be an int in [1, 6], got {face!r}")
        check_range("fraction", fraction, 0.0, 1.0, high_open=True)
        check_range("depth", depth, 0.0, 1.0, high_open=True)
        p = FACE_NORMALS[face - 1] * depth * edge / 2
        solid = (1 - fraction) * solid_cube_inertia(mass, edge)
        weight = fraction * mass * (p @ p * np.eye(3) - np.outer(p, p))
        com = fraction * p
        about_com = solid + weight - mass * (com @ com * np.eye(3) - np.outer(com, com))
        return cls(edge=edge, mass=mass, com=tuple(com), inertia=_as_tuple(about_com))

    @classmethod
    def from_node_masses(cls, masses: np.ndarray, edge: float = DIE_EDGE) -> Die:
        """A die whose whole mass sits in its 8 corner nodes (inertia of those point masses)."""
        masses = np.asarray(masses, dtype=np.float64)
        if masses.shape != (8,):
            raise ValueError(f"masses must have shape (8,), got {masses.shape}")
        check_finite("masses", masses)
        if np.any(masses <= 0):
            raise ValueError("masses must all be > 0")
        total = float(masses.sum())
        corners = CORNER_SIGNS * edge / 2
        com = masses @ corners / total
        rel = corners - com
        inertia = sum(
            mk * (rk @ rk * np.eye(3) - np.outer(rk, rk))
            for mk, rk in zip(masses, rel, strict=True)
        )
        return cls(edge=edge, mass=total, com=tuple(com), inertia=_as_tuple(inertia))

    @property
    def half_edge(self) -> float:
        """Half the edge length (m)."""
        return self.edge / 2

    @property
    def inertia_body(self) -> np.ndarray:
        """Body-frame inertia tensor about the centre of mass, shape (3, 3)."""
        if self.inertia is None:
            return solid_cube_inertia(self.mass, self.edge)
        return np.array(self.inertia, dtype=np.float64)

    @property
    def is_isotropic(self) -> bool:
        """True when the inertia is a multiple of the identity (then ω = L / I exactly)."""
        inertia = self.inertia_body
        return bool(np.all(inertia == inertia[0, 0] * np.eye(3)))

    @property
    def corners_body(self) -> np.ndarray:
        """Corner positions relative to the centre of mass, body frame, shape (8, 3)."""
        return CORNER_SIGNS * self.half_edge - np.asarray(self.com)

    @property
    def resting_heights(self) -> np.ndarray:
        """Height (m) of the centre of mass above the plane with each face up, lying flat, (6,)."""
        return _heights_above_lowest_corner(self.corners_body, FACE_NORMALS)

    @cached_property
    def tipping_heights(self) -> np.ndarray:
        """Least height (m) of the centre of mass above its lowest corner as each face tips, (6,).

        A die can stop showing face ``F`` up only through an orientation in which ``F`` and an
        adjacent face ``G`` point equally far up, further than any other (``u = s (f_F + f_G)
        + t f_F x f_G`` with ``|t| <= s``, ``u`` the up direction in the body frame): for a
        fair die balanced on an edge, ``sqrt(2)`` half edges. Taken as the minimum over a dense
        sampling of those four arcs, lowered by the height's Lipschitz bound times the sampling
        gap, so it is never above the true minimum. Computed once per die (about 10 ms).
        """
        corners = self.corners_body
        t = np.linspace(-1.0, 1.0, 4001) / math.sqrt(3.0)
        s = np.sqrt((1.0 - t * t) / 2.0)
        # |du/dt| <= sqrt(3/2) on an arc; the height is max|r_k|-Lipschitz in u
        slack = float(np.linalg.norm(corners, axis=1).max()) * math.sqrt(1.5) * (t[1] - t[0]) / 2
        out = np.full(6, np.inf)
        for f, normal in enumerate(FACE_NORMALS):
            for other in FACE_NORMALS[FACE_NORMALS @ normal == 0]:
                up = s[:, None] * (normal + other) + t[:, None] * np.cross(normal, other)
                out[f] = min(out[f], _heights_above_lowest_corner(corners, up).min() - slack)
        return out

    @property
    def is_fair(self) -> bool:
        """True for a centred, isotropic die."""
        return not any(self.com) and self.is_isotropic


def _heights_above_lowest_corner(corners: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Height of the centre of mass above the lowest of ``corners`` for each up direction."""
    return (-(up @ corners.T)).max(axis=-1)


def _as_tuple(matrix: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in matrix)


def face_up(orientation: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Number (1–6) of the face whose outward normal points most along the ground ``normal``.

    ``orientation``: (..., 3, 3) body-to-world rotation matrices. Returns an int array (...).
    """
    world_normals = np.einsum("...ij,fj->...fi", orientation, FACE_NORMALS)
    return np.argmax(world_normals @ np.asarray(normal, dtype=np.float64), axis=-1) + 1

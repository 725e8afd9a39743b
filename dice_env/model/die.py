"""The die: a convex polyhedron whose corners are the contact nodes, its mass and its faces.

Body frame: origin at the geometric centre (the uniform solid's centroid). Face ``k``
(0-based) carries the label ``k + 1``. The d6 is the right-handed die of ``docs/model.md``
(1 +z, 2 +x, 3 +y; opposite faces sum to 7).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, fields
from functools import cache, cached_property

import numpy as np

from dice_env.model import polyhedra
from dice_env.model.checks import as_shaped, check_choice, check_int, check_positive, check_range
from dice_env.model.defaults import DIE_EDGE, DIE_MASS
from dice_env.model.pips import Pips, drill, with_defaults

# The d6's corner signs in the order of the paper's cube.m (node k = row k).
_CORNER_SIGNS = np.array([[1, 1, 1], [1, -1, 1], [-1, -1, 1], [-1, 1, 1],
                          [1, 1, -1], [1, -1, -1], [-1, -1, -1], [-1, 1, -1]], dtype=np.float64)
# The d6's outward body-frame normal of face k+1.
_CUBE_NORMALS = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0], [0, -1, 0], [-1, 0, 0], [0, 0, -1]],
                         dtype=np.float64)

# Default density (kg/m^3), the default d6's: 4.5 g at 16 mm, 1099 kg/m^3 (acrylic/resin).
DIE_VOLUME = DIE_EDGE * DIE_EDGE * DIE_EDGE
DENSITY = DIE_MASS / DIE_VOLUME
# Default sizes (m), the least height on a face: our estimate of a common acrylic set next to
# the 16 mm d6, not a measured sample; pass ``size=`` for a measured die.
STANDARD_SIZES = {"d4": 0.014, "d6": DIE_EDGE, "d8": 0.014, "d10": 0.014, "d12": 0.018,
                  "d20": 0.020}
# Tipping heights sample each tie arc at most this far apart (rad): the cube's end spacing
# of 4001 points over its arc, 1 / (2000 sqrt 2).
ARC_STEP = 1.0 / (2000.0 * math.sqrt(2.0))


@dataclass(frozen=True, init=False, repr=False)
class Die:
    """A convex polyhedral die; its corners are the contact nodes.

    ``Die(edge, mass, com, inertia)`` is the cubic d6 (default 16 mm, 4.5 g, uniform solid);
    other shapes come from :meth:`standard`, :meth:`cuboid` and :meth:`from_vertices`, loaded
    dice from :meth:`load`.

    Fields (hashable): ``name``; ``vertices`` (body frame, about the geometric centre);
    ``faces`` (corner indices, counter-clockwise seen from outside, in label order); ``size``
    (m: the least height of the die lying on a face: the cube's edge, a cuboid's shortest side,
    the d4's height); ``mass``; ``com`` (centre of mass from the geometric centre); ``inertia``
    (about the centre of mass, body frame); ``reads_down`` (True for the d4, read face down).
    """

    name: str
    vertices: tuple[tuple[float, float, float], ...]
    faces: tuple[tuple[int, ...], ...]
    size: float
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[tuple[float, float, float], ...]
    reads_down: bool

    def __init__(self, edge: float = DIE_EDGE, mass: float = DIE_MASS,
                 com: tuple[float, float, float] = (0.0, 0.0, 0.0),
                 inertia: tuple[tuple[float, ...], ...] | None = None) -> None:
        check_positive("edge", edge)
        vertices, faces = _unit_shape("d6")
        self._set("d6", vertices * edge, faces, edge, mass, False, com, inertia)

    @classmethod
    def standard(cls, name: str = "d6", size: float | None = None,
                 mass: float | None = None, *, pips: Pips | str | None = None) -> Die:
        """A standard die: "d4", "d6", "d8", "d10", "d12" or "d20", uniform unless ``pips``.

        ``size`` (m) as the field (default :data:`STANDARD_SIZES`); ``mass`` (kg) defaults to
        :data:`DENSITY` times the volume. ``pips`` (d6 only): a
        :class:`~dice_env.model.pips.Pips` or a preset of :data:`dice_env.model.pips.DRILLINGS`
        (which also supplies a size and mass left None); ``mass`` is then the weighed mass.
        Opposite faces sum to ``n + 1`` on the d6, d8, d12 and d20. Numbering:

        - d4: corners ``(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)`` (scaled); face ``k``
          opposite corner ``k``; read face down.
        - d8: corners on the axes; the odd faces meet at +z (counter-clockwise from azimuth
          45 degrees), the even ones at -z.
        - d10: :func:`polyhedra.pentagonal_trapezohedron`; labels are the digits 0–9 plus one
          (opposite digits sum to 9), reading 0, 7, 4, 1, 6, 9, 2, 5, 8, 3 counter-clockwise
          around the zigzag from azimuth 0.
        - d12, d20: lying on face 1 (normal +z); the upper faces take 1 … n/2 by descending
          height, then azimuth from +x; each lower face ``n + 1`` minus its opposite's label.
        """
        check_choice("name", name, STANDARD_SIZES)
        if pips is not None:
            pips, size, mass = with_defaults(name, pips, size, mass)
        size = STANDARD_SIZES[name] if size is None else size
        check_positive("size", size)
        vertices, faces = _unit_shape(name)
        vertices = vertices * size
        volume = _volume(name, vertices, faces, size)
        die = cls._new(name, vertices, faces, size, _mass(mass, volume), name == "d4")
        mass_properties = None if pips is None else drill(size, die.mass, pips)
        return die if mass_properties is None else die._with_mass(die.mass, *mass_properties)

    @classmethod
    def cuboid(cls, sides: tuple[float, float, float], mass: float | None = None) -> Die:
        """A uniform rectangular box of ``sides`` (x, y, z) (m), numbered like the d6.

        ``size`` is the shortest side; equal sides give the d6 of :meth:`standard`. ``mass``
        defaults to :data:`DENSITY` times the volume.
        """
        sides = np.asarray(sides, dtype=np.float64)
        if sides.shape != (3,) or not np.all(np.isfinite(sides)) or np.any(sides <= 0):
            raise ValueError(f"sides must be three finite numbers > 0 (x, y, z), got {sides}")
        x, y, z = (float(s) for s in sides)
        if x == y == z:
            return cls.standard("d6", size=x, mass=mass)
        vertices, faces = _unit_shape("d6")
        return cls._new("cuboid", vertices * sides, faces, min(x, y, z), _mass(mass, x * y * z),
                        False)

    @classmethod
    def from_vertices(cls, vertices: np.ndarray, labels: np.ndarray | None = None,
                      mass: float | None = None, *, reads_down: bool = False) -> Die:
        """A uniform die on any convex vertex set (N, 3) (m), centred on the solid's centroid.

        Every point must be a hull corner (:func:`polyhedra.convex_faces`, whose face order
        ``labels`` follows: a permutation of 1 … F, default 1 … F). ``mass`` defaults to
        :data:`DENSITY` times the volume; ``reads_down`` reads the face down.
        """
        if not isinstance(reads_down, (bool, np.bool_)):
            raise ValueError(f"reads_down must be a bool, got {reads_down!r}")
        faces = polyhedra.convex_faces(vertices, "vertices")
        points = np.asarray(vertices, dtype=np.float64)
        if labels is not None:
            faces = _in_label_order(faces, labels)
        volume, centroid, _ = polyhedra.mass_properties(points, faces)
        if np.abs(centroid).max() > 1e-12 * np.abs(points).max():
            points = points - centroid
        return cls._new("polyhedron", points, faces, _least_height(points, faces),
                        _mass(mass, volume), bool(reads_down))

    @classmethod
    def paper(cls, r: float = 1.0, mass: float = 1.0) -> Die:
        """The paper's cube for corner distance ``r``, solid-cube inertia.

        Its side ``s = -sqrt(2) + 2 sqrt(0.5 + r^2)`` puts the corners at ``s sqrt(3)/2``, not r.
        """
        check_positive("r", r)
        return cls(edge=-math.sqrt(2.0) + 2.0 * math.sqrt(0.5 + r * r), mass=mass)

    @classmethod
    def loaded(cls, face: int = 6, fraction: float = 0.1, depth: float = 0.8,
               edge: float = DIE_EDGE, mass: float = DIE_MASS) -> Die:
        """The d6 of ``edge`` and ``mass`` loaded toward ``face``: ``Die(edge, mass).load(...)``."""
        return cls(edge=edge, mass=mass).load(face, fraction, depth)

    @classmethod
    def from_node_masses(cls, masses: np.ndarray, edge: float = DIE_EDGE) -> Die:
        """A d6 whose whole mass sits in its 8 corner nodes (inertia of those point masses)."""
        masses = as_shaped("masses", masses, (8,))
        if np.any(masses <= 0):
            raise ValueError("masses must all be > 0")
        die = cls(edge=edge)
        total = float(masses.sum())
        corners = np.asarray(die.vertices)
        com = masses @ corners / total
        inertia = sum(mk * polyhedra.point_inertia(rk)
                      for mk, rk in zip(masses, corners - com, strict=True))
        return die._with_mass(total, com, inertia)

    def load(self, face: int, fraction: float = 0.1, depth: float = 0.8) -> Die:
        """A copy with ``fraction`` of the mass moved into a point weight toward ``face``.

        The weight sits on the axis of face ``face`` (a label) at ``depth`` times that face's
        distance from the geometric centre; the rest of the mass keeps its distribution.
        """
        check_int("face", face, 1, self.n_faces)
        check_range("fraction", fraction, 0.0, 1.0, high_open=True)
        check_range("depth", depth, 0.0, 1.0, high_open=True)
        distance = _face_distances(np.array(self.vertices), self.faces, self.face_normals)
        p = self.face_normals[face - 1] * depth * distance[face - 1]
        c0 = np.asarray(self.com)
        solid = (1 - fraction) * (self.inertia_body + self.mass * polyhedra.point_inertia(c0))
        weight = fraction * self.mass * polyhedra.point_inertia(p)
        com = (1 - fraction) * c0 + fraction * p
        about_com = solid + weight - self.mass * polyhedra.point_inertia(com)
        return self._with_mass(self.mass, com, about_com)

    @property
    def vertices_body(self) -> np.ndarray:
        """Corner positions relative to the centre of mass, body frame, shape (N, 3)."""
        return np.array(self.vertices) - np.asarray(self.com)

    @cached_property
    def reach(self) -> float:
        """The largest distance of a corner from the centre of mass (m)."""
        return float(np.sqrt((self.vertices_body**2).sum(axis=1)).max())

    @cached_property
    def face_normals(self) -> np.ndarray:
        """Outward unit normals (F, 3), body frame, in label order (read-only)."""
        return _frozen(polyhedra.face_normals(np.array(self.vertices), self.faces))

    @cached_property
    def reading(self) -> np.ndarray:
        """Reading directions (F, 3), body frame, label order: the normals, negated for the d4."""
        return _frozen(-self.face_normals if self.reads_down else self.face_normals)

    @property
    def labels(self) -> np.ndarray:
        """The printed label of each face, in the order of :attr:`face_normals`: 1 … F."""
        return np.arange(1, self.n_faces + 1)

    @property
    def n_faces(self) -> int:
        """Number of faces (and of outcomes)."""
        return len(self.faces)

    @cached_property
    def edges(self) -> np.ndarray:
        """The edges as corner-index pairs (E, 2), for drawing (read-only)."""
        return _frozen(polyhedra.edges(self.faces))

    @cached_property
    def volume(self) -> float:
        """Volume of the solid (m^3)."""
        return _volume(self.name, np.array(self.vertices), self.faces, self.size)

    def face_read(self, orientation: np.ndarray, up: np.ndarray) -> np.ndarray:
        """The label read in each body-to-world orientation (..., 3, 3): int array (...).

        The face whose :attr:`reading` direction points most along ``up`` (3,).
        """
        orientation = np.asarray(orientation, dtype=np.float64)
        up = np.asarray(up, dtype=np.float64)
        if orientation.shape[-2:] != (3, 3) or up.shape != (3,):
            raise ValueError(f"orientation must have shape (..., 3, 3) and up (3,), got "
                             f"{orientation.shape} and {up.shape}")
        world = np.einsum("...ij,fj->...fi", orientation, self.reading)
        return self.labels[np.argmax(world @ up, axis=-1)]

    @property
    def resting_heights(self) -> np.ndarray:
        """Height (m) of the centre of mass above its lowest corner, each face read up, (F,)."""
        return (-(self.reading @ self.vertices_body.T)).max(axis=-1)

    @cached_property
    def tipping_heights(self) -> np.ndarray:
        """Least height (m) of the centre of mass above its lowest corner as each face tips, (F,).

        Over the orientations where the face ties with another (``docs/performance.md``), each
        tie arc sampled :data:`ARC_STEP` apart and lowered by the Lipschitz bound.
        """
        corners, reading = self.vertices_body, self.reading
        out = np.full(self.n_faces, np.inf)
        for f, g in itertools.combinations(range(self.n_faces), 2):
            # up = cos(phi) m + sin(phi) w on the tie of f and g, m bisecting their reading
            # directions, w normal to both; each other face k asks (a_f - a_k) . up >= 0
            a, b = reading[f], reading[g]
            length = np.linalg.norm(a + b)
            if length < 1e-9:  # opposite directions: another face always reads more on their tie
                continue
            m = (a + b) / length
            w = np.cross(a, b)
            w /= np.linalg.norm(w)
            d = a - np.delete(reading, [f, g], axis=0)
            psi = np.arctan2(d @ w, d @ m)
            lo = max(-math.pi / 2, float((psi - math.pi / 2).max(initial=-math.inf)))
            hi = min(math.pi / 2, float((psi + math.pi / 2).min(initial=math.inf)))
            if lo > hi:
                continue
            n = math.ceil((hi - lo) / ARC_STEP) + 1
            phi = np.linspace(lo, hi, n)
            up = np.cos(phi)[:, None] * m + np.sin(phi)[:, None] * w
            gap = (hi - lo) / (n - 1) if n > 1 else 0.0
            low = float((-(up @ corners.T)).max(axis=-1).min()) - self.reach * gap / 2
            out[f], out[g] = min(out[f], low), min(out[g], low)
        return _frozen(out)

    @property
    def inertia_body(self) -> np.ndarray:
        """Body-frame inertia tensor about the centre of mass, shape (3, 3)."""
        return np.array(self.inertia, dtype=np.float64)

    @property
    def is_isotropic(self) -> bool:
        """True when the inertia is a multiple of the identity (then ω = L / I exactly)."""
        inertia = self.inertia_body
        return bool(np.all(inertia == inertia[0, 0] * np.eye(3)))

    @property
    def is_fair(self) -> bool:
        """True for a standard die, centred, with isotropic inertia or the uniform solid's."""
        return (not any(self.com) and self.name in STANDARD_SIZES
                and (self.is_isotropic or self.inertia_body.tolist() == _solid_inertia(
                    self.name, np.array(self.vertices), self.faces, self.size,
                    self.mass).tolist()))

    @classmethod
    def from_fields(cls, name: str, vertices: tuple, faces: tuple, size: float, mass: float,
                    com: tuple, inertia: tuple, reads_down: bool) -> Die:
        """The die whose fields are these (as :func:`dataclasses.asdict` gives them), checked."""
        faces = tuple(tuple(int(k) for k in face) for face in faces)
        return cls._new(str(name), np.asarray(vertices, dtype=np.float64), faces, size, mass,
                        bool(reads_down), com, inertia)

    def __repr__(self) -> str:
        com = "" if not any(self.com) else f", com={tuple(round(c, 9) for c in self.com)}"
        return f"Die({self.name!r}, size={self.size:g}, mass={self.mass:g}{com})"

    @classmethod
    def _new(cls, *values: object) -> Die:
        die = object.__new__(cls)
        die._set(*values)
        return die

    def _with_mass(self, mass: float, com: np.ndarray, inertia: np.ndarray) -> Die:
        return self._new(self.name, np.array(self.vertices), self.faces, self.size, mass,
                         self.reads_down, com, inertia)

    def _set(self, name: str, vertices: np.ndarray, faces: tuple[tuple[int, ...], ...],
             size: float, mass: float, reads_down: bool,
             com: tuple[float, ...] | np.ndarray = (0.0, 0.0, 0.0),
             inertia: tuple[tuple[float, ...], ...] | None = None) -> None:
        check_positive("mass", mass)
        com = as_shaped("com", com, (3,))
        normals = polyhedra.face_normals(vertices, faces)
        if np.any(normals @ com >= _face_distances(vertices, faces, normals)):
            raise ValueError("com must lie inside the die (closer to the geometric centre than "
                             f"every face plane), got {tuple(com)}")
        if inertia is None:
            inertia = _solid_inertia(name, vertices, faces, size, mass)
        inertia = as_shaped("inertia", inertia, (3, 3))
        if not np.allclose(inertia, inertia.T, rtol=1e-12, atol=0.0):
            raise ValueError("inertia must be symmetric")
        principal = np.linalg.eigvalsh(inertia)
        if principal[0] <= 0 or principal[2] > principal[0] + principal[1] * (1 + 1e-12):
            raise ValueError("inertia must be positive definite with principal moments obeying "
                             f"the triangle inequality, got principal moments {principal}")
        values = (name, _as_tuple(vertices), faces, float(size), float(mass),
                  tuple(float(c) for c in com), _as_tuple(inertia), reads_down)
        for field, value in zip(fields(self), values, strict=True):
            object.__setattr__(self, field.name, value)


@cache
def _unit_shape(name: str) -> tuple[np.ndarray, tuple[tuple[int, ...], ...]]:
    """Corners (centred) and faces (in label order) of the standard die ``name`` at size 1."""
    raw, upper = {
        "d4": (polyhedra.tetrahedron, None),
        "d6": (lambda: _CORNER_SIGNS, None),
        "d8": (polyhedra.octahedron, [1, 3, 5, 7]),
        "d10": (polyhedra.pentagonal_trapezohedron, [1, 5, 7, 3, 9]),
        "d12": (lambda: _face_along_z(polyhedra.dodecahedron()), range(1, 7)),
        "d20": (lambda: _face_along_z(polyhedra.icosahedron()), range(1, 11)),
    }[name]
    raw = raw()
    faces = polyhedra.convex_faces(raw)
    normals = polyhedra.face_normals(raw, faces)
    if name in ("d4", "d6"):  # face k + 1 nearest direction k; the d4's face k opposite corner k
        directions = -raw / math.sqrt(3.0) if name == "d4" else _CUBE_NORMALS
        labels = np.argmax(normals @ directions.T, axis=1) + 1
    else:  # upper faces by descending n_z then azimuth; below, F + 1 minus the opposite's label
        z = np.round(normals[:, 2], 9)
        azimuth = np.mod(np.round(np.arctan2(normals[:, 1], normals[:, 0]), 9), 2 * math.pi)
        top = np.flatnonzero(z > 0)
        labels = np.zeros(len(normals), dtype=np.int64)
        labels[top[np.lexsort((azimuth[top], -z[top]))]] = list(upper)
        for f in np.flatnonzero(z < 0):
            labels[f] = len(normals) + 1 - labels[np.argmin(normals @ normals[f])]
    faces = _in_label_order(faces, labels)
    return _frozen(raw / _least_height(raw, faces)), faces


def _face_along_z(points: np.ndarray) -> np.ndarray:
    """``points`` turned so that the face normal nearest +z (then +x) points along +z."""
    normals = polyhedra.face_normals(points, polyhedra.convex_faces(points))
    top = normals[np.lexsort((np.round(normals[:, 0], 9), np.round(normals[:, 2], 9)))[-1]]
    axis = np.cross(top, [0.0, 0.0, 1.0])
    sin = np.linalg.norm(axis)
    k = np.cross(np.eye(3), axis / sin)  # cross-product matrix of the unit axis
    rotation = np.eye(3) + sin * k + (1.0 - top[2]) * (k @ k)
    return points @ rotation.T


def _in_label_order(faces: tuple[tuple[int, ...], ...],
                    labels: object) -> tuple[tuple[int, ...], ...]:
    """``faces`` in the order of ``labels``, a permutation of 1 … F (else ``ValueError``)."""
    values, n = np.asarray(labels), len(faces)
    if (values.shape != (n,) or not np.issubdtype(values.dtype, np.integer)
            or sorted(values.tolist()) != list(range(1, n + 1))):
        raise ValueError(f"labels must be a permutation of 1 … {n} (one per hull face), "
                         f"got {labels!r}")
    return tuple(faces[i] for i in np.argsort(values))


def _face_distances(vertices: np.ndarray, faces: tuple[tuple[int, ...], ...],
                    normals: np.ndarray) -> np.ndarray:
    """Distance of each face plane from the origin, (F,)."""
    return np.einsum("fi,fi->f", normals, vertices[[face[0] for face in faces]])


def _least_height(vertices: np.ndarray, faces: tuple[tuple[int, ...], ...]) -> float:
    """The least height of the solid lying on one of its faces."""
    spans = polyhedra.face_normals(vertices, faces) @ vertices.T
    return float(np.ptp(spans, axis=1).min())


def _volume(name: str, vertices: np.ndarray, faces: tuple[tuple[int, ...], ...],
            size: float) -> float:
    """Volume of the solid: the d6's ``size^3``, else integrated."""
    return size * size * size if name == "d6" else polyhedra.mass_properties(vertices, faces)[0]


def _mass(mass: float | None, volume: float) -> float:
    """``mass`` if given (checked when the die is built), else the default density's."""
    return DIE_MASS * (volume / DIE_VOLUME) if mass is None else mass


def _solid_inertia(name: str, vertices: np.ndarray, faces: tuple[tuple[int, ...], ...],
                   size: float, mass: float) -> np.ndarray:
    """Inertia of the uniform solid about its centroid: the d6's closed form, else integrated.

    Entries below 1e-12 of the trace become 0, moments equal to 1e-12 exactly isotropic.
    """
    if name == "d6":  # the solid cube's (1/6) m s^2 times identity
        return np.eye(3) * (mass * size * size / 6.0)
    per_mass = polyhedra.mass_properties(vertices, faces)[2]
    scale = np.trace(per_mass)
    per_mass = np.where(np.abs(per_mass) <= 1e-12 * scale, 0.0, per_mass)
    moments = np.diag(per_mass)
    if not (per_mass - np.diag(moments)).any() and np.ptp(moments) <= 1e-12 * scale:
        per_mass = np.eye(3) * (scale / 3.0)
    return mass * per_mass


def _as_tuple(matrix: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in matrix)


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array)
    array.flags.writeable = False
    return array

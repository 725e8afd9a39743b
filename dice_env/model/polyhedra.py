"""Convex polyhedra as (N, 3) corner arrays: hull faces, face normals, the uniform solid's mass.

Pure numpy; the generators return the standard dice shapes at an arbitrary scale.
"""

from __future__ import annotations

import math

import numpy as np

from dice_env.model.checks import check_finite

MAX_VERTICES = 64  # the hull search costs O(N^4) (64: 0.1 s); the d60 has 62 corners
TOLERANCE = 1e-9  # of the vertex set's extent (largest coordinate range): closer is "on a plane"

GOLDEN = (1.0 + math.sqrt(5.0)) / 2.0


def convex_faces(points: np.ndarray, name: str = "vertices") -> tuple[tuple[int, ...], ...]:
    """Faces of the convex hull of ``points`` (N, 3), as tuples of point indices.

    Corners counter-clockwise seen from outside, faces in the order of their sorted index
    tuples; points coplanar within :data:`TOLERANCE` make one face. Raises ``ValueError``
    naming ``name`` unless the points are 4 to :data:`MAX_VERTICES` finite, distinct points,
    not all in one plane, each a corner of the hull.
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {points.shape}")
    if not 4 <= len(points) <= MAX_VERTICES:
        raise ValueError(f"{name} must hold 4 to {MAX_VERTICES} points (a solid needs 4), "
                         f"got {len(points)}")
    check_finite(name, points)
    diameter = float(np.ptp(points, axis=0).max())
    tol = TOLERANCE * diameter
    gaps = np.linalg.norm(points[:, None] - points[None], axis=-1)
    i, j = np.nonzero(np.triu(gaps <= tol, 1))
    if len(i):
        raise ValueError(f"{name} must be distinct points: {name}[{i[0]}] and {name}[{j[0]}] "
                         "coincide")
    centred = points - points.mean(axis=0)
    normal = np.linalg.svd(centred)[2][-1]
    if np.abs(centred @ normal).max() <= tol:
        raise ValueError(f"{name} must not all lie in one plane (a solid needs volume)")
    on_face = np.zeros(len(points), dtype=bool)
    faces = []
    for indices, normal in _supporting_planes(points, tol, diameter).items():
        face = _face_polygon(points, np.array(sorted(indices)), normal, tol * diameter, name)
        on_face[list(face)] = True
        faces.append(face)
    if not on_face.all():
        k = int(np.flatnonzero(~on_face)[0])
        raise ValueError(f"{name} must be in convex position: {name}[{k}] lies inside the hull")
    if len(points) - len(edges(tuple(faces))) + len(faces) != 2:
        raise ValueError(f"{name} are too close to degenerate to tell the faces apart "
                         f"(coplanar within {TOLERANCE:g} of their extent)")
    return tuple(sorted(faces, key=sorted))


def face_normals(points: np.ndarray, faces: tuple[tuple[int, ...], ...]) -> np.ndarray:
    """Outward unit normals (F, 3) of ``faces`` (counter-clockwise seen from outside)."""
    fans = np.array([[f, face[0], face[k], face[k + 1]] for f, face in enumerate(faces)
                     for k in range(1, len(face) - 1)])
    origin = points[fans[:, 1]]
    area = np.zeros((len(faces), 3))
    np.add.at(area, fans[:, 0], np.cross(points[fans[:, 2]] - origin, points[fans[:, 3]] - origin))
    norm = np.linalg.norm(area, axis=1, keepdims=True)
    if not np.all(norm > 0):
        raise ValueError(f"faces must have a non-zero area; face(s) "
                         f"{np.flatnonzero(~(norm[:, 0] > 0)).tolist()} have none (a degenerate "
                         "or underflowing vertex set)")
    return area / norm


def edges(faces: tuple[tuple[int, ...], ...]) -> np.ndarray:
    """The polyhedron's edges as sorted index pairs (E, 2), each once, in sorted order."""
    pairs = {tuple(sorted(pair)) for face in faces
             for pair in zip(face, face[1:] + face[:1], strict=True)}
    return np.array(sorted(pairs), dtype=np.int64)


def mass_properties(points: np.ndarray, faces: tuple[tuple[int, ...], ...]
                    ) -> tuple[float, np.ndarray, np.ndarray]:
    """Volume, centroid (3,) and inertia tensor per unit mass about the centroid (3, 3).

    Of the uniform solid, exactly: tetrahedra ``(0, a, b, c)`` from the mean point to each
    face's fan have volume ``det[a, b, c] / 6`` and second moment
    ``V/20 (a a^T + b b^T + c c^T + s s^T)``, ``s = a + b + c``.
    """
    ref = points.mean(axis=0)
    tri = np.array([[face[0], face[k], face[k + 1]] for face in faces
                    for k in range(1, len(face) - 1)])
    a, b, c = (points[tri[:, k]] - ref for k in range(3))
    volumes = np.einsum("ti,ti->t", a, np.cross(b, c)) / 6.0
    s = a + b + c
    volume = float(volumes.sum())
    if not volume > 0:
        raise ValueError(f"the solid must have a positive volume, got {volume:g} (a flat, "
                         "inside-out or underflowing vertex set)")
    first = (volumes[:, None] * s).sum(axis=0) / 4.0 / volume
    second = np.einsum("t,tij->ij", volumes / 20.0, _outer(a) + _outer(b) + _outer(c) + _outer(s))
    second = second / volume - np.outer(first, first)
    inertia = np.trace(second) * np.eye(3) - second
    return volume, ref + first, (inertia + inertia.T) / 2.0


def point_inertia(r: np.ndarray) -> np.ndarray:
    """Inertia of a unit point mass at ``r`` (3,) about the origin: ``|r|^2 I - r r^T``."""
    return r @ r * np.eye(3) - np.outer(r, r)


def tetrahedron() -> np.ndarray:
    """Regular tetrahedron, edge ``2 sqrt(2)``: alternate corners of the cube ``(+-1)^3``."""
    return np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=np.float64)


def octahedron() -> np.ndarray:
    """Regular octahedron, corners on the axes at distance 1 (edge ``sqrt(2)``)."""
    return np.vstack([np.eye(3), -np.eye(3)])


def icosahedron() -> np.ndarray:
    """Regular icosahedron, edge 2: the cyclic permutations of ``(0, +-1, +-phi)``."""
    return _cyclic(1.0, GOLDEN)


def dodecahedron() -> np.ndarray:
    """Regular dodecahedron, edge ``2/phi``: ``(+-1)^3`` and cyclic ``(0, +-1/phi, +-phi)``."""
    cube = [[x, y, z] for x in (1.0, -1.0) for y in (1.0, -1.0) for z in (1.0, -1.0)]
    return np.vstack([cube, _cyclic(1.0 / GOLDEN, GOLDEN)])


def pentagonal_trapezohedron(apex: float = 1.0 + math.cos(math.pi / 5)) -> np.ndarray:
    """Pentagonal trapezohedron (the d10): apexes ``(0, 0, +-apex)``, a zigzag ring of radius 1.

    The ring's upper corners sit at azimuths ``72 k - 36`` degrees, the lower ones at ``72 k``,
    at heights ``+-z0``, ``z0 = apex (1 - cos 36) / (1 + cos 36)`` (planar kites). The default
    apex gives the dual of the uniform pentagonal antiprism.
    """
    c = math.cos(math.pi / 5)
    z0 = apex * (1 - c) / (1 + c)
    angles = np.radians(np.arange(5) * 72.0)
    upper = np.column_stack([np.cos(angles - math.pi / 5), np.sin(angles - math.pi / 5),
                             np.full(5, z0)])
    lower = np.column_stack([np.cos(angles), np.sin(angles), np.full(5, -z0)])
    return np.vstack([[[0.0, 0.0, apex], [0.0, 0.0, -apex]], upper, lower])


def _outer(v: np.ndarray) -> np.ndarray:
    return v[:, :, None] * v[:, None, :]


def _cyclic(a: float, b: float) -> np.ndarray:
    base = np.array([[0.0, s1 * a, s2 * b] for s1 in (1, -1) for s2 in (1, -1)])
    return np.vstack([np.roll(base, k, axis=1) for k in range(3)])


def _supporting_planes(points: np.ndarray, tol: float,
                       diameter: float) -> dict[frozenset[int], np.ndarray]:
    """Every plane through three points with no point beyond it: the points on it, its normal."""
    n = len(points)
    planes: dict[frozenset[int], np.ndarray] = {}
    for i in range(n - 2):
        j, k = np.triu_indices(n - i - 1, 1)
        j, k = j + i + 1, k + i + 1
        normals = np.cross(points[j] - points[i], points[k] - points[i])
        length = np.linalg.norm(normals, axis=1)
        keep = length > tol * diameter  # not three points on a line
        normals = normals[keep] / length[keep, None]
        side = (points - points[i]) @ normals.T  # (n, triples)
        above, below = (side > tol).any(axis=0), (side < -tol).any(axis=0)
        for t in np.flatnonzero(above != below):
            on = frozenset(np.flatnonzero(np.abs(side[:, t]) <= tol).tolist())
            planes.setdefault(on, normals[t] if below[t] else -normals[t])
    return planes


def _face_polygon(points: np.ndarray, indices: np.ndarray, normal: np.ndarray, area_tol: float,
                  name: str) -> tuple[int, ...]:
    """The face's corners counter-clockwise seen from outside (a 2-D convex hull)."""
    u = points[indices[1]] - points[indices[0]]
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    flat = (points[indices] - points[indices[0]]) @ np.column_stack([u, v])
    order = np.lexsort((flat[:, 1], flat[:, 0]))
    hull: list[int] = []
    for sweep in (order, order[::-1]):  # Andrew's monotone chain: lower, then upper chain
        start = len(hull)
        for p in sweep:
            while len(hull) >= start + 2 and _turn(flat, hull[-2], hull[-1], p) <= area_tol:
                hull.pop()
            hull.append(int(p))
        hull.pop()
    if len(hull) != len(indices):
        k = int(indices[sorted(set(range(len(indices))) - set(hull))[0]])
        raise ValueError(f"{name} must be in convex position: {name}[{k}] lies on an edge or "
                         "inside a face of the hull")
    return tuple(int(indices[p]) for p in hull)


def _turn(flat: np.ndarray, a: int, b: int, c: int) -> float:
    """Twice the signed area of the triangle ``a, b, c`` (> 0: counter-clockwise)."""
    ab, ac = flat[b] - flat[a], flat[c] - flat[a]
    return float(ab[0] * ac[1] - ab[1] * ac[0])

"""Rotation matrices: uniform draws, quaternions, axis-angle, turning a direction up, a check."""

from __future__ import annotations

import numpy as np

# Row k: where 4 q_k q_j (j = w, x, y, z) sits among the squares and pairs of a quaternion.
_PRODUCTS = np.array([[0, 4, 5, 6], [4, 1, 7, 8], [5, 7, 2, 9], [6, 8, 9, 3]])


def random_rotations(rng: np.random.Generator, size: int) -> np.ndarray:
    """``size`` rotation matrices drawn uniformly (Haar) over SO(3), shape (size, 3, 3)."""
    return uniform_rotations(rng.random((3, size)))


def uniform_rotations(uniforms: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) from uniforms (3, n) in [0, 1) (Shoemake 1992)."""
    u1, u2, u3 = uniforms
    a, b = np.sqrt(1 - u1), np.sqrt(u1)
    quat = np.stack([a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2),
                     b * np.sin(2 * np.pi * u3), b * np.cos(2 * np.pi * u3)], axis=-1)
    return quaternion_to_matrix(quat)


def quaternion_to_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) from unit quaternions (..., 4) ordered (w, x, y, z)."""
    w, x, y, z = np.moveaxis(np.asarray(quat, dtype=np.float64), -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def matrix_to_quaternion(rot: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4) (w, x, y, z), w >= 0, of rotation matrices (..., 3, 3).

    Each from its largest squared component (Shepperd 1978): no division near zero.
    """
    r = np.asarray(rot, dtype=np.float64)
    trace = r[..., 0, 0] + r[..., 1, 1] + r[..., 2, 2]
    squares = np.stack([1 + trace, 1 + 2 * r[..., 0, 0] - trace, 1 + 2 * r[..., 1, 1] - trace,
                        1 + 2 * r[..., 2, 2] - trace], axis=-1)  # 4 w^2, 4 x^2, 4 y^2, 4 z^2
    pairs = np.stack([  # 4 w x, 4 w y, 4 w z, 4 x y, 4 x z, 4 y z
        r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1],
        r[..., 1, 0] + r[..., 0, 1], r[..., 0, 2] + r[..., 2, 0], r[..., 2, 1] + r[..., 1, 2],
    ], axis=-1)
    k = squares.argmax(axis=-1)
    row = np.take_along_axis(np.concatenate([squares, pairs], axis=-1), _PRODUCTS[k], axis=-1)
    quat = row / np.sqrt(np.take_along_axis(squares, k[..., None], axis=-1))
    quat = quat / np.linalg.norm(quat, axis=-1, keepdims=True)
    return np.where(quat[..., :1] < 0, -quat, quat)


def matrix_to_rotation_vector(rot: np.ndarray) -> np.ndarray:
    """Rotation vectors (..., 3), axis times angle in [0, pi], of rotation matrices (..., 3, 3)."""
    quat = matrix_to_quaternion(rot)  # w >= 0: half the angle in [0, pi/2]
    half = np.arccos(np.clip(quat[..., :1], -1.0, 1.0))
    sine = np.sin(half)
    axis = np.where(sine > 1e-12, quat[..., 1:] / np.maximum(sine, 1e-12), 0.0)
    return 2.0 * half * axis


def rotation_vector_to_matrix(vectors: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of rotation vectors (..., 3): axis times angle (rad)."""
    flat = np.reshape(vectors, (-1, 3))
    angle = np.linalg.norm(flat, axis=1, keepdims=True)
    safe = np.where(angle > 0, angle, 1.0)
    quaternions = np.hstack([np.cos(angle / 2), np.sin(angle / 2) * flat / safe])
    return quaternion_to_matrix(quaternions).reshape(*np.shape(vectors)[:-1], 3, 3)


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (rad) about ``axis`` (any non-zero length), shape (3, 3)."""
    k = np.asarray(axis, dtype=np.float64)
    k = k / np.linalg.norm(k)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def up_rotation(direction: np.ndarray) -> np.ndarray:
    """A rotation (body to world, 3x3) taking the unit body ``direction`` (3,) to world +z.

    Its x row is ``|direction|`` rolled by one, made orthogonal to it (+z gives the identity).
    """
    z = np.asarray(direction, dtype=np.float64)
    x = np.roll(np.abs(z), 1)
    x = x - (x @ z) * z
    if np.linalg.norm(x) < 1e-6:  # |direction| with equal components: roll maps it to itself
        x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
    x = x / np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def orthonormality_error(rot: np.ndarray) -> np.ndarray:
    """Per matrix: ``max |R R^T - I|`` plus ``|det R - 1|`` (0 for an exact rotation)."""
    rot = np.asarray(rot, dtype=np.float64)
    gram = rot @ np.swapaxes(rot, -1, -2) - np.eye(3)
    return np.abs(gram).max(axis=(-1, -2)) + np.abs(np.linalg.det(rot) - 1)

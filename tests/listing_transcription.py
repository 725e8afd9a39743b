"""Independent reference transcription of the paper's Matlab Listings 1-3 for the tests.

``cube`` follows cube.m, ``real_throw_cube`` follows real_throw_cube.m and ``ground_cube``
follows ground_cube.m, statement by statement and in the listings' order (plotting dropped).
The listings' quirks are kept on purpose: no spin term in the initial node velocities, torque
from the un-rotated ``X_rel``, the Rodrigues ``R`` dividing by ``norm(omega)`` (NaN when omega
is zero), energy using ``I(1,1)`` and ``x_cm(3)``. ``np.fmax`` mirrors Matlab's NaN-ignoring
``max``. This module must not import ``dice_env``: it is what the kernel is checked against.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

Vec = Sequence[float] | np.ndarray

# Listing 1, line 18-19: node sign pattern, row order as in the listing.
_SIGN = np.array(
    [
        [1, 1, 1], [1, -1, 1], [-1, -1, 1], [-1, 1, 1],
        [1, 1, -1], [1, -1, -1], [-1, -1, -1], [-1, 1, -1],
    ],
    dtype=float,
)  # fmt: skip


def cube(r: float, total_mass: float) -> tuple[np.ndarray, np.ndarray]:
    """cube.m: return ``X_rel`` (8, 3) node offsets from the centre of mass and ``I`` (3, 3)."""
    s = -np.sqrt(2) + 2 * np.sqrt(0.5 + r**2)  # side length
    X_rel = _SIGN * s / 2
    I = np.diag([(1 / 6) * total_mass * s**2] * 3)  # noqa: E741
    return X_rel, I


def _unit_normal(normal: Vec) -> np.ndarray:
    ag, bg, cg = (float(c) for c in normal)
    nabcg = np.sqrt(ag**2 + bg**2 + cg**2)
    return np.array([ag / nabcg, bg / nabcg, cg / nabcg])


def _forces(
    X: np.ndarray, U: np.ndarray, n: np.ndarray, m: float, g: float,
    S: float, D: float, mu: float, umin: float,
) -> np.ndarray:  # fmt: skip
    """Lines 61-75 (Listing 2) / 59-73 (Listing 3): gravity plus ground force on each node."""
    F = np.zeros((8, 3))
    F[:, 2] = -(m / 8) * g
    dg = np.fmax(0.0, -(n[0] * X[:, 0] + n[1] * X[:, 1] + n[2] * X[:, 2]))  # depth in ground
    un = n[0] * U[:, 0] + n[1] * U[:, 1] + n[2] * U[:, 2]  # normal velocity
    fn = np.fmax(0.0, S * dg - D * un)  # normal force magnitude
    Utan = U - np.outer(un, n)
    Utan_norm = np.linalg.norm(Utan, axis=1) + umin
    Utan_dir = Utan / Utan_norm[:, None]
    return F + np.outer(fn, n) - (mu * fn)[:, None] * Utan_dir


def real_throw_cube(
    L0: Vec, *, r: float = 1.0, total_mass: float = 1.0, normal: Vec = (0, 0, 1),
    S: float = 1e4, D: float = 0.1, mu: float = 0.1, clockmax: int = 100000,
    tmax: float = 10.0, x0: Vec = (0, 0, 3), u0: Vec = (5, 0, 5), g: float = 9.8,
    record_nodes: bool = False,
) -> dict[str, np.ndarray]:  # fmt: skip
    """real_throw_cube.m with initial angular momentum ``L0`` (the listing's ``rand`` draw).

    Returns ``t`` (clockmax,), ``x_cm`` (clockmax, 3), ``energy`` (clockmax,) and, if
    ``record_nodes``, ``nodes`` (clockmax, 8, 3) = ``X`` after each step.
    """
    m = total_mass
    X_rel, I = cube(r, m)  # noqa: E741
    Idiag = np.diag(I)  # I is diagonal, so I\L is elementwise division (as mldivide does)
    n = _unit_normal(normal)
    umin = 1e-6 * r
    x_cm = np.array(x0, dtype=float)
    u_cm = np.array(u0, dtype=float)
    L = np.array(L0, dtype=float)
    omega = L / Idiag  # computed but unused before the loop, as in the listing
    X = x_cm + X_rel
    U = np.tile(u_cm, (8, 1))  # no spin term at start
    dt = tmax / clockmax
    t_save, X_save, E_save = np.zeros(clockmax), np.zeros((clockmax, 3)), np.zeros(clockmax)
    nodes = np.zeros((clockmax, 8, 3)) if record_nodes else None
    eye = np.eye(3)
    for clock in range(1, clockmax + 1):
        t = clock * dt
        F = _forces(X, U, n, m, g, S, D, mu, umin)
        u_cm = u_cm + dt * F.sum(axis=0) / m
        x_cm = x_cm + dt * u_cm
        torque = np.zeros(3)
        for k in range(8):  # X_rel before rotation
            torque = torque + np.cross(X_rel[k], F[k])
        L = L + dt * torque
        omega = L / Idiag
        nw = np.linalg.norm(omega)
        P = np.outer(omega / nw, omega / nw)
        omega_cross = np.array(
            [[0, -omega[2], omega[1]], [omega[2], 0, -omega[0]], [-omega[1], omega[0], 0]]
        )
        R = P + np.cos(nw * dt) * (eye - P) + np.sin(nw * dt) * (omega_cross / nw)
        X_rel = X_rel @ R.T  # X_rel(k,:) = (R*X_rel(k,:)')'
        U = u_cm + np.cross(omega, X_rel)
        X = x_cm + X_rel
        i = clock - 1
        t_save[i], X_save[i] = t, x_cm
        E_save[i] = 0.5 * m * np.linalg.norm(u_cm) ** 2 + 0.5 * np.linalg.norm(L) ** 2 / I[0, 0]
        E_save[i] += m * g * x_cm[2]
        if nodes is not None:
            nodes[i] = X
    out = {"t": t_save, "x_cm": X_save, "energy": E_save}
    if nodes is not None:
        out["nodes"] = nodes
    return out


def ground_cube(
    *, r: float = 1.0, total_mass: float = 1.0, normal: Vec = (0, 0, 1), S: float = 1e4,
    D: float = 0.2, mu: float = 0.075, clockmax: int = 10000, tmax: float = 10.0,
    x0: Vec = (0, 0, 3), u0: Vec = (5, 0, 5), g: float = 9.8, record_nodes: bool = False,
) -> dict[str, np.ndarray]:  # fmt: skip
    """ground_cube.m: the non-rotating cube. Same outputs as :func:`real_throw_cube`."""
    m = total_mass
    X_rel, _ = cube(r, m)
    n = _unit_normal(normal)
    umin = 1e-6 * r
    x_cm = np.array(x0, dtype=float)
    u_cm = np.array(u0, dtype=float)
    X = x_cm + X_rel
    U = np.tile(u_cm, (8, 1))
    dt = tmax / clockmax
    t_save, X_save, E_save = np.zeros(clockmax), np.zeros((clockmax, 3)), np.zeros(clockmax)
    nodes = np.zeros((clockmax, 8, 3)) if record_nodes else None
    for clock in range(1, clockmax + 1):
        t = clock * dt
        F = _forces(X, U, n, m, g, S, D, mu, umin)
        u_cm = u_cm + dt * F.sum(axis=0) / m
        x_cm = x_cm + dt * u_cm
        X = x_cm + X_rel
        U = np.tile(u_cm, (8, 1))
        i = clock - 1
        t_save[i], X_save[i] = t, x_cm
        E_save[i] = 0.5 * m * np.linalg.norm(u_cm) ** 2 + m * g * x_cm[2]
        if nodes is not None:
            nodes[i] = X
    out = {"t": t_save, "x_cm": X_save, "energy": E_save}
    if nodes is not None:
        out["nodes"] = nodes
    return out

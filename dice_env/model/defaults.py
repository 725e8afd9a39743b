"""A real die on a real table: measured material values, damping from restitution.

The default scene is a 16 mm acrylic die (4.5 g) on a wooden table (values and sources:
``docs/error-vs-runtime.md``). :func:`restitution` gives the flat-landing restitution of the
per-corner spring-dashpot ``fn = max(0, S dg - D un)``; :func:`damping_for_restitution`
inverts it. Imports only :mod:`dice_env.model.checks`.
"""

from __future__ import annotations

import math

import numpy as np

from dice_env.model.checks import check_positive, check_range

DIE_EDGE = 0.016  # a common game die (m)
DIE_MASS = 0.0045  # kg
RESTITUTION = 0.45  # normal, flat landing on a wooden table at about 1 m/s
FRICTION = 0.4  # sliding, plastic on dry wood
STIFFNESS = 1e5  # ground, per corner (N/m): corners sink at most about 3 % of the edge


def restitution(zeta: float, *, clipped: bool = True) -> float:
    """Normal restitution of a linear spring-dashpot with damping ratio ``zeta`` in [0, 1).

    ``clipped=False``: the classical ``exp(-pi zeta / sqrt(1 - zeta^2))``; ``clipped=True``:
    the force ``max(0, ...)`` ends the contact at ``S x + D x' = 0`` (Schwager & Pöschel
    2007). Gravity is neglected.
    """
    check_range("zeta", zeta, 0.0, 1.0, high_open=True)
    root = math.sqrt(1.0 - zeta * zeta)
    if not clipped:
        return math.exp(-math.pi * zeta / root)
    phase = math.pi - math.atan2(2.0 * zeta * root, 1.0 - 2.0 * zeta * zeta)
    decay = math.exp(-zeta * phase / root)
    return -decay * (math.cos(phase) - zeta / root * math.sin(phase))


def damping_ratio(target: float, *, clipped: bool = True) -> float:
    """The damping ratio giving :func:`restitution` ``target`` in (0, 1] (bisection if clipped)."""
    check_range("restitution", target, 0.0, 1.0, low_open=True)
    log_e = math.log(target)
    zeta = -log_e / math.sqrt(math.pi**2 + log_e**2)
    if not clipped:
        return zeta
    # the clipped restitution falls monotonically from 1 (zeta = 0) to a floor near 0.1
    low, high = 0.0, 0.999
    if restitution(high) > target:
        raise ValueError(f"restitution must be >= {restitution(high):.3f} with the clipped law, "
                         f"got {target}")
    for _ in range(100):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if restitution(mid) > target else (low, mid)
    return 0.5 * (low + high)


def damping_for_restitution(target: float, stiffness: float, mass: float, *,
                            clipped: bool = True) -> float:
    """Per-corner damping D (N s/m) giving restitution ``target`` for a flat landing.

    ``D = 2 zeta sqrt(S m/4) = zeta sqrt(S m)``, ``zeta`` from :func:`damping_ratio`.
    """
    check_positive("stiffness", stiffness)
    check_positive("mass", mass)
    return damping_ratio(target, clipped=clipped) * math.sqrt(stiffness * mass)


# Per-corner damping (N s/m) of the default table for the default die.
DAMPING = damping_for_restitution(RESTITUTION, STIFFNESS, DIE_MASS)


def rebound(z: np.ndarray, vz: np.ndarray, height: float, gravity: float,
            speed: float) -> float | None:
    """Restitution from a landing's record of centre height ``z`` and vertical velocity ``vz``.

    The upward speed (gravity undone) when the centre first rises through its resting
    ``height`` over the landing ``speed``; None if it never does.
    """
    left = np.flatnonzero((z > height) & (vz > 0))
    if left.size == 0:
        return None
    j = left[0]
    return math.sqrt(vz[j] ** 2 + 2.0 * gravity * (z[j] - height)) / speed


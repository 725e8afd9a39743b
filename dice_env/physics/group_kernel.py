"""Several dice in one throw: die–die contact and the group's step (numba only).

The model is ``docs/model.md``'s, the speed ``docs/performance.md``'s ("Several dice").
:func:`least_overlap` finds a touching pair's normal, :func:`pair_contacts` its contacts and
forces; :func:`advance_group` steps one throw, each die on the planes as the single die's: at
the table's step while no pair can meet within it (:func:`out_of_reach`), else the pair's;
with islands (:func:`islands`, "Islands" there), each island of dice that may meet on its own.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from dice_env.physics.kernel import (
    ABORTED,
    DECIDED,
    NONFINITE,
    NX,
    NY,
    NZ,
    OFFSET,
    RUNNING,
    SETTLED,
    UP,
    Contact,
    Options,
    PlaneContacts,
    ahead,
    angular_velocity,
    die_move,
    die_on_planes,
    face_read,
    flight_jump,
    free_steps,
    next_pass,
    relative_rise,
    rest_test,
    stick_slip,
    stopped_at,
)

# Edges closer to parallel than this (|e_a x e_b|^2 over |e_a|^2 |e_b|^2) have no edge contact:
# their overlap shows as vertices inside the other die.
PARALLEL = 1e-8
# A slip is stopped by friction over at least 1 / GRIP steps (see Pair).
GRIP = 0.25
# An edge axis is the contact's only where the overlap along it is less than this fraction of
# the least along a face normal: dice face on face, a little turned, must not meet edge on edge.
FACE_BIAS = 0.95
# A corner bears on another die's face when inside it to this fraction of that die's reach
# (corners exactly on a side plane, as in an aligned stack, must bear).
LATERAL = 1e-3
# A point inside a die is no deeper than below each face turned less than about 78 degrees from
# the way it is pushed out (this cosine; see inside_depth); a stack's sides, at right angles to
# it, bound none.
FACING = 0.2
# A die's speed bound from its island's energy (see islands), times this for round-off.
SPEED_MARGIN = 1.25
# The longest window while two dice share an island, in the least windows.
REGROUP = 4


class Bodies(NamedTuple):
    """The N dice of a throw: :class:`dice_env.physics.kernel.Body`'s fields per die, and more.

    Padded to the largest die: ``vertices`` (N, V, 3) and ``n_vertices``, ``faces`` (N, F, 3)
    and ``n_faces``; ``lock`` (N, F): the energy below which a die alone keeps the face it reads
    (``-inf``: no rule); ``floor`` (N,): a lower bound of each die's energy under that rule;
    ``low`` (N,): one on a level floor (``-inf``: none), for :func:`islands`; ``rest`` (N,):
    the energy below which a quiet die alone stays quiet (``-inf``: none; the single die's
    early rest).
    """

    vertices: np.ndarray
    n_vertices: np.ndarray
    faces: np.ndarray
    n_faces: np.ndarray
    mass: np.ndarray
    inv_inertia: np.ndarray
    inv_iso: np.ndarray
    inv_i_min: np.ndarray
    r_max: np.ndarray
    reads_down: np.ndarray
    lock: np.ndarray
    floor: np.ndarray
    low: np.ndarray
    rest: np.ndarray


class Hulls(NamedTuple):
    """The N dice's shapes as die–die contact sees them, body frames, padded by repetition.

    ``axes`` (N, A, 3): one of each pair of opposite face normals; ``directions`` (N, C, 3): one
    per class of parallel edges; ``edges`` (N, E, 2): class by class; ``classes`` (N, C + 1):
    where each class starts in ``edges``; ``planes`` (N, F, 4): ``n . r = offset``, ``n_planes``
    of them the die's own. Padding repeats the first entry: it changes no extent or test.
    """

    axes: np.ndarray
    directions: np.ndarray
    edges: np.ndarray
    classes: np.ndarray
    planes: np.ndarray
    n_planes: np.ndarray
    n_vertices: np.ndarray
    r_max: np.ndarray


class Pair(NamedTuple):
    """The die–die contact's law (``docs/model.md``, "Several dice in one throw").

    With ``stick``, a corner inside another die feels stick-slip friction (``kt``, ``ct``,
    ``dt_m`` the step over the reduced mass); the rest, regularised Coulomb friction at ``vmin``
    capped at ``grip |vt|`` (:data:`GRIP` of the reduced mass over the step). A move takes
    ``near`` steps (the unit of a throw's steps), ``apart`` while no pair is within reach
    (:func:`out_of_reach`): the pair's step and the table's.
    """

    stiffness: float
    damping: float
    friction: float
    vmin: float
    grip: float
    stick: bool
    kt: float
    ct: float
    dt_m: float
    near: int
    apart: int


class GroupStops(NamedTuple):
    """When a throw ends: as :class:`dice_env.physics.kernel.Stops`, for every die.

    Quiet: three contacts with the planes or one with another die; ``decide``: when no die's
    face can change. With ``islands``, dice step in islands (:func:`islands`) for windows of
    ``least`` to ``most`` steps.
    """

    n_steps: int
    at_rest: bool
    v_rest: float
    hold_steps: int
    decide: bool
    energy_scale: float
    islands: bool
    least: int
    most: int


class GroupDice(NamedTuple):
    """G throws of N dice, updated in place, as :class:`dice_env.physics.kernel.Dice`."""

    x: np.ndarray
    u: np.ndarray
    ang: np.ndarray
    q: np.ndarray
    w: np.ndarray


class GroupRecords(NamedTuple):
    """Every ``stride`` steps: ``x`` (G, n, N, 3) and ``orientation`` (G, n or 0, N, 3, 3)."""

    stride: int
    x: np.ndarray
    orientation: np.ndarray


class GroupOutcome(NamedTuple):
    """What each throw gives, as :class:`dice_env.simulation.group.GroupResult`, and ``abort``.

    Per die (G, N) besides: ``contacts`` (vertices on the planes at the end), ``touching``
    (touches another die at the end); ``meet`` (G, 2, N, 6): ``meet_velocity`` and ``meet_spin``.
    """

    status: np.ndarray
    unstable: np.ndarray
    rest_time: np.ndarray
    energy_rise: np.ndarray
    steps: np.ndarray
    overlap: np.ndarray
    impacts: np.ndarray
    max_pen: np.ndarray
    contacts: np.ndarray
    touching: np.ndarray
    die_impacts: np.ndarray
    touched: np.ndarray
    meet_dice: np.ndarray
    meet_steps: np.ndarray
    meet: np.ndarray
    abort: np.ndarray


@njit(cache=True, inline="always")
def contact_force(depth: float, share: float, n: tuple, v: tuple, pair: Pair) -> tuple:
    """Force (3) on the die ``n`` points into, ``depth`` deep at relative velocity ``v``; energy.

    ``share``: the point's depth over the contact's (see :func:`pair_contacts`), which scales
    its damping as its depth scales its spring.
    """
    n0, n1, n2 = n
    v0, v1, v2 = v
    vn = n0 * v0 + n1 * v1 + n2 * v2
    fn = pair.stiffness * depth - share * pair.damping * vn
    spring = 0.5 * pair.stiffness * depth * depth
    if fn <= 0.0:
        return 0.0, 0.0, 0.0, spring
    t0, t1, t2 = v0 - vn * n0, v1 - vn * n1, v2 - vn * n2
    scale = min(pair.friction * fn / (math.sqrt(t0 * t0 + t1 * t1 + t2 * t2) + pair.vmin),
                pair.grip)
    return fn * n0 - scale * t0, fn * n1 - scale * t1, fn * n2 - scale * t2, spring


@njit(cache=True, inline="always")
def _relative_velocity(a: int, b: int, point: tuple, x: np.ndarray, cu: np.ndarray,
                       cw: np.ndarray) -> tuple:
    """Die ``a``'s velocity at ``point`` relative to die ``b``'s, and the two lever arms."""
    ra0, ra1, ra2 = point[0] - x[a, 0], point[1] - x[a, 1], point[2] - x[a, 2]
    rb0, rb1, rb2 = point[0] - x[b, 0], point[1] - x[b, 1], point[2] - x[b, 2]
    va0 = cu[a, 0] + cw[a, 1] * ra2 - cw[a, 2] * ra1
    va1 = cu[a, 1] + cw[a, 2] * ra0 - cw[a, 0] * ra2
    va2 = cu[a, 2] + cw[a, 0] * ra1 - cw[a, 1] * ra0
    vb0 = cu[b, 0] + cw[b, 1] * rb2 - cw[b, 2] * rb1
    vb1 = cu[b, 1] + cw[b, 2] * rb0 - cw[b, 0] * rb2
    vb2 = cu[b, 2] + cw[b, 0] * rb1 - cw[b, 1] * rb0
    return (va0 - vb0, va1 - vb1, va2 - vb2), (ra0, ra1, ra2), (rb0, rb1, rb2)


@njit(cache=True, inline="always")
def _apply(a: int, b: int, f: tuple, ra: tuple, rb: tuple, force: np.ndarray,
           torque: np.ndarray) -> None:
    """The force ``f`` on die ``a`` and ``-f`` on die ``b``, at lever arms ``ra`` and ``rb``."""
    f0, f1, f2 = f
    ra0, ra1, ra2 = ra
    rb0, rb1, rb2 = rb
    force[a, 0] += f0
    force[a, 1] += f1
    force[a, 2] += f2
    force[b, 0] -= f0
    force[b, 1] -= f1
    force[b, 2] -= f2
    torque[a, 0] += ra1 * f2 - ra2 * f1
    torque[a, 1] += ra2 * f0 - ra0 * f2
    torque[a, 2] += ra0 * f1 - ra1 * f0
    torque[b, 0] -= rb1 * f2 - rb2 * f1
    torque[b, 1] -= rb2 * f0 - rb0 * f2
    torque[b, 2] -= rb0 * f1 - rb1 * f0


@njit(cache=True, inline="always")
def _push(a: int, b: int, point: tuple, depth: float, share: float, n: tuple, x: np.ndarray,
          cu: np.ndarray, cw: np.ndarray, pair: Pair, force: np.ndarray,
          torque: np.ndarray) -> float:
    """A contact pushing die ``a`` along ``n``, ``b`` against it; returns the spring's energy."""
    v, ra, rb = _relative_velocity(a, b, point, x, cu, cw)
    f0, f1, f2, spring = contact_force(depth, share, n, v, pair)
    _apply(a, b, (f0, f1, f2), ra, rb, force, torque)
    return spring


@njit(cache=True, forceinline=True)
def _push_tied(a: int, b: int, first: int, k: int, point: tuple, depth: float, share: float,
               n: tuple, x: np.ndarray, q: np.ndarray, cu: np.ndarray, cw: np.ndarray, pair: Pair,
               ties: np.ndarray, fresh: bool, force: np.ndarray, torque: np.ndarray) -> tuple:
    """:func:`_push` for corner ``k`` of die ``first`` (``a`` or ``b``) with stick-slip friction.

    ``ties`` (N, V, N, 4): the tie point on the other die (its body frame), and 1 while tied;
    ``fresh``: the pair did not touch at the last step. Returns the two springs' energy.
    """
    other = b if first == a else a
    v, ra, rb = _relative_velocity(a, b, point, x, cu, cw)
    n0, n1, n2 = n
    vn = n0 * v[0] + n1 * v[1] + n2 * v[2]
    fn = pair.stiffness * depth - share * pair.damping * vn
    spring = 0.5 * pair.stiffness * depth * depth
    if fn <= 0.0:
        ties[first, k, other, 3] = 0.0
        return spring, 0.0
    s = 1.0 if first == a else -1.0  # the corner's die's slip is s times a's
    ut = (s * (v[0] - vn * n0), s * (v[1] - vn * n1), s * (v[2] - vn * n2))
    c0, c1, c2 = ties[first, k, other, 0], ties[first, k, other, 1], ties[first, k, other, 2]
    anchor = (x[other, 0] + q[other, 0, 0] * c0 + q[other, 0, 1] * c1 + q[other, 0, 2] * c2,
              x[other, 1] + q[other, 1, 0] * c0 + q[other, 1, 1] * c1 + q[other, 1, 2] * c2,
              x[other, 2] + q[other, 2, 0] * c0 + q[other, 2, 1] * c1 + q[other, 2, 2] * c2)
    ft0, ft1, ft2, stored, anchor = stick_slip(
        (n0, n1, n2, 0.0, 0.0, 0.0, 0.0, pair.kt, pair.ct), 0.0, 0.0, point, ut,
        pair.friction * fn, 0.0, pair.dt_m, anchor, ties[first, k, other, 3] > 0.0 and not fresh)
    d0, d1, d2 = anchor[0] - x[other, 0], anchor[1] - x[other, 1], anchor[2] - x[other, 2]
    for r in range(3):
        ties[first, k, other, r] = q[other, 0, r] * d0 + q[other, 1, r] * d1 \
            + q[other, 2, r] * d2
    ties[first, k, other, 3] = 1.0
    _apply(a, b, (fn * n0 + s * ft0, fn * n1 + s * ft1, fn * n2 + s * ft2), ra, rb, force,
           torque)
    return spring, stored


@njit(cache=True, inline="always")
def _extent(die: int, n0: float, n1: float, n2: float, world: np.ndarray) -> tuple:
    """The least and the largest projection on ``n`` of die ``die``'s corners in ``world``."""
    low, high = np.inf, -np.inf
    for k in range(world.shape[1]):
        along = n0 * world[die, k, 0] + n1 * world[die, k, 1] + n2 * world[die, k, 2]
        low, high = min(low, along), max(high, along)
    return low, high


@njit(cache=True, inline="always")
def _turned(q: np.ndarray, die: int, v: tuple) -> tuple:
    """The body-frame vector ``v`` of die ``die`` in the world: ``q[die] v``."""
    return (q[die, 0, 0] * v[0] + q[die, 0, 1] * v[1] + q[die, 0, 2] * v[2],
            q[die, 1, 0] * v[0] + q[die, 1, 1] * v[1] + q[die, 1, 2] * v[2],
            q[die, 2, 0] * v[0] + q[die, 2, 1] * v[1] + q[die, 2, 2] * v[2])


@njit(cache=True, inline="always")
def _cross_axis(e: tuple, h: tuple) -> tuple:
    """The unit cross product of unit ``e`` and ``h``, and False if parallel (:data:`PARALLEL`)."""
    c0, c1, c2 = e[1] * h[2] - e[2] * h[1], e[2] * h[0] - e[0] * h[2], e[0] * h[1] - e[1] * h[0]
    size2 = c0 * c0 + c1 * c1 + c2 * c2
    if size2 <= PARALLEL:
        return (0.0, 0.0, 0.0), False
    size = math.sqrt(size2)
    return (c0 / size, c1 / size, c2 / size), True


@njit(cache=True, inline="always")
def _axis_overlap(a: int, b: int, n: tuple, world: np.ndarray, x: np.ndarray) -> tuple:
    """Dice ``a`` and ``b``'s overlap along the unit axis ``n``, and ``n`` turned toward ``a``."""
    n0, n1, n2 = n
    low_a, high_a = _extent(a, n0, n1, n2, world)
    low_b, high_b = _extent(b, n0, n1, n2, world)
    if n0 * (x[a, 0] - x[b, 0]) + n1 * (x[a, 1] - x[b, 1]) + n2 * (x[a, 2] - x[b, 2]) >= 0.0:
        return high_b - low_a, (n0, n1, n2)
    return high_a - low_b, (-n0, -n1, -n2)


@njit(cache=True, inline="always")
def _candidate_overlap(c: int, a: int, b: int, world: np.ndarray, x: np.ndarray,
                       q: np.ndarray, axes: np.ndarray, directions: np.ndarray) -> tuple:
    """Overlap along :func:`least_overlap`'s axis ``c``, the axis (``b`` to ``a``), if real."""
    n_a, n_c = axes.shape[1], directions.shape[1]
    if c < 2 * n_a:
        die, s = (a, c) if c < n_a else (b, c - n_a)
        n, real = _turned(q, die, (axes[die, s, 0], axes[die, s, 1], axes[die, s, 2])), True
    else:
        ca, cb = (c - 2 * n_a) // n_c, (c - 2 * n_a) % n_c
        n, real = _cross_axis(
            _turned(q, a, (directions[a, ca, 0], directions[a, ca, 1], directions[a, ca, 2])),
            _turned(q, b, (directions[b, cb, 0], directions[b, cb, 1], directions[b, cb, 2])))
    if not real:
        return np.inf, n, False
    overlap, axis = _axis_overlap(a, b, n, world, x)
    return overlap, axis, True


@njit(cache=True)
def least_overlap(a: int, b: int, world: np.ndarray, x: np.ndarray, q: np.ndarray,
                  axes: np.ndarray, directions: np.ndarray, first: int) -> tuple:
    """The axis along which dice ``a`` and ``b`` overlap least (separating axes).

    Face ``axes`` of both, then crosses of edge ``directions``; ``first`` (-1: none) first.
    Returns ``(overlap, n, c)``: ``c`` the separating axis if ``overlap <= 0`` (else -1), ``n``
    from ``b`` toward ``a``. A face axis wins unless an edge axis is less by :data:`FACE_BIAS`.
    """
    if first >= 0:
        overlap, axis, real = _candidate_overlap(first, a, b, world, x, q, axes, directions)
        if real and overlap <= 0.0:
            return overlap, axis, first
    best, n, c = np.inf, (0.0, 0.0, 0.0), 0
    for die in (a, b):
        for s in range(axes.shape[1]):
            overlap, axis = _axis_overlap(
                a, b, _turned(q, die, (axes[die, s, 0], axes[die, s, 1], axes[die, s, 2])),
                world, x)
            if overlap <= 0.0:
                return overlap, axis, c
            if overlap < best:
                best, n = overlap, axis
            c += 1
    edge, edge_n = np.inf, (0.0, 0.0, 0.0)
    for ca in range(directions.shape[1]):
        e = _turned(q, a, (directions[a, ca, 0], directions[a, ca, 1], directions[a, ca, 2]))
        for cb in range(directions.shape[1]):
            c += 1
            axis, real = _cross_axis(e, _turned(
                q, b, (directions[b, cb, 0], directions[b, cb, 1], directions[b, cb, 2])))
            if not real:
                continue
            overlap, axis = _axis_overlap(a, b, axis, world, x)
            if overlap <= 0.0:
                return overlap, axis, c - 1
            if overlap < edge:
                edge, edge_n = overlap, axis
    if edge < FACE_BIAS * best:
        return edge, edge_n, -1
    return best, n, -1


@njit(cache=True, inline="always")
def within(h: tuple, die: int, hulls: Hulls, tol: float) -> bool:
    """Whether ``h`` (body frame) is inside die ``die``, its faces' planes moved out by ``tol``."""
    planes = hulls.planes
    for f in range(hulls.n_planes[die]):
        if planes[die, f, 0] * h[0] + planes[die, f, 1] * h[1] + planes[die, f, 2] * h[2] \
                - planes[die, f, 3] > tol:
            return False
    return True


@njit(cache=True, inline="always")
def inside_depth(h: tuple, depth: float, die: int, out: tuple, hulls: Hulls) -> float:
    """How deep the point ``h`` inside die ``die`` lies along ``out`` (both in its body frame).

    At most ``depth`` (below the die's extreme along ``out``); each face turned toward ``out``
    by more than :data:`FACING` bounds it by ``h``'s depth below that face times
    ``(1 - FACING) / (cos - FACING)``: exactly for a face square to ``out``, without limit as
    the face turns to :data:`FACING`, so that the bound never jumps.
    """
    planes = hulls.planes
    for f in range(hulls.n_planes[die]):
        m0, m1, m2 = planes[die, f, 0], planes[die, f, 1], planes[die, f, 2]
        facing = m0 * out[0] + m1 * out[1] + m2 * out[2]
        if facing > FACING:
            below = planes[die, f, 3] - (m0 * h[0] + m1 * h[1] + m2 * h[2])
            depth = min(depth, below * (1.0 - FACING) / (facing - FACING))
    return depth


@njit(cache=True, inline="always")
def _middle(h0: tuple, h1: tuple, die: int, hulls: Hulls) -> tuple:
    """The middle of the stretch of the segment ``h0``-``h1`` inside die ``die`` (body frame)."""
    planes = hulls.planes
    low, high = 0.0, 1.0
    for f in range(hulls.n_planes[die]):
        m0, m1, m2 = planes[die, f, 0], planes[die, f, 1], planes[die, f, 2]
        above0 = m0 * h0[0] + m1 * h0[1] + m2 * h0[2] - planes[die, f, 3]
        above1 = m0 * h1[0] + m1 * h1[1] + m2 * h1[2] - planes[die, f, 3]
        if above0 > 0.0 and above0 > above1:
            low = max(low, above0 / (above0 - above1))
        elif above1 > 0.0 and above1 > above0:
            high = min(high, above0 / (above0 - above1))
    t = 0.5 * (low + high)
    return (h0[0] + t * (h1[0] - h0[0]), h0[1] + t * (h1[1] - h0[1]),
            h0[2] + t * (h1[2] - h0[2]))


@njit(cache=True, inline="always")
def _seen(p: tuple, along: float, n: tuple, seen: np.ndarray, n_seen: int) -> int:
    """Note the contact point ``p`` (``along`` the axis ``n``) as seen across the axis."""
    seen[n_seen, 0] = p[0] - along * n[0]
    seen[n_seen, 1] = p[1] - along * n[1]
    seen[n_seen, 2] = p[2] - along * n[2]
    return n_seen + 1


@njit(cache=True, forceinline=True)
def _crossings(a: int, b: int, first: int, other: int, n: tuple, out: tuple, high_b: float,
               low_a: float, world: np.ndarray, x: np.ndarray, q: np.ndarray, cu: np.ndarray,
               cw: np.ndarray, hulls: Hulls, pair: Pair, seen: np.ndarray, n_seen: int,
               gap2: float, force: np.ndarray, torque: np.ndarray) -> tuple:
    """Push every point where an edge of die ``first`` passes through a face of ``other``.

    Unless within ``sqrt(gap2)`` across the axis of a point in ``seen``; ``out``: the axis out
    of ``other`` (its body frame), as :func:`inside_depth`. A point is no deeper than the
    middle of its edge's stretch inside ``other``: an edge that grazes a ridge of ``other`` far
    from that die's extreme bears as little as it is inside. Returns the springs' energy and
    the new count in ``seen``.
    """
    n0, n1, n2 = n
    planes, edges = hulls.planes, hulls.edges
    tol = LATERAL * hulls.r_max[other]
    spring = 0.0
    for e in range(hulls.classes[first, hulls.classes.shape[1] - 1]):
        k0, k1 = edges[first, e, 0], edges[first, e, 1]
        p0 = (world[first, k0, 0], world[first, k0, 1], world[first, k0, 2])
        p1 = (world[first, k1, 0], world[first, k1, 1], world[first, k1, 2])
        h0, h1 = _turned_back(q, other, p0, x), _turned_back(q, other, p1, x)
        for f in range(hulls.n_planes[other]):
            m0, m1, m2, offset = planes[other, f, 0], planes[other, f, 1], planes[other, f, 2], \
                planes[other, f, 3]
            above0 = m0 * h0[0] + m1 * h0[1] + m2 * h0[2] - offset
            above1 = m0 * h1[0] + m1 * h1[1] + m2 * h1[2] - offset
            if not (above0 < 0.0 < above1 or above1 < 0.0 < above0):
                continue
            t = above0 / (above0 - above1)
            p = (p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1]),
                 p0[2] + t * (p1[2] - p0[2]))
            along = n0 * p[0] + n1 * p[1] + n2 * p[2]
            depth = high_b - along if first == a else along - low_a
            if depth <= 0.0:
                continue
            if not within(_turned_back(q, other, p, x), other, hulls, tol):
                continue
            local = inside_depth(_middle(h0, h1, other, hulls), depth, other, out, hulls)
            if local <= 0.0:
                continue
            r0, r1, r2 = p[0] - along * n0, p[1] - along * n1, p[2] - along * n2
            fresh = True
            for j in range(n_seen):
                g0, g1, g2 = seen[j, 0] - r0, seen[j, 1] - r1, seen[j, 2] - r2
                if g0 * g0 + g1 * g1 + g2 * g2 < gap2:
                    fresh = False
                    break
            if not fresh:
                continue
            n_seen = _seen(p, along, n, seen, n_seen)
            spring += _push(a, b, p, local, local / depth, n, x, cu, cw, pair, force, torque)
    return spring, n_seen


@njit(cache=True, inline="always")
def _turned_back(q: np.ndarray, die: int, p: tuple, x: np.ndarray) -> tuple:
    """The world point ``p`` in die ``die``'s body frame: ``q[die]^T (p - x[die])``."""
    return _body(q, die, (p[0] - x[die, 0], p[1] - x[die, 1], p[2] - x[die, 2]))


@njit(cache=True, inline="always")
def _body(q: np.ndarray, die: int, v: tuple) -> tuple:
    """The world vector ``v`` in die ``die``'s body frame: ``q[die]^T v``."""
    return (q[die, 0, 0] * v[0] + q[die, 1, 0] * v[1] + q[die, 2, 0] * v[2],
            q[die, 0, 1] * v[0] + q[die, 1, 1] * v[1] + q[die, 2, 1] * v[2],
            q[die, 0, 2] * v[0] + q[die, 1, 2] * v[1] + q[die, 2, 2] * v[2])


@njit(cache=True)
def pair_contacts(a: int, b: int, n: tuple, world: np.ndarray, x: np.ndarray, q: np.ndarray,
                  cu: np.ndarray, cw: np.ndarray, hulls: Hulls, pair: Pair, ties: np.ndarray,
                  fresh: bool, seen: np.ndarray, force: np.ndarray, torque: np.ndarray) -> tuple:
    """Every contact of the overlapping dice ``a`` and ``b``, their forces applied.

    ``n``: :func:`least_overlap`'s axis. Corners inside the other die (:func:`_push_tied` with
    ``pair.stick``), then :func:`_crossings`. A point is as deep as it lies beyond the other
    die's extreme along ``n`` or, where less, inside that die (:func:`inside_depth`), and bears
    that share of the damping. Returns the two springs' energy, whether one bears.
    """
    n_vertices = hulls.n_vertices
    n0, n1, n2 = n
    low_a = _extent(a, n0, n1, n2, world)[0]
    high_b = _extent(b, n0, n1, n2, world)[1]
    r_max = hulls.r_max
    spring, stored, found, n_seen = 0.0, 0.0, False, np.int64(0)  # one type: one compile
    # the axis out of each die, in its body frame: a's corners leave b along n, b's a along -n
    out_b, out_a = _body(q, b, n), _body(q, a, (-n0, -n1, -n2))
    for first, other, out in ((a, b, out_b), (b, a, out_a)):
        tol = LATERAL * r_max[other]
        for k in range(n_vertices[first]):
            p = (world[first, k, 0], world[first, k, 1], world[first, k, 2])
            along = n0 * p[0] + n1 * p[1] + n2 * p[2]
            depth = high_b - along if first == a else along - low_a
            local = 0.0
            if depth > 0.0:
                h = _turned_back(q, other, p, x)
                if within(h, other, hulls, tol):
                    local = inside_depth(h, depth, other, out, hulls)
            if local <= 0.0:
                if pair.stick:
                    ties[first, k, other, 3] = 0.0
                continue
            found = True
            n_seen = _seen(p, along, n, seen, n_seen)
            if pair.stick:
                spring_k, stored_k = _push_tied(a, b, first, k, p, local, local / depth, n, x, q,
                                                cu, cw, pair, ties, fresh, force, torque)
                spring += spring_k
                stored += stored_k
            else:
                spring += _push(a, b, p, local, local / depth, n, x, cu, cw, pair, force, torque)
    gap2 = (LATERAL * min(r_max[a], r_max[b])) ** 2
    for first, other, out in ((a, b, out_b), (b, a, out_a)):
        spring_c, n_seen = _crossings(a, b, first, other, n, out, high_b, low_a, world,
                                                 x, q, cu, cw, hulls, pair, seen, n_seen, gap2,
                                                 force, torque)
        spring += spring_c
    return spring, stored, found or n_seen > 0


@njit(cache=True)
def advance_group(g: int, dice: GroupDice, bodies: Bodies, hulls: Hulls, pair: Pair,
                   contact: Contact, options: Options, stops: GroupStops, records: GroupRecords,
                   out: GroupOutcome) -> None:
    """Advance throw ``g`` (its N dice) in place; see :func:`simulate_groups`.

    The dice step together, or with ``stops.islands`` (a level floor) in windows: each island
    (:func:`islands`) steps on its own to the window's end, and one at rest sleeps until a
    die that may reach it wakes it.
    """
    n_dice, n_planes = dice.x.shape[1], contact.planes.shape[0]
    planes, contact_law, stick, vmin = contact.planes, contact.law, contact.stick, contact.vmin
    vertices, n_vertices, mass = bodies.vertices, bodies.n_vertices, bodies.mass
    inv_inertia, inv_iso, r_max = bodies.inv_inertia, bodies.inv_iso, bodies.r_max
    axes, directions = hulls.axes, hulls.directions  # taken once: each costs a reference count
    n0, n1, n2, floor = planes[0, NX], planes[0, NY], planes[0, NZ], planes[0, OFFSET]
    rotation, midpoint, dt, g_acc = options.rotation, options.midpoint, options.dt, options.gravity
    x, u, ang, q = dice.x[g].copy(), dice.u[g].copy(), dice.ang[g].copy(), dice.q[g].copy()
    w = dice.w[g].copy() if rotation else np.zeros((n_dice, 3))
    pu, pw = u.copy(), w.copy()  # velocities one step back, for the midpoint forces
    cu, cw = np.empty((n_dice, 3)), np.empty((n_dice, 3))
    n_v = vertices.shape[1]
    world = np.empty((n_dice, n_v, 3))  # every die's corners, placed where a pair may touch
    placed = np.zeros(n_dice, np.bool_)
    flat = vertices.reshape((n_dice * n_v, 3))  # die a's vertices from row a n_v on
    offsets = np.empty((n_dice * n_v, 3))
    lowest = np.empty((n_dice, n_planes))  # each die's lowest vertex height over each plane
    contacts = PlaneContacts(offsets, np.full((n_planes, n_dice * n_v), -1.0),
                             np.zeros((n_planes, n_dice * n_v, 3)),
                             np.zeros((n_planes, n_dice * n_v), np.bool_), lowest)
    # likewise die against die (see _push_tied)
    die_ties = np.zeros((n_dice, n_v, n_dice, 4) if pair.stick else (0, 0, 0, 4))
    seen = np.empty((2 * n_v + 2 * hulls.edges.shape[1] * hulls.planes.shape[1], 3))
    force, torque = np.empty((n_dice, 3)), np.empty((n_dice, 3))
    kinetic = np.empty(n_dice)
    qa, inv_a = np.empty((3, 3)), np.empty((3, 3))
    touched, max_pen = out.touched, out.max_pen
    touching = np.zeros(n_dice, np.int64)
    near, was = np.zeros(n_dice, np.bool_), np.ones(n_dice, np.bool_)
    fastest, approach = np.zeros(n_dice), np.zeros(n_dice)
    die_touch = np.zeros(n_dice, np.bool_)
    met = np.zeros((n_dice, n_dice), np.bool_)  # each pair touching after the last step
    separating = np.full((n_dice, n_dice), -1, np.int64)  # least_overlap's first axis per pair
    first_a, first_b, parted = -1, -1, False
    v_rest2 = stops.v_rest * stops.v_rest
    floor_total = 0.0
    for a in range(n_dice):
        floor_total += bodies.floor[a]
    decisive = -np.inf  # _decided is False unless the energy is below this
    if stops.decide:
        decisive = np.inf
        for a in range(n_dice):
            decisive = min(decisive, bodies.lock[a].max() + floor_total - bodies.floor[a])
    n_steps, stride, n_rec = stops.n_steps, records.stride, records.x.shape[1]
    e_tol, rise = stops.energy_scale, -np.inf  # rise: the throw's energy over its first
    passes, end = 0, RUNNING
    fine, coarse = pair.near, pair.apart
    depths = np.empty((n_dice, n_dice))  # each pair's overlap (< 0: a gap), as pair_depths
    gaps2, normals = np.empty((n_dice, n_dice)), np.empty((n_dice, n_dice, 3))
    speed = np.empty(n_dice)  # each die's speed bound, taken as needed (_speed)
    overlap, abort = out.overlap[g], out.abort
    # each die's steps, the step its rest began, its island's quiet steps and last move
    clock, rest_at = np.zeros(n_dice, np.int64), np.zeros(n_dice, np.int64)
    quiet_of, moved_of, h_of = np.zeros(n_dice, np.int64), np.ones(n_dice, np.int64), \
        np.full(n_dice, fine * dt)
    asleep = np.zeros(n_dice, np.bool_)
    # each die's energy at its last step (a pair's springs shared), as checked and tangential
    energy, stored = np.zeros(n_dice), np.zeros(n_dice)
    label, members, pool = np.zeros(n_dice, np.int64), np.arange(n_dice), np.empty(n_dice)
    level = stops.islands and n0 == 0.0 and n1 == 0.0 and n2 == 1.0
    least = max(1, stops.least // coarse) * coarse  # a window's steps, whole moves apart
    most = max(least, stops.most // coarse * coarse)
    for a in range(n_dice):  # at most, the spin's taken about the least inertia
        energy[a] = 0.5 * mass[a] * (u[a, 0] ** 2 + u[a, 1] ** 2 + u[a, 2] ** 2) + 0.5 * (
            ang[a, 0] ** 2 + ang[a, 1] ** 2 + ang[a, 2] ** 2) * bodies.inv_i_min[a] \
            + mass[a] * g_acc * x[a, 2]
    first = 0.0  # the throw's energy: each die's at its first step (until then, as above)
    for a in range(n_dice):
        first += energy[a]
    t = 0
    while t < n_steps and end == RUNNING:
        t_end = n_steps
        if level:
            window = islands(x, q, energy, stored, bodies, hulls, world, separating, depths,
                             label, pool, least * dt) / dt
            parted = _part(out, g, t, label, met, first_a, first_b, parted, members, u, w)
            longest = most
            for a in range(n_dice):
                if label[a] != a:  # dice together: seen again soon, to part when they can
                    longest = REGROUP * least
            t_end = min(n_steps, t + (longest if not window < longest
                                      else max(least, int(window) // coarse * coarse)))
        for c in range(n_dice):
            n_m, own, others, others_t, quiet, moved = _gather(
                c, t, label, asleep, energy, stored, clock, quiet_of, moved_of, members, records,
                g, x, q)
            if n_m == 0:
                continue
            step, next_record, island = t, (t // stride + 1) * stride, RUNNING
            while step < t_end:
                passes, island = next_pass(passes, abort)
                if island == ABORTED:
                    break
                step += 1
                apart = pair_depths(members, n_m, x, q, vertices, n_vertices, r_max, world,
                                    placed, axes, directions, separating, depths, gaps2,
                                    normals)  # every pair's spheres apart
                for i in range(n_m):
                    speed[members[i]] = np.nan
                moves = min(fine, t_end - step + 1)  # ``coarse`` while no pair can meet
                if coarse > fine and step - 1 + coarse <= t_end and out_of_reach(
                        members, n_m, depths, gaps2, r_max, u, w, speed, coarse * dt):
                    moves = coarse
                h = moves * dt
                checked, tangential = 0.0, 0.0
                for i in range(n_m):
                    a = members[i]
                    if midpoint and h != h_of[a]:  # the last kick, as it would be over this step
                        _rescale(a, u, pu, h / h_of[a])
                        _rescale(a, w, pw, h / h_of[a])
                    h_of[a] = h
                    u0, u1, u2, w0, w1, w2 = u[a, 0], u[a, 1], u[a, 2], w[a, 0], w[a, 1], w[a, 2]
                    cu0, cu1, cu2, cw0, cw1, cw2 = u0, u1, u2, w0, w1, w2
                    if midpoint:
                        cu0, cu1, cu2 = ahead((u0, u1, u2), (pu[a, 0], pu[a, 1], pu[a, 2]))
                        cw0, cw1, cw2 = ahead((w0, w1, w2), (pw[a, 0], pw[a, 1], pw[a, 2]))
                    cu[a, 0], cu[a, 1], cu[a, 2], cw[a, 0], cw[a, 1], cw[a, 2] = cu0, cu1, cu2, \
                        cw0, cw1, cw2
                    l0, l1, l2 = ang[a, 0], ang[a, 1], ang[a, 2]
                    if not inv_iso[a] > 0.0:  # else angular_velocity reads neither
                        _take(a, q, inv_inertia, inv_iso, qa, inv_a)
                    wl0, wl1, wl2 = angular_velocity(qa, inv_a, inv_iso[a], l0, l1, l2)
                    m = mass[a]
                    kinetic[a] = 0.5 * m * (u0 * u0 + u1 * u1 + u2 * u2) + 0.5 * (
                        l0 * wl0 + l1 * wl1 + l2 * wl2)
                    near[a] = stops.at_rest and kinetic[a] < 0.5 * m * stops.v_rest * stops.v_rest
                    x0, x1, x2 = x[a, 0], x[a, 1], x[a, 2]
                    law = (contact_law, stick, vmin, midpoint, rotation, h, h / m, m * g_acc)
                    (f0, f1, f2, t0, t1, t2, spring, spring_t, touching[a], approach[a],
                     fastest[a], sink) = die_on_planes(  # unsigned rows: no look for a negative
                        a, np.uint64(a * n_v), np.uint64(n_vertices[a]), flat, planes, law,
                        contacts, (q[a, 0, 0], q[a, 0, 1], q[a, 0, 2], q[a, 1, 0], q[a, 1, 1],
                                   q[a, 1, 2], q[a, 2, 0], q[a, 2, 1], q[a, 2, 2]),
                        ((x0, x1, x2), (u0, u1, u2), (w0, w1, w2), (cu0, cu1, cu2),
                         (cw0, cw1, cw2)), near[a])
                    max_pen[g, a] = max(max_pen[g, a], sink)
                    for p in range(n_planes):
                        if lowest[a, p] < 0.0:
                            touched[g, a, p] = True
                    force[a, 0], force[a, 1], force[a, 2] = f0, f1, f2
                    torque[a, 0], torque[a, 1], torque[a, 2] = t0, t1, t2
                    energy[a] = kinetic[a] + m * g_acc * x2 + spring
                    stored[a] = spring_t
                    checked += energy[a]
                    tangential += spring_t
                # die against die
                for i in range(n_m):
                    die_touch[members[i]] = False
                for i in range(n_m):
                    a = members[i]
                    for j in range(i + 1, n_m):
                        b = members[j]
                        touch_ab = False
                        if depths[a, b] > 0.0:
                            spring, tied, touch_ab = pair_contacts(
                                a, b, (normals[a, b, 0], normals[a, b, 1], normals[a, b, 2]),
                                world, x, q, cu, cw, hulls, pair, die_ties, not met[a, b], seen,
                                force, torque)
                            checked += spring
                            tangential += tied
                            energy[a] += 0.5 * spring
                            energy[b] += 0.5 * spring
                            stored[a] += 0.5 * tied
                            stored[b] += 0.5 * tied
                            overlap = max(overlap, depths[a, b])
                        if touch_ab and not met[a, b]:
                            s0, s1, s2 = u[a, 0] - u[b, 0], u[a, 1] - u[b, 1], u[a, 2] - u[b, 2]
                            if s0 * s0 + s1 * s1 + s2 * s2 > v_rest2:
                                out.die_impacts[g, a] += 1
                                out.die_impacts[g, b] += 1
                            if first_a < 0 or step - 1 < out.meet_steps[g, 0]:  # the earliest
                                if first_a >= 0:  # met later in an island stepped before
                                    _forget_meeting(out, g)
                                first_a, first_b, parted = a, b, False
                                _meeting(out, g, 0, step - 1, members, n_m, u, w)
                        elif met[a, b] and not touch_ab and a == first_a and b == first_b \
                                and not parted:
                            parted = True
                            _meeting(out, g, 1, step - 1, members, n_m, u, w)
                        met[a, b] = touch_ab
                        if touch_ab:
                            die_touch[a] = True
                            die_touch[b] = True
                if step == 1:
                    first += checked - own  # the island's first step in place of its start
                    for i in range(n_m):
                        a = members[i]
                        e_tol += kinetic[a]
                        e_tol += mass[a] * g_acc * max(0.0, (n0 * x[a, 0] + n1 * x[a, 1]
                                                             + n2 * x[a, 2]) - floor)
                else:  # the other islands' energies at their last step
                    rise = max(rise, checked + others - first)
                for i in range(n_m):
                    a = members[i]
                    now = touching[a] > 0 or die_touch[a]
                    if now and not was[a] and approach[a] > stops.v_rest:
                        out.impacts[g, a] += 1
                    was[a] = now
                # no island gains energy: the others' at their last step bound theirs to come
                bound = others_t + (others + checked) + tangential
                if bound < decisive and _decided(bodies, q, bound, floor_total, UP):
                    island = DECIDED
                    break
                if stops.at_rest:
                    quiet_now = True
                    for i in range(n_m):
                        a = members[i]
                        if not ((touching[a] >= 3 or die_touch[a]) and near[a]
                                and fastest[a] < v_rest2):
                            quiet_now = False
                            break
                    a = members[0]  # a die alone may prove its rest (level: else -inf)
                    quiet, island = rest_test(quiet_now, quiet + (moved - 1 if quiet > 0 else 0),
                                              stops.hold_steps, n_m == 1 and level
                                              and energy[a] + stored[a] < bodies.rest[a])
                    if island == SETTLED:
                        break
                jump = 1
                # only moves apart jump, as stepping would take them; no record inside a jump
                if options.flight and apart and moves == coarse and _airborne(members, n_m,
                                                                              touching):
                    for i in range(n_m):
                        _speed(members[i], u, w, r_max, speed)
                    jump = min(_group_jump(members, n_m, planes, lowest, speed, x, u, ang, force,
                                           bodies, rotation, h, (t_end - step + 1) // moves),
                               (next_record - step + moves) // moves)
                finite = True
                for i in range(n_m):
                    a = members[i]
                    dt_m = h / mass[a]
                    dv0, dv1, dv2 = force[a, 0] * dt_m, force[a, 1] * dt_m, force[a, 2] * dt_m
                    _take(a, q, inv_inertia, inv_iso, qa, inv_a)
                    finite, (x0, x1, x2), (nu0, nu1, nu2), (l0, l1, l2), (w0, w1, w2) = \
                        die_move((x[a, 0], x[a, 1], x[a, 2]), (u[a, 0], u[a, 1], u[a, 2]),
                                 (ang[a, 0], ang[a, 1], ang[a, 2]), (w[a, 0], w[a, 1], w[a, 2]),
                                 (dv0, dv1, dv2), (torque[a, 0], torque[a, 1], torque[a, 2]),
                                 qa, inv_a, inv_iso[a], h, jump, rotation)
                    if not finite:
                        break
                    if midpoint:
                        pu[a, 0], pu[a, 1], pu[a, 2] = nu0 - dv0, nu1 - dv1, nu2 - dv2
                        pw[a, 0], pw[a, 1], pw[a, 2] = w[a, 0], w[a, 1], w[a, 2]
                    u[a, 0], u[a, 1], u[a, 2], x[a, 0], x[a, 1], x[a, 2] = nu0, nu1, nu2, x0, x1, \
                        x2
                    ang[a, 0], ang[a, 1], ang[a, 2] = l0, l1, l2
                    w[a, 0], w[a, 1], w[a, 2] = w0, w1, w2
                    for r in range(3):
                        for c2 in range(3):
                            q[a, r, c2] = qa[r, c2]
                if not finite:
                    island = NONFINITE
                    break
                moved = moves * jump
                step += moved - 1
                if step >= next_record:  # a record inside a move holds the state at its end
                    for j in range(next_record // stride - 1, min(step // stride, n_rec)):
                        for i in range(n_m):
                            _record(records, j, g, members[i], x, q)
                    next_record = (step // stride + 1) * stride
            step, rest = stopped_at(island, step, quiet)
            for i in range(n_m):
                a = members[i]
                clock[a], rest_at[a], quiet_of[a], moved_of[a] = step, rest, quiet, moved
                asleep[a] = island == SETTLED
            if island != RUNNING and island != SETTLED:
                end = island
                break
        if end == RUNNING and asleep.all():
            end = SETTLED
        t = t_end
    for a in range(n_dice):  # dice that stopped early stay where they are
        _record_die(records, g, a, clock[a], n_rec, x, q)
    _put(dice.x[g], x)
    _put(dice.u[g], u)
    _put(dice.ang[g], ang)
    _put(dice.q[g], q)
    if rotation:
        _put(dice.w[g], w)
    for a in range(n_dice):
        out.contacts[g, a] = touching[a]
        out.touching[g, a] = die_touch[a]
    out.status[g] = end
    out.unstable[g] = end == NONFINITE
    out.rest_time[g] = rest_at.max() * dt
    out.steps[g] = clock.max()
    out.overlap[g] = overlap
    out.meet_dice[g, 0], out.meet_dice[g, 1] = first_a, first_b
    out.energy_rise[g] = max(out.energy_rise[g], relative_rise(rise, 0.0, e_tol))


@njit(cache=True)
def _gather(c: int, t: int, label: np.ndarray, asleep: np.ndarray, energy: np.ndarray,
            stored: np.ndarray, clock: np.ndarray, quiet_of: np.ndarray, moved_of: np.ndarray,
            members: np.ndarray, records: GroupRecords, g: int, x: np.ndarray,
            q: np.ndarray) -> tuple:
    """Island ``c``'s dice into ``members``, woken at step ``t`` unless all asleep.

    Returns their count (0: none awake), their energy (as checked), the other dice's (as
    checked, and tangential), and the island's quiet steps and last move (its least quiet
    die's).
    """
    n_m, sleeping, own, others, others_t = 0, True, 0.0, 0.0, 0.0
    for a in range(label.shape[0]):
        if label[a] == c:
            members[n_m] = a
            n_m += 1
            sleeping = sleeping and asleep[a]
            own += energy[a]
        else:
            others += energy[a]
            others_t += stored[a]
    if sleeping:
        return 0, own, others, others_t, 0, 1
    quiet, moved = quiet_of[members[0]], moved_of[members[0]]
    for i in range(n_m):
        a = members[i]
        if asleep[a]:  # woken: it kept its place
            _record_die(records, g, a, clock[a], t // records.stride, x, q)
            asleep[a], clock[a], quiet_of[a] = False, t, 0
        if quiet_of[a] < quiet:
            quiet, moved = quiet_of[a], moved_of[a]
    return n_m, own, others, others_t, quiet, moved


@njit(cache=True, forceinline=True, _nrt=False)
def pair_depths(members: np.ndarray, n_m: int, x: np.ndarray, q: np.ndarray,
                vertices: np.ndarray, n_vertices: np.ndarray, r_max: np.ndarray, world: np.ndarray,
                placed: np.ndarray, axes: np.ndarray, directions: np.ndarray,
                separating: np.ndarray, depths: np.ndarray, gaps2: np.ndarray,
                normals: np.ndarray) -> bool:
    """Each pair's overlap ``depths`` (N, N; < 0: at least that far apart) and its ``normals``.

    Over the pairs of the ``n_m`` dice ``members`` (ascending).

    Pairs whose bounding spheres meet by :func:`least_overlap` (their dice placed in ``world``,
    ``placed``; ``gaps2`` -1), the others' depth ``-inf`` and their centres' squared distance in
    ``gaps2`` (the gap for :func:`out_of_reach`, taken only as needed). Returns whether every
    pair's spheres are apart.
    """
    for i in range(n_m):
        placed[members[i]] = False
    apart = True
    for i in range(n_m):
        a = members[i]
        for j in range(i + 1, n_m):
            b = members[j]
            d0, d1, d2 = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2]
            reach = r_max[a] + r_max[b]
            distance2 = d0 * d0 + d1 * d1 + d2 * d2
            if distance2 >= reach * reach:
                depths[a, b], gaps2[a, b] = -np.inf, distance2
                continue
            apart, gaps2[a, b] = False, -1.0
            for c in (a, b):
                if not placed[c]:
                    _place(world, c, vertices, n_vertices[c], x, q)
                    placed[c] = True
            depths[a, b], n, separating[a, b] = least_overlap(a, b, world, x, q, axes, directions,
                                                             separating[a, b])
            normals[a, b, 0], normals[a, b, 1], normals[a, b, 2] = n
    return apart


@njit(cache=True, forceinline=True, _nrt=False)
def _speed(a: int, u: np.ndarray, w: np.ndarray, r_max: np.ndarray, speed: np.ndarray) -> float:
    """Die ``a``'s speed bound, ``|u| + r_max |w|``, kept in ``speed`` (NaN: not yet taken)."""
    if math.isnan(speed[a]):
        speed[a] = math.sqrt(u[a, 0] ** 2 + u[a, 1] ** 2 + u[a, 2] ** 2) + r_max[a] * math.sqrt(
            w[a, 0] ** 2 + w[a, 1] ** 2 + w[a, 2] ** 2)
    return speed[a]


@njit(cache=True, forceinline=True, _nrt=False)
def out_of_reach(members: np.ndarray, n_m: int, depths: np.ndarray, gaps2: np.ndarray,
                 r_max: np.ndarray, u: np.ndarray, w: np.ndarray, speed: np.ndarray,
                 h: float) -> bool:
    """Whether no two of the ``n_m`` dice ``members`` can meet within a time ``h``.

    Each pair's gap, ``-depths`` or its spheres' (``gaps2``, :func:`pair_depths`), must exceed
    twice what the dice may close by at their speed (:func:`_speed`): a plane's force changes
    a velocity over many steps, not within a few.
    """
    for i in range(n_m):
        a = members[i]
        for j in range(i + 1, n_m):
            b = members[j]
            depth = depths[a, b]
            if gaps2[a, b] >= 0.0:
                depth = r_max[a] + r_max[b] - math.sqrt(gaps2[a, b])
            if not -depth > 2.0 * h * (_speed(a, u, w, r_max, speed)
                                       + _speed(b, u, w, r_max, speed)):
                return False
    return True


@njit(cache=True, forceinline=True, _nrt=False)
def _take(a: int, q: np.ndarray, inv_inertia: np.ndarray, inv_iso: np.ndarray, qa: np.ndarray,
          inv_a: np.ndarray) -> None:
    """Die ``a``'s rotation into ``qa``, its inertia into ``inv_a`` unless isotropic (unread).

    As the single die's kernel takes them: a view of ``q[a]`` costs a reference count.
    """
    for r in range(3):
        for c in range(3):
            qa[r, c] = q[a, r, c]
    if not inv_iso[a] > 0.0:  # angular_velocity reads it
        for r in range(3):
            for c in range(3):
                inv_a[r, c] = inv_inertia[a, r, c]


@njit(cache=True, forceinline=True, _nrt=False)
def _rescale(a: int, v: np.ndarray, before: np.ndarray, ratio: float) -> None:
    """``before[a]`` moved so that ``v[a] - before[a]``, die ``a``'s last change, is ``ratio`` x."""
    for k in range(3):
        before[a, k] = v[a, k] - ratio * (v[a, k] - before[a, k])


@njit(cache=True, forceinline=True, _nrt=False)
def _place(world: np.ndarray, a: int, vertices: np.ndarray, count: int, x: np.ndarray,
           q: np.ndarray) -> None:
    """Die ``a``'s corners in the world, ``world[a]``: ``x[a] + q[a] v`` (as die_on_planes)."""
    for k in range(count):
        b0, b1, b2 = vertices[a, k, 0], vertices[a, k, 1], vertices[a, k, 2]
        for r in range(3):
            world[a, k, r] = x[a, r] + (q[a, r, 0] * b0 + q[a, r, 1] * b1 + q[a, r, 2] * b2)
    for k in range(count, world.shape[1]):
        world[a, k, 0], world[a, k, 1], world[a, k, 2] = world[a, 0, 0], world[a, 0, 1], \
            world[a, 0, 2]


@njit(cache=True, _nrt=False)
def _group_jump(members: np.ndarray, n_m: int, planes: np.ndarray, lowest: np.ndarray,
                speed: np.ndarray, x: np.ndarray, u: np.ndarray, ang: np.ndarray,
                force: np.ndarray, bodies: Bodies, rotation: bool, dt: float, limit: int) -> int:
    """Flight steps the ``n_m`` dice ``members`` take at once (at least 1), as :func:`flight_jump`.

    Every pair stays out of reach (:func:`out_of_reach`, ``speed`` as :func:`_speed`) over the
    steps, as stepping would find it: under gravity alone a pair's distance shrinks by
    ``dt |u_a - u_b|`` a step, and the reach grows with the speeds.
    """
    jump = limit
    for i in range(n_m):
        a = members[i]
        m = bodies.mass[a]
        spin = 0.0
        if rotation:
            spin = math.sqrt(ang[a, 0] ** 2 + ang[a, 1] ** 2 + ang[a, 2] ** 2) \
                * bodies.inv_i_min[a]
        dt_m = dt / m
        jump = min(jump, flight_jump(planes, lowest, a, (u[a, 0], u[a, 1], u[a, 2]), spin,
                                     bodies.r_max[a], (force[a, 0] * dt_m, force[a, 1] * dt_m,
                                                       force[a, 2] * dt_m), dt, limit))
        for j in range(i + 1, n_m):
            b = members[j]
            gap = math.sqrt((x[a, 0] - x[b, 0]) ** 2 + (x[a, 1] - x[b, 1]) ** 2
                            + (x[a, 2] - x[b, 2]) ** 2) - bodies.r_max[a] - bodies.r_max[b] \
                - 2.0 * dt * (speed[a] + speed[b])
            kick = dt_m * math.sqrt(force[a, 0] ** 2 + force[a, 1] ** 2 + force[a, 2] ** 2) \
                + dt / bodies.mass[b] * math.sqrt(force[b, 0] ** 2 + force[b, 1] ** 2
                                                  + force[b, 2] ** 2)
            closing = math.sqrt((u[a, 0] - u[b, 0]) ** 2 + (u[a, 1] - u[b, 1]) ** 2
                                + (u[a, 2] - u[b, 2]) ** 2)
            jump = min(jump, max(1, free_steps(gap, -closing - 2.0 * kick, 0.0, 0.0, 0.0, dt,
                                               limit) - 1))  # all but the last free step
    return jump


@njit(cache=True)
def _decided(bodies: Bodies, q: np.ndarray, energy: float, floor_total: float, up: tuple) -> bool:
    """Whether no die can reach its lock: ``energy`` less the other dice's floors is below it."""
    for a in range(q.shape[0]):
        most = energy - (floor_total - bodies.floor[a])
        lock = bodies.lock[a]
        if most >= lock.max():
            return False
        read = face_read(q[a], bodies.faces[a, :bodies.n_faces[a]], bodies.reads_down[a],
                         up[0], up[1], up[2])
        if most >= lock[read]:
            return False
    return True


@njit(cache=True)
def _meeting(out: GroupOutcome, g: int, end: int, done: int, members: np.ndarray, n_m: int,
             u: np.ndarray, w: np.ndarray) -> None:
    """Store the first die–die contact's start (``end`` 0) or end (1), after ``done`` steps.

    The velocities of the ``n_m`` dice ``members``, its island's.
    """
    out.meet_steps[g, end] = done
    for i in range(n_m):
        a = members[i]
        for k in range(3):
            out.meet[g, end, a, k] = u[a, k]
            out.meet[g, end, a, 3 + k] = w[a, k]


@njit(cache=True)
def _part(out: GroupOutcome, g: int, t: int, label: np.ndarray, met: np.ndarray, first_a: int,
          first_b: int, parted: bool, members: np.ndarray, u: np.ndarray, w: np.ndarray) -> bool:
    """Part the pairs that touched at their last step and now lie in different islands.

    As the step that finds a pair apart does: its contact ends (a later touch starts afresh,
    with new stick-slip anchors) and, for the first meeting's pair, its end is stored after
    ``t`` steps with the dice of both islands. Returns whether the first meeting has ended.
    """
    n_dice = label.shape[0]
    for a in range(n_dice):
        for b in range(a + 1, n_dice):
            if met[a, b] and label[a] != label[b]:
                met[a, b] = False
                if a == first_a and b == first_b and not parted:
                    parted, n_m = True, 0
                    for c in range(n_dice):
                        if label[c] == label[a] or label[c] == label[b]:
                            members[n_m] = c
                            n_m += 1
                    _meeting(out, g, 1, t, members, n_m, u, w)
    return parted


@njit(cache=True)
def _forget_meeting(out: GroupOutcome, g: int) -> None:
    """Clear a first meeting found to be later than another island's."""
    out.meet_steps[g, 1] = -1
    for end in range(2):
        for a in range(out.meet.shape[2]):
            for k in range(6):
                out.meet[g, end, a, k] = 0.0


@njit(cache=True)
def _record(records: GroupRecords, j: int, g: int, a: int, x: np.ndarray, q: np.ndarray) -> None:
    """Store record ``j`` of die ``a``: its centre and orientation after a step."""
    for k in range(3):
        records.x[g, j, a, k] = x[a, k]
    if records.orientation.shape[1] > 0:
        for r in range(3):
            for k in range(3):
                records.orientation[g, j, a, r, k] = q[a, r, k]


@njit(cache=True)
def _record_die(records: GroupRecords, g: int, a: int, clock: int, until: int, x: np.ndarray,
                q: np.ndarray) -> None:
    """Die ``a``, still since step ``clock``, in its records after it, up to record ``until``."""
    for j in range(clock // records.stride, min(until, records.x.shape[1])):
        _record(records, j, g, a, x, q)


@njit(cache=True, forceinline=True, _nrt=False)
def _airborne(members: np.ndarray, n_m: int, touching: np.ndarray) -> bool:
    """Whether none of the ``n_m`` dice ``members`` touches a plane."""
    for i in range(n_m):
        if touching[members[i]] > 0:
            return False
    return True


@njit(cache=True)
def islands(x: np.ndarray, q: np.ndarray, energy: np.ndarray, stored: np.ndarray,
            bodies: Bodies, hulls: Hulls, world: np.ndarray, separating: np.ndarray,
            gaps: np.ndarray, label: np.ndarray, pool: np.ndarray, least: float) -> float:
    """Each die's island in ``label`` (its least die), and the time (s) no two islands meet in.

    A die's centre is no faster than ``sqrt(2 E / m)`` and its corners than
    ``sqrt(2 E (1/m + r_max^2 / I_min))`` (Cauchy-Schwarz), ``E`` its island's energy
    (``energy`` and ``stored``, each die's) above its dice's least (``Bodies.low``), times
    :data:`SPEED_MARGIN`: an island that touches no other gains no energy. Two dice close the
    gap between their bounding spheres at most at their centres' speeds and the gap along a
    separating axis (:func:`least_overlap`, for dice whose spheres meet; kept in ``gaps``) at
    most at their corners'. Dice that may meet within ``least`` share an island.
    """
    n_dice, r_max = x.shape[0], bodies.r_max
    for a in range(n_dice):
        label[a] = a
        for b in range(a + 1, n_dice):
            gaps[a, b] = 0.0
            if (x[a, 0] - x[b, 0]) ** 2 + (x[a, 1] - x[b, 1]) ** 2 + (x[a, 2] - x[b, 2]) ** 2 \
                    < (r_max[a] + r_max[b]) ** 2:
                for c in (a, b):
                    _place(world, c, bodies.vertices, bodies.n_vertices[c], x, q)
                overlap, _, separating[a, b] = least_overlap(
                    a, b, world, x, q, hulls.axes, hulls.directions, separating[a, b])
                gaps[a, b] = max(0.0, -overlap)
    merged = True
    while merged:
        merged = False
        for a in range(n_dice):
            pool[a] = 0.0
        for a in range(n_dice):
            pool[label[a]] += max(0.0, energy[a] + stored[a] - bodies.low[a])
        for a in range(n_dice):
            for b in range(a + 1, n_dice):
                if label[a] != label[b] and _meet_time(a, b, x, gaps, pool, label,
                                                       bodies) < least:
                    gone, kept = max(label[a], label[b]), min(label[a], label[b])
                    for c in range(n_dice):
                        if label[c] == gone:
                            label[c] = kept
                    merged = True
    window = np.inf
    for a in range(n_dice):
        for b in range(a + 1, n_dice):
            if label[a] != label[b]:
                window = min(window, _meet_time(a, b, x, gaps, pool, label, bodies))
    return window


@njit(cache=True, forceinline=True, _nrt=False)
def _meet_time(a: int, b: int, x: np.ndarray, gaps: np.ndarray, pool: np.ndarray,
               label: np.ndarray, bodies: Bodies) -> float:
    """The least time (s) dice ``a`` and ``b`` take to meet (:func:`islands`)."""
    mass, r_max, inv_i = bodies.mass, bodies.r_max, bodies.inv_i_min
    e_a, e_b = 2.0 * pool[label[a]], 2.0 * pool[label[b]]
    sphere = math.sqrt((x[a, 0] - x[b, 0]) ** 2 + (x[a, 1] - x[b, 1]) ** 2
                       + (x[a, 2] - x[b, 2]) ** 2) - r_max[a] - r_max[b]
    time = 0.0
    if sphere > 0.0:
        closing = SPEED_MARGIN * (math.sqrt(e_a / mass[a]) + math.sqrt(e_b / mass[b]))
        time = sphere / closing if closing > 0.0 else np.inf
    elif gaps[a, b] > 0.0:
        closing = SPEED_MARGIN * (math.sqrt(e_a * (1.0 / mass[a] + r_max[a] ** 2 * inv_i[a]))
                                  + math.sqrt(e_b * (1.0 / mass[b] + r_max[b] ** 2 * inv_i[b])))
        time = gaps[a, b] / closing if closing > 0.0 else np.inf
    return time


@njit(cache=True)
def _put(target: np.ndarray, values: np.ndarray) -> None:
    """``target[...] = values`` element by element (numba's shape check is slow to compile)."""
    for index in np.ndindex(values.shape):
        target[index] = values[index]


@njit(cache=True, parallel=True, nogil=True)
def simulate_groups(dice: GroupDice, bodies: Bodies, hulls: Hulls, pair: Pair,
                    contact: Contact, options: Options, stops: GroupStops,
                    records: GroupRecords, out: GroupOutcome) -> None:
    """Advance G throws of N dice in place, in parallel over throws (the GIL released)."""
    for g in prange(dice.x.shape[0]):  # prange's index is unsigned: one signature for both
        advance_group(np.int64(g), dice, bodies, hulls, pair, contact, options, stops, records,
                      out)


@njit(cache=True, nogil=True)
def simulate_groups_serial(dice: GroupDice, bodies: Bodies, hulls: Hulls, pair: Pair,
                           contact: Contact, options: Options, stops: GroupStops,
                           records: GroupRecords, out: GroupOutcome) -> None:
    """:func:`simulate_groups` on the calling thread, with the same results."""
    for g in range(dice.x.shape[0]):
        advance_group(g, dice, bodies, hulls, pair, contact, options, stops, records, out)

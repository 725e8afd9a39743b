"""The compiled single-die integrator: the paper's step, written once, run over a batch of dice.

The physics is ``docs/model.md``'s, the speed ``docs/performance.md``'s. :func:`advance` steps
one die in its caller's scratch arrays (:func:`simulate_one` on the CPU,
:mod:`dice_env.physics.cuda_kernel` on a GPU). The groups are built by
:func:`dice_env.simulation.simulate.pack_scene` and ``pack_run``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

# Per-die end status.
RUNNING, SETTLED, NONFINITE, DECIDED, ABORTED = 0, 1, 2, 3, 4
ABORT_EVERY = 4096  # loop passes between looks at the abort flag (a power of two)
SERIES = 2.44140625e-4  # (1/64 rad)^2: below this squared turn, R's coefficients from series
UP = (0.0, 0.0, 1.0)  # faces are read against gravity


class Body(NamedTuple):
    """The die, body frame about its centre of mass.

    ``vertices`` (N, 3); ``inv_iso``: ``1/I`` for an isotropic die, else 0; ``inv_i_min``: the
    inverse of the smallest principal moment; ``r_max``: the farthest vertex's distance; ``faces``
    (F, 3): outward unit normals, in ``Stops.lock``'s order.
    """

    vertices: np.ndarray
    mass: float
    inv_inertia: np.ndarray
    inv_iso: float
    inv_i_min: float
    r_max: float
    faces: np.ndarray
    reads_down: bool


# Columns of Contact.planes: unit normal (3), offset, S, D, mu, stick-slip spring and damper.
NX, NY, NZ, OFFSET, STIFF, DAMP, MU, KT, CT = range(9)
# Contact.law: the spring-dashpot on the vertices below a plane only, or the listing's on all.
GATED, PAPER = 0, 1


class Contact(NamedTuple):
    """The planes the die stays on, ``n . X >= offset``, and the contact laws.

    ``planes`` (P, 9): the columns ``NX`` ... ``CT`` per plane, plane 0 the floor; ``law``:
    ``GATED`` or ``PAPER``; ``stick``: stick-slip friction, else ``-mu fn Ut/(|Ut| + vmin)``.
    """

    planes: np.ndarray
    law: int
    stick: bool
    vmin: float


class Options(NamedTuple):
    """The integration: ``gravity`` (-z), ``dt``, ``rotation``, ``flight`` jumps, ``midpoint``."""

    gravity: float
    dt: float
    rotation: bool
    flight: bool
    midpoint: bool


class Stops(NamedTuple):
    """When a die ends: after ``n_steps``; with ``at_rest``, quiet for ``hold_steps``.

    Quiet: three contacts, every vertex slower than ``v_rest``; a quiet step below ``rest_energy +
    rest_excess`` ends it too; so does an energy below ``lock`` (F,) of the face read (``-inf``:
    never). ``energy_scale``: added to the start's energy to measure a gain in.
    """

    n_steps: int
    at_rest: bool
    v_rest: float
    hold_steps: int
    rest_energy: float
    rest_excess: float
    lock: np.ndarray
    energy_scale: float


class Records(NamedTuple):
    """Every ``stride`` steps: ``x`` (B, n, 3), ``energy``, ``orientation``, ``nodes`` (or none)."""

    stride: int
    x: np.ndarray
    energy: np.ndarray
    orientation: np.ndarray
    nodes: np.ndarray


class Dice(NamedTuple):
    """B dice in place: the five arrays of :class:`dice_env.simulation.simulate.State`, in order."""

    x: np.ndarray
    u: np.ndarray
    ang: np.ndarray
    q: np.ndarray
    w: np.ndarray


class Outcome(NamedTuple):
    """What each die's run gives (arrays (B,), as :class:`dice_env.Result`'s), and the abort flag.

    ``abort`` (1,): set non-zero from another thread, every running die ends ``ABORTED`` within
    ``ABORT_EVERY`` loop passes.
    """

    status: np.ndarray
    unstable: np.ndarray
    rest_time: np.ndarray
    impacts: np.ndarray
    max_pen: np.ndarray
    energy_rise: np.ndarray
    steps: np.ndarray
    abort: np.ndarray


class PlaneContacts(NamedTuple):
    """The vertices against the planes, kept from step to step (:func:`die_on_planes`).

    Per vertex row (V: a group's dice one after another) and plane (P): ``offsets`` (V, 3) from
    the die's centre, ``heights`` (P, V) entering the last step, ``anchors`` (P, V, 3) and
    ``tied`` (P, V) the stick-slip ties; ``lowest`` (D, P) each die's lowest height on each plane.
    """

    offsets: np.ndarray
    heights: np.ndarray
    anchors: np.ndarray
    tied: np.ndarray
    lowest: np.ndarray


class Scratch(NamedTuple):
    """One die's scratch in :func:`advance`: orientation ``qi``, ``qj`` for records, contacts."""

    qi: np.ndarray
    qj: np.ndarray
    contacts: PlaneContacts


@njit(cache=True, inline="always")
def rotation_series(t2: float) -> tuple[float, float]:
    """``sin(t)/t``, ``(1 - cos t)/t^2`` for ``t^2 < SERIES``: series to 1e-25, no call."""
    a = 1.0 - t2 * (1.0 / 6.0 - t2 * (1.0 / 120.0 - t2 * (1.0 / 5040.0 - t2 / 362880.0)))
    b = 0.5 - t2 * (1.0 / 24.0 - t2 * (1.0 / 720.0 - t2 * (1.0 / 40320.0 - t2 / 3628800.0)))
    return a, b


@njit(cache=True, inline="always")
def rodrigues(v0: float, v1: float, v2: float, t2: float, a: float, b: float) -> tuple:
    """The entries of ``R = (1 - b t^2) E + a [v]x + b v v^T``, row by row."""
    d = 1.0 - b * t2
    r00, r11, r22 = d + b * v0 * v0, d + b * v1 * v1, d + b * v2 * v2
    r01, r10 = b * v0 * v1 - a * v2, b * v0 * v1 + a * v2
    r02, r20 = b * v0 * v2 + a * v1, b * v0 * v2 - a * v1
    r12, r21 = b * v1 * v2 - a * v0, b * v1 * v2 + a * v0
    return r00, r01, r02, r10, r11, r12, r20, r21, r22


@njit(cache=True, inline="always")
def rotate(q: np.ndarray, w0: float, w1: float, w2: float, dt: float) -> None:
    """Turn ``q`` (3x3) in place: ``q = R(w dt) q`` (:func:`rodrigues`), ``R = E`` at ``w = 0``."""
    v0, v1, v2 = w0 * dt, w1 * dt, w2 * dt
    t2 = v0 * v0 + v1 * v1 + v2 * v2
    if t2 == 0.0:
        return
    if t2 < SERIES:
        a, b = rotation_series(t2)
    else:
        t = math.sqrt(t2)
        a = math.sin(t) / t
        half = math.sin(0.5 * t) / t
        b = 2.0 * half * half
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = rodrigues(v0, v1, v2, t2, a, b)
    for j in range(3):
        q0, q1, q2 = q[0, j], q[1, j], q[2, j]
        q[0, j] = r00 * q0 + r01 * q1 + r02 * q2
        q[1, j] = r10 * q0 + r11 * q1 + r12 * q2
        q[2, j] = r20 * q0 + r21 * q1 + r22 * q2


@njit(cache=True, inline="always")
def angular_velocity(q: np.ndarray, inv_body: np.ndarray, inv_iso: float, l0: float, l1: float,
                     l2: float) -> tuple[float, float, float]:
    """``I_world^-1 L`` with ``I_world = Q I_body Q^T``; ``L * inv_iso`` when ``inv_iso > 0``."""
    if inv_iso > 0.0:
        return l0 * inv_iso, l1 * inv_iso, l2 * inv_iso
    b0 = q[0, 0] * l0 + q[1, 0] * l1 + q[2, 0] * l2
    b1 = q[0, 1] * l0 + q[1, 1] * l1 + q[2, 1] * l2
    b2 = q[0, 2] * l0 + q[1, 2] * l1 + q[2, 2] * l2
    c0 = inv_body[0, 0] * b0 + inv_body[0, 1] * b1 + inv_body[0, 2] * b2
    c1 = inv_body[1, 0] * b0 + inv_body[1, 1] * b1 + inv_body[1, 2] * b2
    c2 = inv_body[2, 0] * b0 + inv_body[2, 1] * b1 + inv_body[2, 2] * b2
    return (
        q[0, 0] * c0 + q[0, 1] * c1 + q[0, 2] * c2,
        q[1, 0] * c0 + q[1, 1] * c1 + q[1, 2] * c2,
        q[2, 0] * c0 + q[2, 1] * c1 + q[2, 2] * c2,
    )


@njit(cache=True, forceinline=True, _nrt=False)
def body_frame(q: tuple, v0: float, v1: float, v2: float) -> tuple[float, float, float]:
    """``Q^T v``: the world direction ``v`` in the body frame (``q`` nine numbers, row by row)."""
    return (q[0] * v0 + q[3] * v1 + q[6] * v2, q[1] * v0 + q[4] * v1 + q[7] * v2,
            q[2] * v0 + q[5] * v1 + q[8] * v2)


@njit(cache=True, forceinline=True, _nrt=False)
def face_up(faces: np.ndarray | tuple, reads_down: bool, up: tuple) -> int:
    """Index of the face most along ``up`` (body frame; against it if ``reads_down``).

    ``faces``: F outward normals, (F, 3) or a tuple of triples; the first of equals.
    """
    sign = -1.0 if reads_down else 1.0
    best, index = -np.inf, 0
    for f in range(len(faces)):
        face = faces[f]
        value = sign * (face[0] * up[0] + face[1] * up[1] + face[2] * up[2])
        if value > best:
            best, index = value, f
    return index


@njit(cache=True)
def face_read(q: np.ndarray, faces: np.ndarray, reads_down: bool, n0: float, n1: float,
              n2: float) -> int:
    """Index of the face read (:func:`face_up`) at orientation ``q``, ``n`` the world's up."""
    return face_up(faces, reads_down, body_frame(
        (q[0, 0], q[0, 1], q[0, 2], q[1, 0], q[1, 1], q[1, 2], q[2, 0], q[2, 1], q[2, 2]),
        n0, n1, n2))


@njit(cache=True, inline="always")
def free_steps(lowest: float, un: float, spin: float, r_max: float, dvn: float, dt: float,
               limit: int) -> int:
    """Number of steps from now (1 to ``limit``) surely free of contact with one plane.

    ``lowest``: the lowest vertex's height; ``un``, ``dvn``: the centre's normal velocity and its
    change per step (``docs/performance.md``, "Analytic free flight").
    """
    b = dt * (un - spin * r_max)
    a = -0.5 * dt * dvn  # >= 0 when gravity pulls toward the plane
    if a <= 0.0:
        if b >= 0.0:
            return limit
        last = lowest / -b
    else:
        # largest j with lowest + (b - a) j - a j^2 >= 0
        p = b - a
        last = (p + math.sqrt(p * p + 4.0 * a * lowest)) / (2.0 * a)
    if not last < limit:  # also catches inf and NaN
        return limit
    return max(1, int(last) + 1)


@njit(cache=True, forceinline=True)
def torque_free(q: np.ndarray, inv_body: np.ndarray, inv_iso: float, l0: float, l1: float,
                l2: float, dt: float, n: int) -> tuple[float, float, float]:
    """``n`` rotation steps of ``q`` at constant ``L`` (one if isotropic); the last ``w``."""
    w0, w1, w2 = angular_velocity(q, inv_body, inv_iso, l0, l1, l2)
    turns, h = (1, n * dt) if inv_iso > 0.0 else (n, dt)
    for k in range(turns):
        if k > 0:
            w0, w1, w2 = angular_velocity(q, inv_body, inv_iso, l0, l1, l2)
        rotate(q, w0, w1, w2, h)
    return w0, w1, w2


@njit(cache=True, forceinline=True)
def vertex_on_plane(plane: tuple, stick: bool, vmin: float, height: float, before: float,
                    position: tuple, velocity: tuple, middle: tuple, midpoint: bool, dt: float,
                    dt_m: float, anchor: tuple, tied: bool) -> tuple:
    """The force of a plane on one vertex, and the step's books.

    ``before``: the height entering the last step; ``middle``: the velocity mid-kick (with
    ``midpoint``). Returns the force (3), the normal and tangential springs' energy, whether below
    the plane, the sink, the approach speed, and the tie point (3) and tie after the step.
    """
    n0, n1, n2, _, stiff, damp, mu, _, _ = plane
    uk0, uk1, uk2 = velocity
    dg = max(0.0, -height)
    un = n0 * uk0 + n1 * uk1 + n2 * uk2
    below = height < 0.0
    spring = 0.5 * stiff * dg * dg if below else 0.0
    approach = -un
    fn = stiff * dg
    if midpoint:
        uk0, uk1, uk2 = middle
        un = n0 * uk0 + n1 * uk1 + n2 * uk2
    friction_limit = fn  # without the onset weight (docs/model.md, "Midpoint step")
    if damp > 0.0:
        friction_limit -= damp * un
        if midpoint and before > 0.0 and height < 0.0:
            fn -= (0.5 - height / (before - height)) * damp * un
        else:
            fn = friction_limit
    if fn <= 0.0:
        return 0.0, 0.0, 0.0, spring, 0.0, below, dg, approach, anchor, False
    fk0, fk1, fk2 = fn * n0, fn * n1, fn * n2
    stored = 0.0
    if mu > 0.0:
        cap = mu * max(friction_limit, 0.0)  # Coulomb's limit mu fn
        ut0, ut1, ut2 = uk0 - un * n0, uk1 - un * n1, uk2 - un * n2
        if stick:
            ft0, ft1, ft2, stored, anchor = stick_slip(
                plane, height, before, position, (ut0, ut1, ut2), cap, dt, dt_m, anchor, tied)
            tied = True
        else:
            scale = cap / (math.sqrt(ut0 * ut0 + ut1 * ut1 + ut2 * ut2) + vmin)
            ft0, ft1, ft2 = -scale * ut0, -scale * ut1, -scale * ut2
        fk0 += ft0
        fk1 += ft1
        fk2 += ft2
    return fk0, fk1, fk2, spring, stored, below, dg, approach, anchor, tied


@njit(cache=True, inline="always")
def stick_slip(plane: tuple, height: float, before: float, position: tuple, ut: tuple,
                cap: float, dt: float, dt_m: float, anchor: tuple, tied: bool) -> tuple:
    """Stick-slip friction (``docs/model.md``): tangential force (3), energy, tie point after."""
    n0, n1, n2, _, _, _, _, kt, ct = plane
    p0, p1, p2 = position
    ut0, ut1, ut2 = ut
    a0, a1, a2 = anchor
    if not tied:
        crossed = before > 0.0 and height < 0.0  # (the paper's law also ties vertices above)
        back = dt * height / (before - height) if crossed else 0.0
        a0, a1, a2 = p0 + back * ut0, p1 + back * ut1, p2 + back * ut2
    e0, e1, e2 = p0 - a0, p1 - a1, p2 - a2
    en = n0 * e0 + n1 * e1 + n2 * e2
    e0, e1, e2 = e0 - en * n0, e1 - en * n1, e2 - en * n2
    ft0, ft1, ft2 = -kt * e0 - ct * ut0, -kt * e1 - ct * ut1, -kt * e2 - ct * ut2
    size = math.sqrt(ft0 * ft0 + ft1 * ft1 + ft2 * ft2)
    if size > cap:
        # slip: against the slip velocity, or along the spring's pull while slower than a step's
        # friction kick on a quarter of the die (its direction then means nothing)
        speed = math.sqrt(ut0 * ut0 + ut1 * ut1 + ut2 * ut2)
        if speed > 4.0 * cap * dt_m:
            ratio = -cap / speed
            ft0, ft1, ft2 = ratio * ut0, ratio * ut1, ratio * ut2
        else:
            ratio = cap / size
            ft0, ft1, ft2 = ratio * ft0, ratio * ft1, ratio * ft2
        e0, e1, e2 = -ft0 / kt, -ft1 / kt, -ft2 / kt
        a0, a1, a2 = p0 - e0, p1 - e1, p2 - e2
    return ft0, ft1, ft2, 0.5 * kt * (e0 * e0 + e1 * e1 + e2 * e2), (a0, a1, a2)


@njit(cache=True, forceinline=True, _nrt=False)
def die_on_planes(die: int, first: int, count: int, vertices: np.ndarray, planes: np.ndarray,
                  law: tuple, contacts: PlaneContacts, q: tuple, motion: tuple,
                  near_rest: bool) -> tuple:
    """One die's step on the planes: their forces and torques on it, and the step's books.

    The die's vertices: rows ``first`` to ``first + count`` of ``vertices`` and ``contacts``;
    ``q``: nine numbers row by row; ``motion``: ``(x, u, w, cu, cw)``, ``cu``, ``cw`` at the
    midpoint forces' time. Returns the force (3, weight included), the torque (3), the normal and
    tangential springs' energy, the vertices below a plane, their fastest approach, the largest
    squared vertex speed (``near_rest`` only) and the deepest sink.
    """
    contact_law, stick, vmin, midpoint, rotation, dt, dt_m, weight = law
    q00, q01, q02, q10, q11, q12, q20, q21, q22 = q
    (x0, x1, x2), (u0, u1, u2), (w0, w1, w2), (cu0, cu1, cu2), (cw0, cw1, cw2) = motion
    offsets, heights, anchors, tied = contacts.offsets, contacts.heights, contacts.anchors, \
        contacts.tied
    f0, f1, f2 = 0.0, 0.0, -weight
    t0, t1, t2 = 0.0, 0.0, 0.0
    spring, spring_t, touching, approach, fastest, pen = 0.0, 0.0, 0, 0.0, 0.0, 0.0
    for k in range(first, first + count):
        b0, b1, b2 = vertices[k, 0], vertices[k, 1], vertices[k, 2]
        rk0 = q00 * b0 + q01 * b1 + q02 * b2
        rk1 = q10 * b0 + q11 * b1 + q12 * b2
        rk2 = q20 * b0 + q21 * b1 + q22 * b2
        offsets[k, 0], offsets[k, 1], offsets[k, 2] = rk0, rk1, rk2
        if near_rest:
            v0, v1, v2 = u0 + w1 * rk2 - w2 * rk1, u1 + w2 * rk0 - w0 * rk2, \
                u2 + w0 * rk1 - w1 * rk0
            fastest = max(fastest, v0 * v0 + v1 * v1 + v2 * v2)
    for p in range(planes.shape[0]):
        plane = (planes[p, NX], planes[p, NY], planes[p, NZ], planes[p, OFFSET],
                 planes[p, STIFF], planes[p, DAMP], planes[p, MU], planes[p, KT], planes[p, CT])
        pn0, pn1, pn2, offset = plane[0], plane[1], plane[2], plane[3]
        low = np.inf
        for k in range(first, first + count):
            rk0, rk1, rk2 = offsets[k, 0], offsets[k, 1], offsets[k, 2]
            position = (x0 + rk0, x1 + rk1, x2 + rk2)
            height = pn0 * position[0] + pn1 * position[1] + pn2 * position[2] - offset
            low = min(low, height)
            before = heights[p, k]
            heights[p, k] = height
            if height >= 0.0:
                tied[p, k] = False
                if contact_law != PAPER:
                    continue
            velocity = (u0 + w1 * rk2 - w2 * rk1, u1 + w2 * rk0 - w0 * rk2,
                        u2 + w0 * rk1 - w1 * rk0)
            middle = velocity
            if midpoint:
                middle = (cu0 + cw1 * rk2 - cw2 * rk1, cu1 + cw2 * rk0 - cw0 * rk2,
                          cu2 + cw0 * rk1 - cw1 * rk0)
            anchor, tie = (0.0, 0.0, 0.0), False  # the ties matter to stick-slip only
            if stick:
                anchor = (anchors[p, k, 0], anchors[p, k, 1], anchors[p, k, 2])
                tie = tied[p, k]
            fk0, fk1, fk2, spring_k, stored, below, dg, approach_k, anchor, tie = (
                vertex_on_plane(plane, stick, vmin, height, before, position, velocity,
                                middle, midpoint, dt, dt_m, anchor, tie))
            if stick:
                anchors[p, k, 0], anchors[p, k, 1], anchors[p, k, 2] = anchor
                tied[p, k] = tie
            if below:
                touching += 1
                spring += spring_k
                pen = max(pen, dg)
                approach = max(approach, approach_k)
            spring_t += stored
            f0 += fk0
            f1 += fk1
            f2 += fk2
            if rotation:
                t0 += rk1 * fk2 - rk2 * fk1
                t1 += rk2 * fk0 - rk0 * fk2
                t2 += rk0 * fk1 - rk1 * fk0
        contacts.lowest[die, p] = low
    return f0, f1, f2, t0, t1, t2, spring, spring_t, touching, approach, fastest, pen


@njit(cache=True, forceinline=True, _nrt=False)
def next_pass(passes: int, abort: np.ndarray) -> tuple[int, int]:
    """Pass count + 1, and ``ABORTED`` or ``RUNNING`` (``abort`` read every ``ABORT_EVERY``)."""
    passes += 1
    return passes, ABORTED if passes & (ABORT_EVERY - 1) == 0 and abort[0] != 0 else RUNNING


@njit(cache=True, forceinline=True, _nrt=False)
def rest_test(quiet_now: bool, quiet: int, hold_steps: int, proven: bool) -> tuple[int, int]:
    """Quiet steps in a row, and ``SETTLED`` (beyond ``hold_steps``, or ``proven``) or not."""
    if not quiet_now:
        return 0, RUNNING
    quiet += 1
    return quiet, SETTLED if quiet > hold_steps or proven else RUNNING


@njit(cache=True, forceinline=True, _nrt=False)
def stopped_at(end: int, step: int, quiet: int) -> tuple[int, int]:
    """The steps a loop kept (not the one a stop was found in) and the step its rest began."""
    if end == DECIDED or end == SETTLED or end == NONFINITE:
        return step - 1, step - quiet if end == SETTLED else step - 1
    return step, step


@njit(cache=True)
def decided(lock: np.ndarray, faces: np.ndarray, reads_down: bool, q: np.ndarray, up: tuple,
            energy: float) -> bool:
    """Whether ``energy`` is below the ``lock`` of the face read (call only below the largest)."""
    return energy < lock[face_read(q, faces, reads_down, up[0], up[1], up[2])]


@njit(cache=True)
def relative_rise(e_max: float, e_start: float, e_tol: float) -> float:
    """The energy gain ``e_max - e_start`` over the scale ``e_tol`` (any gain infinite at 0)."""
    rise = e_max - e_start
    if e_tol > 0.0:
        return rise / e_tol
    return np.inf if rise > 0.0 else rise


@njit(cache=True)
def simulate_one(i: int, dice: Dice, body: Body, contact: Contact, options: Options,
                 stops: Stops, records: Records, out: Outcome) -> None:
    """Advance die ``i`` in place; see :func:`simulate_batch`."""
    n_vertices, n_planes = body.vertices.shape[0], contact.planes.shape[0]
    advance(i, dice, body, contact, options, stops, records, out, Scratch(
        np.empty((3, 3)), np.empty((3, 3)), PlaneContacts(
            np.empty((n_vertices, 3)), np.empty((n_planes, n_vertices)),
            np.empty((n_planes, n_vertices, 3)), np.empty((n_planes, n_vertices), np.bool_),
            np.empty((1, n_planes)))))


@njit(cache=True)
def advance(i: int, dice: Dice, body: Body, contact: Contact, options: Options, stops: Stops,
            records: Records, out: Outcome, scratch: Scratch) -> None:
    """:func:`simulate_one` in the caller's :class:`Scratch`; allocation-free, so CUDA too."""
    qi, qj, contacts = scratch
    heights, anchors, tied, lowest = contacts.heights, contacts.anchors, contacts.tied, \
        contacts.lowest
    # taken out once: each taking costs a reference count
    vertices, planes, faces, lock = body.vertices, contact.planes, body.faces, stops.lock
    abort = out.abort
    inv_body, inv_iso, reads_down = body.inv_inertia, body.inv_iso, body.reads_down
    contact_law, stick, vmin = contact.law, contact.stick, contact.vmin
    n0, n1, n2, floor = planes[0, NX], planes[0, NY], planes[0, NZ], planes[0, OFFSET]
    up = UP
    x0, x1, x2 = dice.x[i, 0], dice.x[i, 1], dice.x[i, 2]
    u0, u1, u2 = dice.u[i, 0], dice.u[i, 1], dice.u[i, 2]
    l0, l1, l2 = dice.ang[i, 0], dice.ang[i, 1], dice.ang[i, 2]
    rotation, midpoint, dt, g = options.rotation, options.midpoint, options.dt, options.gravity
    mass = body.mass
    w0, w1, w2 = (dice.w[i, 0], dice.w[i, 1], dice.w[i, 2]) if rotation else (0.0, 0.0, 0.0)
    dt_m = dt / mass
    law = (contact_law, stick, vmin, midpoint, rotation, dt, dt_m, mass * g)
    n_steps, stride = stops.n_steps, records.stride
    for a in range(3):
        for c in range(3):
            qi[a, c] = dice.q[i, a, c]
    n_rec = records.x.shape[1]
    kinetic_rest = 0.5 * mass * stops.v_rest * stops.v_rest
    lock_max = -np.inf
    for f in range(lock.shape[0]):
        lock_max = max(lock_max, lock[f])
    e_start, e_tol, e_max = 0.0, 1.0, -np.inf
    quiet = 0
    was_in_contact = True
    end = RUNNING
    pen = out.max_pen[i]
    hits = out.impacts[i]
    step = 0
    passes = 0
    next_record = stride
    pu0, pu1, pu2 = u0, u1, u2  # velocities one step back, for the midpoint forces
    pw0, pw1, pw2 = w0, w1, w2
    n_vertices, n_planes = vertices.shape[0], planes.shape[0]
    for p in range(n_planes):
        for k in range(n_vertices):
            heights[p, k] = -1.0
            tied[p, k] = False
            anchors[p, k, 0], anchors[p, k, 1], anchors[p, k, 2] = 0.0, 0.0, 0.0
    while step < n_steps:
        passes, end = next_pass(passes, abort)
        if end == ABORTED:
            break
        step += 1
        cu, cw = (u0, u1, u2), (w0, w1, w2)
        if midpoint:
            cu, cw = ahead(cu, (pu0, pu1, pu2)), ahead(cw, (pw0, pw1, pw2))
        wl0, wl1, wl2 = angular_velocity(qi, inv_body, inv_iso, l0, l1, l2)
        kinetic = 0.5 * mass * (u0 * u0 + u1 * u1 + u2 * u2) + 0.5 * (
            l0 * wl0 + l1 * wl1 + l2 * wl2
        )
        near_rest = stops.at_rest and kinetic < kinetic_rest
        # 1.-2. the planes' forces and torques on the vertices
        (f0, f1, f2, t0, t1, t2, spring, spring_t, touching, approach, fastest,
         sink) = die_on_planes(
            0, 0, n_vertices, vertices, planes, law, contacts,
            (qi[0, 0], qi[0, 1], qi[0, 2], qi[1, 0], qi[1, 1], qi[1, 2], qi[2, 0], qi[2, 1],
             qi[2, 2]),
            ((x0, x1, x2), (u0, u1, u2), (w0, w1, w2), cu, cw), near_rest)
        pen = max(pen, sink)
        # the gain check leaves out the tangential springs, the decided-face lock counts them
        # (docs/model.md, "Friction and the step of the default scene")
        checked = kinetic + mass * g * x2 + spring
        energy = checked + spring_t
        if step == 1:
            e_start = checked
            e_tol = stops.energy_scale + kinetic + mass * g * max(
                0.0, (n0 * x0 + n1 * x1 + n2 * x2) - floor)
        else:
            e_max = max(e_max, checked)
        if touching > 0 and not was_in_contact and approach > stops.v_rest:
            hits += 1
        was_in_contact = touching > 0
        if energy < lock_max and decided(lock, faces, reads_down, qi, up, energy):
            end = DECIDED
            break
        if stops.at_rest:
            quiet, end = rest_test(
                touching >= 3 and near_rest and fastest < stops.v_rest * stops.v_rest, quiet,
                stops.hold_steps, energy - stops.rest_energy < stops.rest_excess)
            if end == SETTLED:
                break
        # 3. the kick, and in free flight how many steps it takes at once
        dv0, dv1, dv2 = f0 * dt_m, f1 * dt_m, f2 * dt_m
        jump = 1
        if options.flight and touching == 0:
            spin = math.sqrt(l0 * l0 + l1 * l1 + l2 * l2) * body.inv_i_min if rotation else 0.0
            jump = flight_jump(planes, lowest, 0, (u0, u1, u2), spin, body.r_max,
                               (dv0, dv1, dv2), dt, n_steps - step + 1)
        if jump > 1:
            if n_rec > 0:  # the records falling inside the jump (it does not depend on them)
                _record_jump(records, i, step, jump, (x0, x1, x2), (u0, u1, u2), (l0, l1, l2),
                             (dv0, dv1, dv2), qi, qj, body, options)
        # 4. the move: centre of mass, angular momentum and orientation
        finite, (x0, x1, x2), (nu0, nu1, nu2), (l0, l1, l2), (nw0, nw1, nw2) = die_move(
            (x0, x1, x2), (u0, u1, u2), (l0, l1, l2), (w0, w1, w2), (dv0, dv1, dv2),
            (t0, t1, t2), qi, inv_body, inv_iso, dt, jump, rotation)
        if not finite:
            end = NONFINITE
            break
        if midpoint:
            pu0, pu1, pu2 = nu0 - dv0, nu1 - dv1, nu2 - dv2
            pw0, pw1, pw2 = w0, w1, w2
        u0, u1, u2, w0, w1, w2 = nu0, nu1, nu2, nw0, nw1, nw2
        step += jump - 1
        if step >= next_record:  # a multiple of the stride reached or jumped over
            if step % stride == 0 and step // stride <= n_rec:
                _record(records, step // stride - 1, i, (x0, x1, x2), (u0, u1, u2),
                        (l0, l1, l2), qi, body, g)
            next_record = (step // stride + 1) * stride
    step, rest = stopped_at(end, step, quiet)
    # a die that stopped early stays where it is for the rest of the record
    for j in range(step // stride, n_rec):
        _record(records, j, i, (x0, x1, x2), (u0, u1, u2), (l0, l1, l2), qi, body, g)
    dice.x[i, 0], dice.x[i, 1], dice.x[i, 2] = x0, x1, x2
    dice.u[i, 0], dice.u[i, 1], dice.u[i, 2] = u0, u1, u2
    dice.ang[i, 0], dice.ang[i, 1], dice.ang[i, 2] = l0, l1, l2
    if rotation:
        dice.w[i, 0], dice.w[i, 1], dice.w[i, 2] = w0, w1, w2
    for a in range(3):
        for c in range(3):
            dice.q[i, a, c] = qi[a, c]
    out.status[i] = end
    out.unstable[i] = end == NONFINITE
    out.rest_time[i] = rest * dt
    out.steps[i] = step
    out.max_pen[i] = pen
    out.impacts[i] = hits
    # (e - e0) / tol is monotone in e, so its largest value is that of the largest e
    out.energy_rise[i] = max(out.energy_rise[i], relative_rise(e_max, e_start, e_tol))


@njit(cache=True, inline="always")
def euler_steps(x: tuple, u: tuple, dv: tuple, dt: float, n: int) -> tuple:
    """``(x_n, u_n)``: ``n`` steps ``u += dv; x += dt u`` in closed form (bit-exact at n = 1)."""
    x0, x1, x2 = x
    u0, u1, u2 = u
    dv0, dv1, dv2 = dv
    if n == 1:
        nu0, nu1, nu2 = u0 + dv0, u1 + dv1, u2 + dv2
        return (x0 + dt * nu0, x1 + dt * nu1, x2 + dt * nu2), (nu0, nu1, nu2)
    half = 0.5 * n * (n + 1)
    return ((x0 + dt * (n * u0 + half * dv0), x1 + dt * (n * u1 + half * dv1),
             x2 + dt * (n * u2 + half * dv2)), (u0 + n * dv0, u1 + n * dv1, u2 + n * dv2))


@njit(cache=True, forceinline=True, _nrt=False)
def die_move(x: tuple, u: tuple, ang: tuple, w: tuple, dv: tuple, torque: tuple, q: np.ndarray,
             inv_body: np.ndarray, inv_iso: float, dt: float, n: int, rotation: bool) -> tuple:
    """One die moved ``n`` steps by the kick ``dv`` and the ``torque``, ``q`` in place.

    Returns whether the moved state is finite, then its ``x``, ``u``, ``L`` and ``w``; a
    non-finite state is not moved (nor ``q``).
    """
    nx, (nu0, nu1, nu2) = euler_steps(x, u, dv, dt, n)
    nl0, nl1, nl2 = ang
    if rotation:
        nl0, nl1, nl2 = nl0 + dt * torque[0], nl1 + dt * torque[1], nl2 + dt * torque[2]
    if not math.isfinite(nu0 + nu1 + nu2 + nx[0] + nx[1] + nx[2] + nl0 + nl1 + nl2):
        return False, x, u, ang, w
    if rotation:
        w = torque_free(q, inv_body, inv_iso, nl0, nl1, nl2, dt, n)
    return True, nx, (nu0, nu1, nu2), (nl0, nl1, nl2), w


@njit(cache=True, inline="always")
def ahead(v: tuple, before: tuple) -> tuple:
    """A velocity half a step ahead, ``v + (v - before) / 2`` (the midpoint forces')."""
    return (1.5 * v[0] - 0.5 * before[0], 1.5 * v[1] - 0.5 * before[1],
            1.5 * v[2] - 0.5 * before[2])


@njit(cache=True, inline="always")
def flight_jump(planes: np.ndarray, lowest: np.ndarray, die: int, u: tuple, spin: float,
                r_max: float, dv: tuple, dt: float, limit: int) -> int:
    """Flight steps for die ``die`` to take at once (at least 1), all but the last contact-free."""
    free = limit
    for p in range(planes.shape[0]):
        n0, n1, n2 = planes[p, NX], planes[p, NY], planes[p, NZ]
        free = min(free, free_steps(lowest[die, p], n0 * u[0] + n1 * u[1] + n2 * u[2], spin,
                                    r_max, n0 * dv[0] + n1 * dv[1] + n2 * dv[2], dt, limit))
    return max(1, free - 1)


@njit(cache=True)
def _record_jump(records: Records, i: int, step: int, jump: int, x: tuple, u: tuple, ang: tuple,
                 dv: tuple, qi: np.ndarray, qj: np.ndarray, body: Body, options: Options) -> None:
    """Record the states inside a jump of ``jump`` flight steps from ``step`` (its closed form)."""
    stride, n_rec, dt = records.stride, records.x.shape[1], options.dt
    l0, l1, l2 = ang
    for s in range((step + stride - 1) // stride * stride, step + jump - 1, stride):
        if s // stride > n_rec:
            break
        j = s - step + 1
        for a in range(3):
            for c in range(3):
                qj[a, c] = qi[a, c]
        if options.rotation:
            torque_free(qj, body.inv_inertia, body.inv_iso, l0, l1, l2, dt, j)
        xj, uj = euler_steps(x, u, dv, dt, j)
        _record(records, s // stride - 1, i, xj, uj, ang, qj, body, options.gravity)


@njit(cache=True)
def _record(records: Records, j: int, i: int, x: tuple, u: tuple, ang: tuple, q: np.ndarray,
            body: Body, g: float) -> None:
    """Store the state after a step: centre of mass, the listing's energy, orientation, nodes."""
    x0, x1, x2 = x
    u0, u1, u2 = u
    l0, l1, l2 = ang
    records.x[i, j, 0], records.x[i, j, 1], records.x[i, j, 2] = x0, x1, x2
    if records.energy.shape[1] > 0:
        if body.inv_iso > 0.0:
            rot = 0.5 * (l0 * l0 + l1 * l1 + l2 * l2) * body.inv_iso
        else:
            wl0, wl1, wl2 = angular_velocity(q, body.inv_inertia, body.inv_iso, l0, l1, l2)
            rot = 0.5 * (l0 * wl0 + l1 * wl1 + l2 * wl2)
        records.energy[i, j] = 0.5 * body.mass * (u0 * u0 + u1 * u1 + u2 * u2) + rot \
            + body.mass * g * x2
    if records.orientation.shape[1] > 0:
        for a in range(3):
            for c in range(3):
                records.orientation[i, j, a, c] = q[a, c]
    if records.nodes.shape[1] > 0:
        vertices = body.vertices
        for k in range(vertices.shape[0]):
            for a in range(3):
                records.nodes[i, j, k, a] = (
                    x[a] + q[a, 0] * vertices[k, 0] + q[a, 1] * vertices[k, 1]
                    + q[a, 2] * vertices[k, 2]
                )


@njit(cache=True, parallel=True, nogil=True)
def simulate_batch(dice: Dice, body: Body, contact: Contact, options: Options, stops: Stops,
                   records: Records, out: Outcome) -> None:
    """Advance a batch of dice in place, in parallel over dice (the GIL released)."""
    for i in prange(dice.x.shape[0]):  # prange's index is unsigned: one signature for both
        simulate_one(np.int64(i), dice, body, contact, options, stops, records, out)


@njit(cache=True, nogil=True)
def simulate_serial(dice: Dice, body: Body, contact: Contact, options: Options, stops: Stops,
                    records: Records, out: Outcome) -> None:
    """:func:`simulate_batch` on the calling thread (no parallel region), same results."""
    for i in range(dice.x.shape[0]):
        simulate_one(i, dice, body, contact, options, stops, records, out)

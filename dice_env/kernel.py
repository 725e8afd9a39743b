"""The compiled integrator: the paper's step, written once, run over a batch of dice.

One step of ``real_throw_cube.m`` for one die (the listing's order, "modified forward Euler"):

1. corner offsets ``r_k = Q b_k`` and velocities ``U_k = u + w x r_k`` from the state;
2. per corner: ``dg = max(0, -n.X_k)``, ``un = n.U_k``, ``fn = max(0, S dg - D un)`` (only
   corners with ``n.X_k < 0`` under the gated law), friction ``-mu fn Ut/(|Ut| + vmin)``
   (the listing's) or stick-slip (below);
3. ``u += dt F/m`` (gravity included), then ``x += dt u`` with the new ``u``;
4. ``L += dt sum_k r_k x F_k`` (offsets before rotating), ``w = I_world^-1 L`` with
   ``I_world = Q I_body Q^T``, then ``Q = R(w dt) Q`` with the Rodrigues rotation
   ``R = P + cos(|w|dt)(E - P) + sin(|w|dt) [w]x/|w|``; ``R = E`` exactly when ``w = 0``.

Stick-slip friction (``stick``, the default scene's; Cundall and Strack 1979): a corner that
touches the ground is tied to the point where it touched; the tangential force is a spring and
damper ``-kt e - ct Ut`` on its tangential offset ``e`` from that point, and when that exceeds
``mu fn`` the corner slips: the force is ``mu fn`` against the slip velocity (against the
spring's pull while the corner is too slow for its direction to mean anything) and the tie
point moves so that the spring alone carries it. Taking the slip direction from the velocity
rather than from the lagging spring is what makes sliding converge (about 8 times smaller
trajectory errors at the default step). The tie is released when the corner leaves the ground
or its normal force vanishes. A sticking corner thus stays put instead of dithering about zero
slip speed as a sign-like friction does.

Work a scene does not need is skipped, with the result of computing it as zero: no rotation
when ``rotation`` is off, no friction when ``mu = 0``, no damping term when ``D = 0``, no
records unless asked (and then only every ``stride`` steps).

Free flight (``flight``: gated law, or ``D = 0`` where the paper law is the same): a step whose
corners are all above the plane feels gravity alone, and so do the following steps until a
corner can reach the plane. A lower bound on the lowest corner (centre on its exact discrete
parabola, corners moving at most ``|w| r_max`` along the normal) gives how many steps are
surely contact-free; all but the last (so a contact step always follows a plain one) are taken
in one jump: the centre in the closed form of those Euler steps, the orientation by one
rotation of angle ``N |w| dt`` (isotropic die: ``w`` is constant) or by the plain torque-free
rotation steps (loaded die). Every other step is the plain step above.

Midpoint contact forces (``midpoint``, ``Scheme.MIDPOINT``, the default scene's): the kick of a
step stands for the interval from half a step before to half a step after the positions it
uses, so the velocity-dependent forces (damping and friction) take the corner velocity
extrapolated to the positions' time, ``u + (u - u_prev)/2`` and ``w + (w - w_prev)/2``, and a
corner that entered contact during the last step (height ``h_prev > 0``, now ``h < 0``) gets
its damping weighted by the time in contact within that interval,
``1/2 - h / (h_prev - h)``. Both remove first-order errors of the listing's step at every
impact; the sign-like friction of a tiny ``vmin`` keeps another one (``docs/error-vs-runtime.md``).
The friction's limit ``mu fn`` takes the unweighted normal force: weighting it too left about
6 % of gentle throws' faces unconverged between dt/8 and dt/16 (measured; with it unweighted,
99 %+ agree).

Layout (vectorised across dice): the batch is cut into chunks that run in parallel
(``prange``); a chunk runs through a tile of ``TILE`` lanes, one die per lane, every field of a
die a row of the tile, so that one pass of a loop over the lanes does one step of every die and
LLVM turns it into SIMD code (4 dice per instruction with AVX2). In that pass every lane
computes every branch of the step (each corner's contact, friction, slip, rest and lock tests)
and keeps the one the step takes, as selects; scene flags that are constants in a
specialisation (:func:`_step_table`, :func:`_step_listing`) cost nothing. What does not
vectorise is left to a scalar pass over the lanes that need it: the free-flight jump, a turn
above 1/64 rad per step (``sin``), records, and a die's end, whose lane then takes the next
die of the chunk. Dice are independent and every lane does the same arithmetic in the same
order as a lone die would (no fast-math, so no reassociation or fused multiply-add), so
results are bit-identical for any batch size or thread count.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

# Per-die end status.
RUNNING, SETTLED, NONFINITE, DECIDED = 0, 1, 2, 3

# A tile holds TILE dice as rows of TILE lanes: field r of lane i is tile[r * TILE + i]. The
# constant row stride lets LLVM prove the lanes independent and vectorise the step across them.
TILE = 32
X, U, L, W, Q = 0, 3, 6, 9, 12  # centre, velocity, angular momentum, angular velocity, Q (9)
PU, PW = 21, 24  # velocities one step back, for the midpoint forces
HEIGHT, TIED, ANCHOR = 27, 35, 43  # per corner: height entering the last step, tie, tie point
STEP, QUIET, E_START, E_TOL, E_MAX, WAS, PEN, HITS = 67, 68, 69, 70, 71, 72, 73, 74
F, TQ, LOWEST, TOUCH, NEXT_RECORD, REST_T = 75, 78, 81, 82, 83, 84
FLAG, DIE = 85, 86
ROWS = 87
# Lane flags after the vectorised part of a step: what the scalar part still has to do.
DONE_STEP, FLIGHT, BIG_TURN, RECORD, END = 0, 1, 2, 4, 8
# Below this squared rotation angle per step, R(w dt) comes from its series (vectorisable).
SERIES = 2.44140625e-4


@njit(cache=True, inline="always")
def _rotation(v0: float, v1: float, v2: float, t2: float, a: float, b: float) -> tuple:
    """``R = (1 - b t^2) E + a [v]x + b v v^T`` as its 9 entries, row by row."""
    d = 1.0 - b * t2
    r00, r11, r22 = d + b * v0 * v0, d + b * v1 * v1, d + b * v2 * v2
    r01, r10 = b * v0 * v1 - a * v2, b * v0 * v1 + a * v2
    r02, r20 = b * v0 * v2 + a * v1, b * v0 * v2 - a * v1
    r12, r21 = b * v1 * v2 - a * v0, b * v1 * v2 + a * v0
    return r00, r01, r02, r10, r11, r12, r20, r21, r22


@njit(cache=True, inline="always")
def _series(t2: float) -> tuple[float, float]:
    """``a = sin(t)/t`` and ``b = (1 - cos t)/t^2`` from their series in ``t^2`` (t < 1/64)."""
    a = 1.0 - t2 * (1.0 / 6.0 - t2 * (1.0 / 120.0 - t2 * (1.0 / 5040.0 - t2 / 362880.0)))
    b = 0.5 - t2 * (1.0 / 24.0 - t2 * (1.0 / 720.0 - t2 * (1.0 / 40320.0 - t2 / 3628800.0)))
    return a, b


@njit(cache=True, inline="always")
def _times(r: tuple, c0: float, c1: float, c2: float) -> tuple[float, float, float]:
    """``R c`` for a column ``c``."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = r
    return (r00 * c0 + r01 * c1 + r02 * c2, r10 * c0 + r11 * c1 + r12 * c2,
            r20 * c0 + r21 * c1 + r22 * c2)


@njit(cache=True, inline="always")
def _rotate(q: np.ndarray, w0: float, w1: float, w2: float, dt: float) -> None:
    """Left-multiply the orientation ``q`` (3x3, in place) by the Rodrigues rotation R(w dt).

    With ``v = w dt`` and ``t = |v|``: ``R = (1 - b t^2) E + a [v]x + b v v^T``,
    ``a = sin(t)/t``, ``b = (1 - cos t)/t^2`` (the listing's ``P + cos(E - P) + sin [k]x``
    rearranged). Below 1/64 rad, a step's rotation as a rule, ``a`` and ``b`` come from their
    series in ``t^2`` (first omitted terms below 1e-25): no square root, division or library
    call. ``R = E`` exactly when ``w = 0``.
    """
    v0, v1, v2 = w0 * dt, w1 * dt, w2 * dt
    t2 = v0 * v0 + v1 * v1 + v2 * v2
    if t2 == 0.0:
        return
    if t2 < SERIES:
        a, b = _series(t2)
    else:
        t = math.sqrt(t2)
        a = math.sin(t) / t
        half = math.sin(0.5 * t) / t
        b = 2.0 * half * half
    r = _rotation(v0, v1, v2, t2, a, b)
    for j in range(3):
        q[0, j], q[1, j], q[2, j] = _times(r, q[0, j], q[1, j], q[2, j])


@njit(cache=True, inline="always")
def _inverse_world_inertia_times(
    q: np.ndarray, inv_body: np.ndarray, inv_iso: float, l0: float, l1: float, l2: float
) -> tuple[float, float, float]:
    """``I_world^-1 L`` with ``I_world = Q I_body Q^T``; ``L * inv_iso`` when ``inv_iso > 0``."""
    return _world_inverse_inertia_times(
        q[0, 0], q[0, 1], q[0, 2], q[1, 0], q[1, 1], q[1, 2], q[2, 0], q[2, 1], q[2, 2],
        (inv_body[0, 0], inv_body[0, 1], inv_body[0, 2], inv_body[1, 0], inv_body[1, 1],
         inv_body[1, 2], inv_body[2, 0], inv_body[2, 1], inv_body[2, 2]), inv_iso, l0, l1, l2)


@njit(cache=True, inline="always")
def _free_steps(lowest: float, un: float, spin: float, r_max: float, dvn: float, dt: float,
                limit: int) -> int:
    """Number of steps from now (1 to ``limit``) surely free of contact.

    Given the lowest corner height ``lowest >= 0`` entering this step.
    After ``j`` flight steps the centre has moved ``dt (j un + dvn j(j+1)/2)`` along the normal
    (``un`` its normal velocity, ``dvn`` the per-step change of it from gravity) and a corner at
    most ``j dt spin r_max`` relative to it; the count is the last ``j`` where that bound on the
    lowest corner is still >= 0, plus one.
    """
    b = dt * (un - spin * r_max)
    a = -0.5 * dt * dvn  # >= 0: gravity pulls toward the plane
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


@njit(cache=True, inline="always")
def _torque_free(q: np.ndarray, inv_body: np.ndarray, inv_iso: float, l0: float, l1: float,
                 l2: float, dt: float, n: int) -> tuple[float, float, float]:
    """``n`` rotation steps of step 4 at constant ``L``, in place on ``q``; returns the last ``w``.

    An isotropic die spins at the constant ``w = L / I``: one rotation of angle ``n |w| dt``.
    A loaded die takes the ``n`` plain steps (``w`` follows ``I_world``).
    """
    w0, w1, w2 = _inverse_world_inertia_times(q, inv_body, inv_iso, l0, l1, l2)
    if inv_iso > 0.0:
        _rotate(q, w0, w1, w2, n * dt)
        return w0, w1, w2
    _rotate(q, w0, w1, w2, dt)
    for _ in range(n - 1):
        w0, w1, w2 = _inverse_world_inertia_times(q, inv_body, inv_iso, l0, l1, l2)
        _rotate(q, w0, w1, w2, dt)
    return w0, w1, w2


@njit(cache=True, inline="always")
def _record(j, i, x0, x1, x2, u0, u1, u2, l0, l1, l2, qi, inv_body, inv_iso, body, mass, g,
            rec_x, rec_e, rec_q, rec_nodes, record_e, record_q, record_nodes):
    """Store the state after a step: centre of mass, the listing's energy, orientation, nodes."""
    rec_x[i, j, 0], rec_x[i, j, 1], rec_x[i, j, 2] = x0, x1, x2
    if record_e:
        if inv_iso > 0.0:
            rot = 0.5 * (l0 * l0 + l1 * l1 + l2 * l2) * inv_iso
        else:
            wl0, wl1, wl2 = _inverse_world_inertia_times(qi, inv_body, inv_iso, l0, l1, l2)
            rot = 0.5 * (l0 * wl0 + l1 * wl1 + l2 * wl2)
        rec_e[i, j] = 0.5 * mass * (u0 * u0 + u1 * u1 + u2 * u2) + rot + mass * g * x2
    if record_q:
        rec_q[i, j] = qi
    if record_nodes:
        for k in range(8):
            for a in range(3):
                rec_nodes[i, j, k, a] = (
                    (x0, x1, x2)[a]
                    + qi[a, 0] * body[k, 0] + qi[a, 1] * body[k, 1] + qi[a, 2] * body[k, 2]
                )


@njit(cache=True, inline="always")
def _at(row: int, i: int) -> int:
    return row * TILE + i


@njit(cache=True, inline="always")
def _max(a: float, b: float) -> float:
    """``max(a, b)`` as a select (numba's builtin is a call, which stops vectorisation)."""
    return b if b > a else a


@njit(cache=True, inline="always")
def _min(a: float, b: float) -> float:
    """``min(a, b)`` as a select."""
    return b if b < a else a


@njit(cache=True, inline="always")
def _corner(t, i, k, b0, b1, b2, lane, ground):
    """Corner ``k`` of lane ``i``: the kernel's per-corner step, written without branches.

    ``lane``: the lane's orientation, centre, velocity, angular velocity and their midpoint
    extrapolations; ``ground``: the normal and the contact constants.

    Returns whether it pushes, the force and torque it then adds, its normal and tangential
    spring energies, whether it touches, its approach speed (0 if not touching), its sink, its
    height, and the squared speed ``|u + w x r|^2`` of the corner.
    """
    (q00, q01, q02, q10, q11, q12, q20, q21, q22, x0, x1, x2, u0, u1, u2, w0, w1, w2, cu0, cu1,
     cu2, cw0, cw1, cw2) = lane
    n0, n1, n2, stiff, damp, mu, vmin, stick, kt, ct, dt, dt_m, gated, midpoint = ground
    rk0 = q00 * b0 + q01 * b1 + q02 * b2
    rk1 = q10 * b0 + q11 * b1 + q12 * b2
    rk2 = q20 * b0 + q21 * b1 + q22 * b2
    height = n0 * (x0 + rk0) + n1 * (x1 + rk1) + n2 * (x2 + rk2)
    before = t[_at(HEIGHT + k, i)]
    t[_at(HEIGHT + k, i)] = height
    tied = t[_at(TIED + k, i)] > 0.0
    above = height >= 0.0
    if above:
        tied = False
    skip = above and gated
    uk0 = u0 + w1 * rk2 - w2 * rk1
    uk1 = u1 + w2 * rk0 - w0 * rk2
    uk2 = u2 + w0 * rk1 - w1 * rk0
    speed2 = uk0 * uk0 + uk1 * uk1 + uk2 * uk2
    dg = _max(0.0, -height)
    un = n0 * uk0 + n1 * uk1 + n2 * uk2
    below = height < 0.0
    spring = 0.0
    tangential = 0.0
    approach = 0.0
    if below:
        spring = 0.5 * stiff * dg * dg
        approach = -un
    fn = stiff * dg
    if midpoint:
        uk0 = cu0 + cw1 * rk2 - cw2 * rk1
        uk1 = cu1 + cw2 * rk0 - cw0 * rk2
        uk2 = cu2 + cw0 * rk1 - cw1 * rk0
        un = n0 * uk0 + n1 * uk1 + n2 * uk2
    friction_limit = fn
    if damp > 0.0:
        friction_limit -= damp * un
        onset = midpoint and before > 0.0 and below
        weighted = fn - (0.5 - height / (before - height)) * damp * un
        fn = weighted if onset else friction_limit
    pushes = not (fn <= 0.0) and not skip
    if fn <= 0.0:
        tied = False
    fk0, fk1, fk2 = fn * n0, fn * n1, fn * n2
    o0, o1 = t[_at(ANCHOR + 3 * k, i)], t[_at(ANCHOR + 3 * k + 1, i)]
    o2 = t[_at(ANCHOR + 3 * k + 2, i)]
    a0, a1, a2 = o0, o1, o2
    if mu > 0.0:
        cap = mu * _max(friction_limit, 0.0)
        ut0, ut1, ut2 = uk0 - un * n0, uk1 - un * n1, uk2 - un * n2
        if stick:
            p0, p1, p2 = x0 + rk0, x1 + rk1, x2 + rk2
            back = dt * height / (before - height) if before > 0.0 else 0.0
            if not tied:
                a0, a1, a2 = p0 + back * ut0, p1 + back * ut1, p2 + back * ut2
            e0, e1, e2 = p0 - a0, p1 - a1, p2 - a2
            en = n0 * e0 + n1 * e1 + n2 * e2
            e0, e1, e2 = e0 - en * n0, e1 - en * n1, e2 - en * n2
            ft0, ft1, ft2 = -kt * e0 - ct * ut0, -kt * e1 - ct * ut1, -kt * e2 - ct * ut2
            size = math.sqrt(ft0 * ft0 + ft1 * ft1 + ft2 * ft2)
            speed = math.sqrt(ut0 * ut0 + ut1 * ut1 + ut2 * ut2)
            if size > cap:
                if speed > 4.0 * cap * dt_m:
                    ratio = -cap / speed
                    ft0, ft1, ft2 = ratio * ut0, ratio * ut1, ratio * ut2
                else:
                    ratio = cap / size
                    ft0, ft1, ft2 = ratio * ft0, ratio * ft1, ratio * ft2
                e0, e1, e2 = -ft0 / kt, -ft1 / kt, -ft2 / kt
                a0, a1, a2 = p0 - e0, p1 - e1, p2 - e2
            if pushes:
                tangential = 0.5 * kt * (e0 * e0 + e1 * e1 + e2 * e2)
                tied = True
            fk0 += ft0
            fk1 += ft1
            fk2 += ft2
        else:
            scale = cap / (math.sqrt(ut0 * ut0 + ut1 * ut1 + ut2 * ut2) + vmin)
            fk0 -= scale * ut0
            fk1 -= scale * ut1
            fk2 -= scale * ut2
    if not pushes:
        a0, a1, a2 = o0, o1, o2
    t[_at(ANCHOR + 3 * k, i)], t[_at(ANCHOR + 3 * k + 1, i)] = a0, a1
    t[_at(ANCHOR + 3 * k + 2, i)] = a2
    t[_at(TIED + k, i)] = 1.0 if tied else 0.0
    tk0 = rk1 * fk2 - rk2 * fk1
    tk1 = rk2 * fk0 - rk0 * fk2
    tk2 = rk0 * fk1 - rk1 * fk0
    return (pushes, fk0, fk1, fk2, tk0, tk1, tk2, spring, tangential, below, approach, dg,
            height, speed2)


@njit(cache=True, inline="always")
def _add(acc, corner, rotation):
    """Add a corner's share to the step's sums (in the corners' order, as the kernel does)."""
    f0, f1, f2, t0, t1, t2, spring, touching, approach, lowest, pen, fastest = acc
    (pushes, fk0, fk1, fk2, tk0, tk1, tk2, normal_spring, tangential_spring, below, approach_k,
     dg, height, speed2) = corner
    lowest = _min(lowest, height)
    fastest = _max(fastest, speed2)
    if below:
        touching += 1
        spring += normal_spring
        pen = _max(pen, dg)
        approach = _max(approach, approach_k)
    if pushes:
        spring += tangential_spring
        f0 += fk0
        f1 += fk1
        f2 += fk2
        if rotation:
            t0 += tk0
            t1 += tk1
            t2 += tk2
    return f0, f1, f2, t0, t1, t2, spring, touching, approach, lowest, pen, fastest


@njit(cache=True, inline="always")
def _world_inverse_inertia_times(q00, q01, q02, q10, q11, q12, q20, q21, q22, inv_body,
                                 inv_iso, l0, l1, l2):
    """``I_world^-1 L`` with ``I_world = Q I_body Q^T``; ``L * inv_iso`` when ``inv_iso > 0``.

    ``inv_body``: the inverse body inertia as a tuple of its 9 entries, row by row.
    """
    if inv_iso > 0.0:
        return l0 * inv_iso, l1 * inv_iso, l2 * inv_iso
    i00, i01, i02, i10, i11, i12, i20, i21, i22 = inv_body
    b0 = q00 * l0 + q10 * l1 + q20 * l2
    b1 = q01 * l0 + q11 * l1 + q21 * l2
    b2 = q02 * l0 + q12 * l1 + q22 * l2
    c0 = i00 * b0 + i01 * b1 + i02 * b2
    c1 = i10 * b0 + i11 * b1 + i12 * b2
    c2 = i20 * b0 + i21 * b1 + i22 * b2
    return (q00 * c0 + q01 * c1 + q02 * c2, q10 * c0 + q11 * c1 + q12 * c2,
            q20 * c0 + q21 * c1 + q22 * c2)


@njit(cache=True, inline="always")
def _tile_step(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu, vmin, stick,
               kt, ct, g, dt, gated, rotation, flight, midpoint, n_steps, stop_at_rest, v_rest,
               hold_steps, rest_energy, rest_excess, lock, energy_scale_add):
    """One step of every lane of the tile ``t``, vectorised across lanes.

    Every lane computes every branch of the step and keeps the one the kernel takes, so a flag
    (``stick``, ``gated``, ``midpoint``) that is a constant here costs nothing: see
    :func:`_step_table` and :func:`_step_listing`.

    Leaves in ``FLAG`` what the scalar part still has to do for a lane: finish a contact-free
    step (``FLIGHT``: the jump), turn by a large angle (``BIG_TURN``), record, or end the die.
    """
    n0, n1, n2 = normal[0], normal[1], normal[2]
    dt_m = dt / mass
    kinetic_rest = 0.5 * mass * v_rest * v_rest
    lock0, lock1, lock2, lock3, lock4, lock5 = lock[0], lock[1], lock[2], lock[3], lock[4], lock[5]
    lock_max = _max(_max(_max(lock0, lock1), _max(lock2, lock3)), _max(lock4, lock5))
    b00, b01, b02 = body[0, 0], body[0, 1], body[0, 2]
    b10, b11, b12 = body[1, 0], body[1, 1], body[1, 2]
    b20, b21, b22 = body[2, 0], body[2, 1], body[2, 2]
    b30, b31, b32 = body[3, 0], body[3, 1], body[3, 2]
    b40, b41, b42 = body[4, 0], body[4, 1], body[4, 2]
    b50, b51, b52 = body[5, 0], body[5, 1], body[5, 2]
    b60, b61, b62 = body[6, 0], body[6, 1], body[6, 2]
    b70, b71, b72 = body[7, 0], body[7, 1], body[7, 2]
    ground = (n0, n1, n2, stiff, damp, mu, vmin, stick, kt, ct, dt, dt_m, gated, midpoint)
    inverse = (inv_body[0, 0], inv_body[0, 1], inv_body[0, 2], inv_body[1, 0], inv_body[1, 1],
                inv_body[1, 2], inv_body[2, 0], inv_body[2, 1], inv_body[2, 2])
    for i in range(lanes):
        step = t[_at(STEP, i)] + 1.0
        x0, x1, x2 = t[_at(X, i)], t[_at(X + 1, i)], t[_at(X + 2, i)]
        u0, u1, u2 = t[_at(U, i)], t[_at(U + 1, i)], t[_at(U + 2, i)]
        l0, l1, l2 = t[_at(L, i)], t[_at(L + 1, i)], t[_at(L + 2, i)]
        w0, w1, w2 = t[_at(W, i)], t[_at(W + 1, i)], t[_at(W + 2, i)]
        q00, q01, q02 = t[_at(Q, i)], t[_at(Q + 1, i)], t[_at(Q + 2, i)]
        q10, q11, q12 = t[_at(Q + 3, i)], t[_at(Q + 4, i)], t[_at(Q + 5, i)]
        q20, q21, q22 = t[_at(Q + 6, i)], t[_at(Q + 7, i)], t[_at(Q + 8, i)]
        pu0, pu1, pu2 = t[_at(PU, i)], t[_at(PU + 1, i)], t[_at(PU + 2, i)]
        pw0, pw1, pw2 = t[_at(PW, i)], t[_at(PW + 1, i)], t[_at(PW + 2, i)]
        cu0, cu1, cu2 = 1.5 * u0 - 0.5 * pu0, 1.5 * u1 - 0.5 * pu1, 1.5 * u2 - 0.5 * pu2
        cw0, cw1, cw2 = 1.5 * w0 - 0.5 * pw0, 1.5 * w1 - 0.5 * pw1, 1.5 * w2 - 0.5 * pw2
        lane = (q00, q01, q02, q10, q11, q12, q20, q21, q22, x0, x1, x2, u0, u1, u2, w0, w1, w2,
                cu0, cu1, cu2, cw0, cw1, cw2)
        acc = (0.0, 0.0, -mass * g, 0.0, 0.0, 0.0, 0.0, 0, 0.0, np.inf, t[_at(PEN, i)], 0.0)
        acc = _add(acc, _corner(t, i, 0, b00, b01, b02, lane, ground), rotation)
        acc = _add(acc, _corner(t, i, 1, b10, b11, b12, lane, ground), rotation)
        acc = _add(acc, _corner(t, i, 2, b20, b21, b22, lane, ground), rotation)
        acc = _add(acc, _corner(t, i, 3, b30, b31, b32, lane, ground), rotation)
        acc = _add(acc, _corner(t, i, 4, b40, b41, b42, lane, ground), rotation)
        acc = _add(acc, _corner(t, i, 5, b50, b51, b52, lane, ground), rotation)
        acc = _add(acc, _corner(t, i, 6, b60, b61, b62, lane, ground), rotation)
        acc = _add(acc, _corner(t, i, 7, b70, b71, b72, lane, ground), rotation)
        f0, f1, f2, t0, t1, t2, spring, touching, approach, lowest, pen, fastest = acc
        wl0, wl1, wl2 = _world_inverse_inertia_times(q00, q01, q02, q10, q11, q12, q20, q21,
                                                     q22, inverse, inv_iso, l0, l1, l2)
        kinetic = 0.5 * mass * (u0 * u0 + u1 * u1 + u2 * u2) + 0.5 * (
            l0 * wl0 + l1 * wl1 + l2 * wl2)
        energy = kinetic + mass * g * x2 + spring
        e_start, e_tol, e_max = t[_at(E_START, i)], t[_at(E_TOL, i)], t[_at(E_MAX, i)]
        if step == 1.0:
            e_start = energy
            e_tol = energy_scale_add + kinetic + mass * g * _max(
                0.0, n0 * x0 + n1 * x1 + n2 * x2)
        else:
            e_max = _max(e_max, energy)
        hits = t[_at(HITS, i)]
        if touching > 0 and not t[_at(WAS, i)] > 0.0 and approach > v_rest:
            hits += 1.0
        flag = DONE_STEP
        end = RUNNING
        # the face up, for the lock (the order of die.FACE_NORMALS)
        up_x = q00 * n0 + q10 * n1 + q20 * n2
        up_y = q01 * n0 + q11 * n1 + q21 * n2
        up_z = q02 * n0 + q12 * n1 + q22 * n2
        best, below_lock = up_z, lock0
        if up_x > best:
            best, below_lock = up_x, lock1
        if up_y > best:
            best, below_lock = up_y, lock2
        if -up_y > best:
            best, below_lock = -up_y, lock3
        if -up_x > best:
            best, below_lock = -up_x, lock4
        if -up_z > best:
            best, below_lock = -up_z, lock5
        quiet = t[_at(QUIET, i)]
        rest_t = t[_at(REST_T, i)]
        if energy < lock_max and energy < below_lock:
            end = DECIDED
        elif stop_at_rest:
            if touching >= 3 and kinetic < kinetic_rest and fastest < v_rest * v_rest:
                quiet += 1.0
                if quiet > hold_steps or energy - rest_energy < rest_excess:
                    rest_t = (step - quiet) * dt
                    end = SETTLED
            else:
                quiet = 0.0
        # 3.-4. the plain update (a contact-free step under free flight is left to the jump)
        dv0, dv1, dv2 = f0 * dt_m, f1 * dt_m, f2 * dt_m
        nu0, nu1, nu2 = u0 + dv0, u1 + dv1, u2 + dv2
        nx0, nx1, nx2 = x0 + dt * nu0, x1 + dt * nu1, x2 + dt * nu2
        nl0, nl1, nl2 = l0, l1, l2
        if rotation:
            nl0, nl1, nl2 = l0 + dt * t0, l1 + dt * t1, l2 + dt * t2
        total = nu0 + nu1 + nu2 + nx0 + nx1 + nx2 + nl0 + nl1 + nl2
        jumps = flight and touching == 0
        if end == RUNNING and not jumps and not total * 0.0 == 0.0:  # not finite
            end = NONFINITE
        nw0, nw1, nw2 = w0, w1, w2
        nq00, nq01, nq02, nq10, nq11, nq12 = q00, q01, q02, q10, q11, q12
        nq20, nq21, nq22 = q20, q21, q22
        turn = 0.0
        if rotation:
            nw0, nw1, nw2 = _world_inverse_inertia_times(
                q00, q01, q02, q10, q11, q12, q20, q21, q22, inverse, inv_iso, nl0, nl1, nl2)
            v0, v1, v2 = nw0 * dt, nw1 * dt, nw2 * dt
            turn = v0 * v0 + v1 * v1 + v2 * v2
            if turn > 0.0 and turn < SERIES:  # R(w dt) Q as _rotate: larger turns are BIG_TURN
                a, b = _series(turn)
                r = _rotation(v0, v1, v2, turn, a, b)
                nq00, nq10, nq20 = _times(r, q00, q10, q20)
                nq01, nq11, nq21 = _times(r, q01, q11, q21)
                nq02, nq12, nq22 = _times(r, q02, q12, q22)
        if end != RUNNING:
            flag = END
            step -= 1.0
        elif jumps:
            flag = FLIGHT
        else:
            if midpoint:
                pu0, pu1, pu2 = nu0 - dv0, nu1 - dv1, nu2 - dv2
                pw0, pw1, pw2 = w0, w1, w2
            u0, u1, u2, x0, x1, x2, l0, l1, l2 = nu0, nu1, nu2, nx0, nx1, nx2, nl0, nl1, nl2
            w0, w1, w2 = nw0, nw1, nw2
            q00, q01, q02, q10, q11, q12 = nq00, nq01, nq02, nq10, nq11, nq12
            q20, q21, q22 = nq20, nq21, nq22
            if turn >= SERIES:
                flag = BIG_TURN
            if step == t[_at(NEXT_RECORD, i)]:
                flag |= RECORD
            if step >= n_steps:
                flag |= END
        t[_at(STEP, i)] = step
        t[_at(X, i)], t[_at(X + 1, i)], t[_at(X + 2, i)] = x0, x1, x2
        t[_at(U, i)], t[_at(U + 1, i)], t[_at(U + 2, i)] = u0, u1, u2
        t[_at(L, i)], t[_at(L + 1, i)], t[_at(L + 2, i)] = l0, l1, l2
        t[_at(W, i)], t[_at(W + 1, i)], t[_at(W + 2, i)] = w0, w1, w2
        t[_at(Q, i)], t[_at(Q + 1, i)], t[_at(Q + 2, i)] = q00, q01, q02
        t[_at(Q + 3, i)], t[_at(Q + 4, i)], t[_at(Q + 5, i)] = q10, q11, q12
        t[_at(Q + 6, i)], t[_at(Q + 7, i)], t[_at(Q + 8, i)] = q20, q21, q22
        t[_at(PU, i)], t[_at(PU + 1, i)], t[_at(PU + 2, i)] = pu0, pu1, pu2
        t[_at(PW, i)], t[_at(PW + 1, i)], t[_at(PW + 2, i)] = pw0, pw1, pw2
        t[_at(F, i)], t[_at(F + 1, i)], t[_at(F + 2, i)] = f0, f1, f2
        t[_at(TQ, i)], t[_at(TQ + 1, i)], t[_at(TQ + 2, i)] = t0, t1, t2
        t[_at(E_START, i)], t[_at(E_TOL, i)], t[_at(E_MAX, i)] = e_start, e_tol, e_max
        t[_at(HITS, i)] = hits
        t[_at(WAS, i)] = 1.0 if touching > 0 else 0.0
        t[_at(PEN, i)] = pen
        t[_at(QUIET, i)] = quiet
        t[_at(REST_T, i)] = rest_t
        t[_at(LOWEST, i)] = lowest
        t[_at(TOUCH, i)] = touching
        t[_at(FLAG, i)] = flag * 16 + end


@njit(cache=True, error_model="numpy")
def _step_table(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu, vmin, kt, ct,
                g, dt, rotation, flight, n_steps, stop_at_rest, v_rest, hold_steps, rest_energy,
                rest_excess, lock, energy_scale_add):
    """:func:`_tile_step` of the default table: gated law, stick-slip friction, midpoint step."""
    _tile_step(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu, vmin, True,
               kt, ct, g, dt, True, rotation, flight, True, n_steps, stop_at_rest, v_rest,
               hold_steps, rest_energy, rest_excess, lock, energy_scale_add)


@njit(cache=True, error_model="numpy")
def _step_listing(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu, vmin, kt,
                  ct, g, dt, rotation, flight, n_steps, stop_at_rest, v_rest, hold_steps,
                  rest_energy, rest_excess, lock, energy_scale_add):
    """:func:`_tile_step` of the paper's listing: its contact law, friction and step."""
    _tile_step(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu, vmin, False,
               kt, ct, g, dt, False, rotation, flight, False, n_steps, stop_at_rest, v_rest,
               hold_steps, rest_energy, rest_excess, lock, energy_scale_add)


@njit(cache=True, error_model="numpy")
def _step_any(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu, vmin, stick, kt,
              ct, g, dt, gated, rotation, flight, midpoint, n_steps, stop_at_rest, v_rest,
              hold_steps, rest_energy, rest_excess, lock, energy_scale_add):
    """:func:`_tile_step` for any other scene."""
    _tile_step(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu, vmin, stick,
               kt, ct, g, dt, gated, rotation, flight, midpoint, n_steps, stop_at_rest, v_rest,
               hold_steps, rest_energy, rest_excess, lock, energy_scale_add)


@njit(cache=True, inline="always")
def _load(t, i, die, x, u, ang, q, w, rotation, max_pen, impacts, stride):
    """Put die ``die`` into lane ``i`` at its start."""
    for a in range(3):
        t[_at(X + a, i)] = x[die, a]
        t[_at(U + a, i)] = u[die, a]
        t[_at(PU + a, i)] = u[die, a]
        t[_at(L + a, i)] = ang[die, a]
        spin = w[die, a] if rotation else 0.0
        t[_at(W + a, i)] = spin
        t[_at(PW + a, i)] = spin
        for b in range(3):
            t[_at(Q + 3 * a + b, i)] = q[die, a, b]
    for k in range(8):
        t[_at(HEIGHT + k, i)] = -1.0
        t[_at(TIED + k, i)] = 0.0
        for a in range(3):
            t[_at(ANCHOR + 3 * k + a, i)] = 0.0
    t[_at(STEP, i)] = 0.0
    t[_at(QUIET, i)] = 0.0
    t[_at(E_START, i)] = 0.0
    t[_at(E_TOL, i)] = 1.0
    t[_at(E_MAX, i)] = -np.inf
    t[_at(WAS, i)] = 1.0
    t[_at(PEN, i)] = max_pen[die]
    t[_at(HITS, i)] = impacts[die]
    t[_at(NEXT_RECORD, i)] = stride
    t[_at(REST_T, i)] = 0.0
    t[_at(DIE, i)] = die


@njit(cache=True, inline="always")
def _lane_orientation(t, i, qi):
    for a in range(3):
        for b in range(3):
            qi[a, b] = t[_at(Q + 3 * a + b, i)]


@njit(cache=True, inline="always")
def _set_lane_orientation(t, i, qi):
    for a in range(3):
        for b in range(3):
            t[_at(Q + 3 * a + b, i)] = qi[a, b]


@njit(cache=True)
def _record_lane(t, i, j, qi, inv_body, inv_iso, body, mass, g, rec_x, rec_e, rec_q, rec_nodes):
    """Record lane ``i``'s state as record ``j`` of its die."""
    _lane_orientation(t, i, qi)
    _record(j, int(t[_at(DIE, i)]), t[_at(X, i)], t[_at(X + 1, i)], t[_at(X + 2, i)],
            t[_at(U, i)], t[_at(U + 1, i)], t[_at(U + 2, i)], t[_at(L, i)], t[_at(L + 1, i)],
            t[_at(L + 2, i)], qi, inv_body, inv_iso, body, mass, g, rec_x, rec_e, rec_q,
            rec_nodes, rec_e.shape[1] > 0, rec_q.shape[1] > 0, rec_nodes.shape[1] > 0)


@njit(cache=True)
def _finish_flight(t, i, qi, body, mass, inv_body, inv_iso, inv_i_min, r_max, normal,
                   g, dt, rotation, midpoint, n_steps, stride, rec_x, rec_e, rec_q, rec_nodes):
    """The rest of a contact-free step of lane ``i``: the free-flight jump (the kernel's 3.-4.).

    Returns the lane's remaining flags and end status.
    """
    n0, n1, n2 = normal[0], normal[1], normal[2]
    dt_m = dt / mass
    n_rec = rec_x.shape[1]
    step = int(t[_at(STEP, i)])
    x0, x1, x2 = t[_at(X, i)], t[_at(X + 1, i)], t[_at(X + 2, i)]
    u0, u1, u2 = t[_at(U, i)], t[_at(U + 1, i)], t[_at(U + 2, i)]
    l0, l1, l2 = t[_at(L, i)], t[_at(L + 1, i)], t[_at(L + 2, i)]
    dv0, dv1, dv2 = t[_at(F, i)] * dt_m, t[_at(F + 1, i)] * dt_m, t[_at(F + 2, i)] * dt_m
    _lane_orientation(t, i, qi)
    die = int(t[_at(DIE, i)])
    spin = math.sqrt(l0 * l0 + l1 * l1 + l2 * l2) * inv_i_min if rotation else 0.0
    jump = max(1, _free_steps(t[_at(LOWEST, i)], n0 * u0 + n1 * u1 + n2 * u2, spin, r_max,
                              n0 * dv0 + n1 * dv1 + n2 * dv2, dt, n_steps - step + 1) - 1)
    if jump > 1:
        for s in range((step + stride - 1) // stride * stride, step + jump - 1, stride):
            if s // stride > n_rec:
                break
            j = s - step + 1
            half = 0.5 * j * (j + 1)
            qj = qi.copy()
            if rotation:
                _torque_free(qj, inv_body, inv_iso, l0, l1, l2, dt, j)
            _record(s // stride - 1, die, x0 + dt * (j * u0 + half * dv0),
                    x1 + dt * (j * u1 + half * dv1), x2 + dt * (j * u2 + half * dv2),
                    u0 + j * dv0, u1 + j * dv1, u2 + j * dv2, l0, l1, l2, qj, inv_body,
                    inv_iso, body, mass, g, rec_x, rec_e, rec_q, rec_nodes,
                    rec_e.shape[1] > 0, rec_q.shape[1] > 0, rec_nodes.shape[1] > 0)
        half = 0.5 * jump * (jump + 1)
        nx0 = x0 + dt * (jump * u0 + half * dv0)
        nx1 = x1 + dt * (jump * u1 + half * dv1)
        nx2 = x2 + dt * (jump * u2 + half * dv2)
        nu0, nu1, nu2 = u0 + jump * dv0, u1 + jump * dv1, u2 + jump * dv2
    else:
        nu0, nu1, nu2 = u0 + dv0, u1 + dv1, u2 + dv2
        nx0, nx1, nx2 = x0 + dt * nu0, x1 + dt * nu1, x2 + dt * nu2
    nl0, nl1, nl2 = l0, l1, l2
    if rotation:
        nl0 = l0 + dt * t[_at(TQ, i)]
        nl1 = l1 + dt * t[_at(TQ + 1, i)]
        nl2 = l2 + dt * t[_at(TQ + 2, i)]
    if not math.isfinite(nu0 + nu1 + nu2 + nx0 + nx1 + nx2 + nl0 + nl1 + nl2):
        t[_at(STEP, i)] = step - 1
        return END, NONFINITE
    if midpoint:
        t[_at(PU, i)], t[_at(PU + 1, i)], t[_at(PU + 2, i)] = nu0 - dv0, nu1 - dv1, nu2 - dv2
        for a in range(3):
            t[_at(PW + a, i)] = t[_at(W + a, i)]
    t[_at(X, i)], t[_at(X + 1, i)], t[_at(X + 2, i)] = nx0, nx1, nx2
    t[_at(U, i)], t[_at(U + 1, i)], t[_at(U + 2, i)] = nu0, nu1, nu2
    t[_at(L, i)], t[_at(L + 1, i)], t[_at(L + 2, i)] = nl0, nl1, nl2
    if rotation:
        w0, w1, w2 = _torque_free(qi, inv_body, inv_iso, nl0, nl1, nl2, dt, jump)
        t[_at(W, i)], t[_at(W + 1, i)], t[_at(W + 2, i)] = w0, w1, w2
        _set_lane_orientation(t, i, qi)
    step += jump - 1
    t[_at(STEP, i)] = step
    flag = DONE_STEP
    if step % stride == 0:
        flag |= RECORD
    t[_at(NEXT_RECORD, i)] = (step // stride + 1) * stride
    if step >= n_steps:
        flag |= END
    return flag, RUNNING


@njit(cache=True)
def _finish(t, i, end, qi, x, u, ang, q, w, body, mass, inv_body, inv_iso, g, dt, rotation,
            stride, rec_x, rec_e, rec_q, rec_nodes, status, unstable, rest_time, impacts,
            max_pen, energy_rise, steps):
    """Write lane ``i``'s die back: its state, its outcome and the rest of its record."""
    die = int(t[_at(DIE, i)])
    step = int(t[_at(STEP, i)])
    for j in range(step // stride, rec_x.shape[1]):
        _record_lane(t, i, j, qi, inv_body, inv_iso, body, mass, g, rec_x, rec_e, rec_q,
                     rec_nodes)
    _lane_orientation(t, i, qi)
    for a in range(3):
        x[die, a] = t[_at(X + a, i)]
        u[die, a] = t[_at(U + a, i)]
        ang[die, a] = t[_at(L + a, i)]
        if rotation:
            w[die, a] = t[_at(W + a, i)]
    q[die] = qi
    status[die] = end
    unstable[die] = end == NONFINITE
    rest_time[die] = t[_at(REST_T, i)] if end == SETTLED else step * dt
    steps[die] = step
    max_pen[die] = t[_at(PEN, i)]
    impacts[die] = int(t[_at(HITS, i)])
    # (e - e0) / tol is monotone in e, so its largest value is that of the largest e
    energy_rise[die] = max(energy_rise[die], (t[_at(E_MAX, i)] - t[_at(E_START, i)])
                           / t[_at(E_TOL, i)])


@njit(cache=True)
def _run_chunk(first, last, x, u, ang, q, w, body, mass, inv_body, iso, inv_i_min, normal,
               stiff, damp, mu, vmin, stick, kt, ct, g, dt, gated, rotation, flight, midpoint,
               n_steps, stop_at_rest, v_rest, hold_steps, rest_energy, rest_excess, lock,
               energy_scale_add, stride, rec_x, rec_e, rec_q, rec_nodes, status, unstable,
               rest_time, impacts, max_pen, energy_rise, steps):
    """Dice ``first`` to ``last - 1`` through one tile: a die that ends makes room for the next."""
    t = np.zeros(ROWS * TILE)
    qi = np.empty((3, 3))
    inv_iso = 1.0 / iso if iso > 0.0 else 0.0
    r_max = 0.0
    for k in range(8):
        r_max = max(r_max, math.sqrt(body[k, 0] ** 2 + body[k, 1] ** 2 + body[k, 2] ** 2))
    n_rec = rec_x.shape[1]
    lanes = min(TILE, last - first)
    queued = first
    for i in range(lanes):
        _load(t, i, queued, x, u, ang, q, w, rotation, max_pen, impacts, stride)
        queued += 1
    table = stick and gated and midpoint
    listing = not (stick or gated or midpoint)
    while lanes > 0:
        if table:
            _step_table(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu, vmin,
                        kt, ct, g, dt, rotation, flight, n_steps, stop_at_rest, v_rest,
                        hold_steps, rest_energy, rest_excess, lock, energy_scale_add)
        elif listing:
            _step_listing(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu,
                          vmin, kt, ct, g, dt, rotation, flight, n_steps, stop_at_rest, v_rest,
                          hold_steps, rest_energy, rest_excess, lock, energy_scale_add)
        else:
            _step_any(t, lanes, body, mass, inv_body, inv_iso, normal, stiff, damp, mu, vmin,
                      stick, kt, ct, g, dt, gated, rotation, flight, midpoint, n_steps,
                      stop_at_rest, v_rest, hold_steps, rest_energy, rest_excess, lock,
                      energy_scale_add)
        i = 0
        while i < lanes:
            code = int(t[_at(FLAG, i)])
            flag, end = code // 16, code % 16
            if flag & FLIGHT:
                flag, end = _finish_flight(t, i, qi, body, mass, inv_body, inv_iso, inv_i_min,
                                           r_max, normal, g, dt, rotation, midpoint, n_steps,
                                           stride, rec_x, rec_e, rec_q, rec_nodes)
            if flag & BIG_TURN:
                _lane_orientation(t, i, qi)
                _rotate(qi, t[_at(W, i)], t[_at(W + 1, i)], t[_at(W + 2, i)], dt)
                _set_lane_orientation(t, i, qi)
            if flag & RECORD:
                step = int(t[_at(STEP, i)])
                if step // stride <= n_rec:
                    _record_lane(t, i, step // stride - 1, qi, inv_body, inv_iso, body, mass,
                                 g, rec_x, rec_e, rec_q, rec_nodes)
                t[_at(NEXT_RECORD, i)] = step + stride
            if not flag & END:
                i += 1
                continue
            _finish(t, i, end, qi, x, u, ang, q, w, body, mass, inv_body, inv_iso, g, dt,
                    rotation, stride, rec_x, rec_e, rec_q, rec_nodes, status, unstable,
                    rest_time, impacts, max_pen, energy_rise, steps)
            if queued < last:
                _load(t, i, queued, x, u, ang, q, w, rotation, max_pen, impacts, stride)
                queued += 1
                i += 1
            else:  # no die waiting: the last lane moves here, flags and all
                lanes -= 1
                for r in range(ROWS):
                    t[_at(r, i)] = t[_at(r, lanes)]


# Dice per chunk of the batch: a chunk runs through one tile, chunks run in parallel.
CHUNK = 4 * TILE


@njit(cache=True, parallel=True)
def simulate_batch(
    x, u, ang, q, w, body, mass, inv_body, iso, inv_i_min, normal, stiff, damp, mu, vmin, stick,
    kt, ct, g, dt, gated, rotation, flight, midpoint, n_steps, stop_at_rest, v_rest, hold_steps,
    rest_energy, rest_excess, lock_energy, energy_scale_add, stride, rec_x, rec_e, rec_q,
    rec_nodes, status, unstable, rest_time, impacts, max_pen, energy_rise, steps,
):
    """Advance a batch of dice in place, chunks of it in parallel."""
    n = x.shape[0]
    for c in prange((n + CHUNK - 1) // CHUNK):
        _run_chunk(c * CHUNK, min(n, (c + 1) * CHUNK), x, u, ang, q, w, body, mass, inv_body,
                   iso, inv_i_min, normal, stiff, damp, mu, vmin, stick, kt, ct, g, dt, gated,
                   rotation, flight, midpoint, n_steps, stop_at_rest, v_rest, hold_steps,
                   rest_energy, rest_excess, lock_energy, energy_scale_add, stride, rec_x,
                   rec_e, rec_q, rec_nodes, status, unstable, rest_time, impacts, max_pen,
                   energy_rise, steps)


@njit(cache=True)
def simulate_serial(
    x, u, ang, q, w, body, mass, inv_body, iso, inv_i_min, normal, stiff, damp, mu, vmin, stick,
    kt, ct, g, dt, gated, rotation, flight, midpoint, n_steps, stop_at_rest, v_rest, hold_steps,
    rest_energy, rest_excess, lock_energy, energy_scale_add, stride, rec_x, rec_e, rec_q,
    rec_nodes, status, unstable, rest_time, impacts, max_pen, energy_rise, steps,
):
    """:func:`simulate_batch` on the calling thread, with the same results."""
    _run_chunk(0, x.shape[0], x, u, ang, q, w, body, mass, inv_body, iso, inv_i_min, normal,
               stiff, damp, mu, vmin, stick, kt, ct, g, dt, gated, rotation, flight, midpoint,
               n_steps, stop_at_rest, v_rest, hold_steps, rest_energy, rest_excess, lock_energy,
               energy_scale_add, stride, rec_x, rec_e, rec_q, rec_nodes, status, unstable,
               rest_time, impacts, max_pen, energy_rise, steps)

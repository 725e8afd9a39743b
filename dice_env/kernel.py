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

Dice are independent: each die steps until its time limit, rest, or a non-finite state, so
results are bit-identical for any batch size or thread count (``prange`` over the batch).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

# Per-die end status.
RUNNING, SETTLED, NONFINITE, DECIDED, ABORTED = 0, 1, 2, 3, 4
ABORT_EVERY = 4096  # loop passes between looks at the abort flag (a power of two)


SERIES = 2.44140625e-4  # (1/64 rad)^2: below this squared turn, R's coefficients from series


@njit(cache=True, inline="always")
def _rotation_series(t2: float) -> tuple[float, float]:
    """``a = sin(t)/t`` and ``b = (1 - cos t)/t^2`` from their series in ``t^2 < SERIES``.

    First omitted terms below 1e-25: no square root, division or library call.
    """
    a = 1.0 - t2 * (1.0 / 6.0 - t2 * (1.0 / 120.0 - t2 * (1.0 / 5040.0 - t2 / 362880.0)))
    b = 0.5 - t2 * (1.0 / 24.0 - t2 * (1.0 / 720.0 - t2 * (1.0 / 40320.0 - t2 / 3628800.0)))
    return a, b


@njit(cache=True, inline="always")
def _rodrigues(v0: float, v1: float, v2: float, t2: float, a: float, b: float) -> tuple:
    """The entries of ``R = (1 - b t^2) E + a [v]x + b v v^T``, row by row."""
    d = 1.0 - b * t2
    r00, r11, r22 = d + b * v0 * v0, d + b * v1 * v1, d + b * v2 * v2
    r01, r10 = b * v0 * v1 - a * v2, b * v0 * v1 + a * v2
    r02, r20 = b * v0 * v2 + a * v1, b * v0 * v2 - a * v1
    r12, r21 = b * v1 * v2 - a * v0, b * v1 * v2 + a * v0
    return r00, r01, r02, r10, r11, r12, r20, r21, r22


@njit(cache=True, inline="always")
def _rotate(q: np.ndarray, w0: float, w1: float, w2: float, dt: float) -> None:
    """Left-multiply the orientation ``q`` (3x3, in place) by the Rodrigues rotation R(w dt).

    With ``v = w dt`` and ``t = |v|``: ``R = (1 - b t^2) E + a [v]x + b v v^T``,
    ``a = sin(t)/t``, ``b = (1 - cos t)/t^2`` (the listing's ``P + cos(E - P) + sin [k]x``
    rearranged). Below 1/64 rad, a step's rotation as a rule, ``a`` and ``b`` come from their
    series (:func:`_rotation_series`). ``R = E`` exactly when ``w = 0``.
    """
    v0, v1, v2 = w0 * dt, w1 * dt, w2 * dt
    t2 = v0 * v0 + v1 * v1 + v2 * v2
    if t2 == 0.0:
        return
    if t2 < SERIES:
        a, b = _rotation_series(t2)
    else:
        t = math.sqrt(t2)
        a = math.sin(t) / t
        half = math.sin(0.5 * t) / t
        b = 2.0 * half * half
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = _rodrigues(v0, v1, v2, t2, a, b)
    for j in range(3):
        q0, q1, q2 = q[0, j], q[1, j], q[2, j]
        q[0, j] = r00 * q0 + r01 * q1 + r02 * q2
        q[1, j] = r10 * q0 + r11 * q1 + r12 * q2
        q[2, j] = r20 * q0 + r21 * q1 + r22 * q2


@njit(cache=True, inline="always")
def _inverse_world_inertia_times(
    q: np.ndarray, inv_body: np.ndarray, inv_iso: float, l0: float, l1: float, l2: float
) -> tuple[float, float, float]:
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


@njit(cache=True, inline="always")
def _face_up_index(q: np.ndarray, n0: float, n1: float, n2: float) -> int:
    """Index (0-5, the order of ``die.FACE_NORMALS``) of the face pointing most along ``n``."""
    up_x = q[0, 0] * n0 + q[1, 0] * n1 + q[2, 0] * n2  # n in the body frame, Q^T n
    up_y = q[0, 1] * n0 + q[1, 1] * n1 + q[2, 1] * n2
    up_z = q[0, 2] * n0 + q[1, 2] * n1 + q[2, 2] * n2
    best, index = up_z, 0
    for value, k in ((up_x, 1), (up_y, 2), (-up_y, 3), (-up_x, 4), (-up_z, 5)):
        if value > best:
            best, index = value, k
    return index


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


@njit(cache=True)
def _simulate_one(
    i, x, u, ang, q, w, body, mass, inv_body, iso, inv_i_min, normal, stiff, damp, mu, vmin,
    stick, kt, ct, g, dt, gated, rotation, flight, midpoint, n_steps, stop_at_rest, v_rest,
    hold_steps, rest_energy, rest_excess, lock_energy, energy_scale_add, stride, rec_x, rec_e,
    rec_q, rec_nodes, status, unstable, rest_time, impacts, max_pen, energy_rise, steps, abort,
):
    """Advance die ``i`` in place; see :func:`simulate_batch` for the arguments."""
    n0, n1, n2 = normal[0], normal[1], normal[2]
    x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
    u0, u1, u2 = u[i, 0], u[i, 1], u[i, 2]
    l0, l1, l2 = ang[i, 0], ang[i, 1], ang[i, 2]
    w0, w1, w2 = (w[i, 0], w[i, 1], w[i, 2]) if rotation else (0.0, 0.0, 0.0)
    inv_iso = 1.0 / iso if iso > 0.0 else 0.0
    dt_m = dt / mass
    r_max = 0.0
    for k in range(8):
        r_max = max(r_max, math.sqrt(body[k, 0] ** 2 + body[k, 1] ** 2 + body[k, 2] ** 2))
    qi = q[i].copy()
    n_rec = rec_x.shape[1]
    record_e, record_q = rec_e.shape[1] > 0, rec_q.shape[1] > 0
    record_nodes = rec_nodes.shape[1] > 0
    kinetic_rest = 0.5 * mass * v_rest * v_rest
    lock_max = lock_energy.max()
    e_start = 0.0
    e_tol = 1.0
    e_max = -np.inf
    quiet = 0
    was_in_contact = True
    end = RUNNING
    pen = max_pen[i]
    hits = impacts[i]
    step = 0
    passes = 0
    next_record = stride
    pu0, pu1, pu2 = u0, u1, u2  # velocities one step back, for the midpoint forces
    pw0, pw1, pw2 = w0, w1, w2
    heights = np.full(8, -1.0)  # corner heights entering the last step
    anchors = np.zeros((8, 3))  # stick-slip: where each corner's tangential spring is tied
    tied = np.zeros(8, np.bool_)
    while step < n_steps:
        passes += 1
        if passes & (ABORT_EVERY - 1) == 0 and abort[0] != 0:
            end = ABORTED
            break
        step += 1
        if midpoint:
            cu0, cu1, cu2 = 1.5 * u0 - 0.5 * pu0, 1.5 * u1 - 0.5 * pu1, 1.5 * u2 - 0.5 * pu2
            cw0, cw1, cw2 = 1.5 * w0 - 0.5 * pw0, 1.5 * w1 - 0.5 * pw1, 1.5 * w2 - 0.5 * pw2
        # 1.-2. corners, and the forces and torques of the ground on them
        f0, f1, f2 = 0.0, 0.0, -mass * g
        t0, t1, t2 = 0.0, 0.0, 0.0
        spring = 0.0  # energy in the normal springs
        spring_t = 0.0  # and in the stick-slip tangential springs
        touching = 0
        approach = 0.0
        lowest = np.inf
        # kinetic energy of the state entering this step; near rest, the fastest corner
        wl0, wl1, wl2 = _inverse_world_inertia_times(qi, inv_body, inv_iso, l0, l1, l2)
        kinetic = 0.5 * mass * (u0 * u0 + u1 * u1 + u2 * u2) + 0.5 * (
            l0 * wl0 + l1 * wl1 + l2 * wl2
        )
        near_rest = stop_at_rest and kinetic < kinetic_rest
        fastest = 0.0  # largest squared corner speed |u + w x r_k|^2, when near_rest
        for k in range(8):
            b0, b1, b2 = body[k, 0], body[k, 1], body[k, 2]
            rk0 = qi[0, 0] * b0 + qi[0, 1] * b1 + qi[0, 2] * b2
            rk1 = qi[1, 0] * b0 + qi[1, 1] * b1 + qi[1, 2] * b2
            rk2 = qi[2, 0] * b0 + qi[2, 1] * b1 + qi[2, 2] * b2
            height = n0 * (x0 + rk0) + n1 * (x1 + rk1) + n2 * (x2 + rk2)
            lowest = min(lowest, height)
            before = heights[k]
            heights[k] = height
            if height >= 0.0:
                tied[k] = False
                if gated:
                    if near_rest:
                        v0 = u0 + w1 * rk2 - w2 * rk1
                        v1 = u1 + w2 * rk0 - w0 * rk2
                        v2 = u2 + w0 * rk1 - w1 * rk0
                        fastest = max(fastest, v0 * v0 + v1 * v1 + v2 * v2)
                    continue
            uk0 = u0 + w1 * rk2 - w2 * rk1
            uk1 = u1 + w2 * rk0 - w0 * rk2
            uk2 = u2 + w0 * rk1 - w1 * rk0
            if near_rest:
                fastest = max(fastest, uk0 * uk0 + uk1 * uk1 + uk2 * uk2)
            dg = max(0.0, -height)
            un = n0 * uk0 + n1 * uk1 + n2 * uk2
            if height < 0.0:
                touching += 1
                spring += 0.5 * stiff * dg * dg
                pen = max(pen, dg)
                approach = max(approach, -un)
            fn = stiff * dg
            if midpoint:
                uk0 = cu0 + cw1 * rk2 - cw2 * rk1
                uk1 = cu1 + cw2 * rk0 - cw0 * rk2
                uk2 = cu2 + cw0 * rk1 - cw1 * rk0
                un = n0 * uk0 + n1 * uk1 + n2 * uk2
            friction_limit = fn  # normal force for the friction, without the onset weight
            if damp > 0.0:
                friction_limit -= damp * un
                if midpoint and before > 0.0 and height < 0.0:
                    fn -= (0.5 - height / (before - height)) * damp * un
                else:
                    fn = friction_limit
            if fn <= 0.0:
                tied[k] = False
                continue
            fk0, fk1, fk2 = fn * n0, fn * n1, fn * n2
            if mu > 0.0:
                cap = mu * max(friction_limit, 0.0)  # Coulomb's limit mu fn
                ut0, ut1, ut2 = uk0 - un * n0, uk1 - un * n1, uk2 - un * n2
                if stick:
                    # tangential spring from the tie point plus damping, capped at mu fn
                    p0, p1, p2 = x0 + rk0, x1 + rk1, x2 + rk2
                    if not tied[k]:
                        # tied where it crossed the plane during the last step, if it did
                        tied[k] = True
                        back = dt * height / (before - height) if before > 0.0 else 0.0
                        anchors[k, 0] = p0 + back * ut0
                        anchors[k, 1] = p1 + back * ut1
                        anchors[k, 2] = p2 + back * ut2
                    e0, e1, e2 = p0 - anchors[k, 0], p1 - anchors[k, 1], p2 - anchors[k, 2]
                    en = n0 * e0 + n1 * e1 + n2 * e2
                    e0, e1, e2 = e0 - en * n0, e1 - en * n1, e2 - en * n2
                    ft0, ft1, ft2 = -kt * e0 - ct * ut0, -kt * e1 - ct * ut1, -kt * e2 - ct * ut2
                    size = math.sqrt(ft0 * ft0 + ft1 * ft1 + ft2 * ft2)
                    if size > cap:
                        # slip: Coulomb's force against the slip velocity, or along the
                        # spring's pull while the corner is slower than one step's friction
                        # kick on a quarter of the die could make it (then its direction
                        # means nothing); the tie point follows the corner
                        speed = math.sqrt(ut0 * ut0 + ut1 * ut1 + ut2 * ut2)
                        if speed > 4.0 * cap * dt_m:
                            ratio = -cap / speed
                            ft0, ft1, ft2 = ratio * ut0, ratio * ut1, ratio * ut2
                        else:
                            ratio = cap / size
                            ft0, ft1, ft2 = ratio * ft0, ratio * ft1, ratio * ft2
                        e0, e1, e2 = -ft0 / kt, -ft1 / kt, -ft2 / kt
                        anchors[k, 0], anchors[k, 1], anchors[k, 2] = p0 - e0, p1 - e1, p2 - e2
                    spring_t += 0.5 * kt * (e0 * e0 + e1 * e1 + e2 * e2)
                    fk0 += ft0
                    fk1 += ft1
                    fk2 += ft2
                else:
                    scale = cap / (math.sqrt(ut0 * ut0 + ut1 * ut1 + ut2 * ut2) + vmin)
                    fk0 -= scale * ut0
                    fk1 -= scale * ut1
                    fk2 -= scale * ut2
            f0 += fk0
            f1 += fk1
            f2 += fk2
            if rotation:
                t0 += rk1 * fk2 - rk2 * fk1
                t1 += rk2 * fk0 - rk0 * fk2
                t2 += rk0 * fk1 - rk1 * fk0
        # energy of the state entering this step. The gain check leaves out the tangential
        # springs: a slip re-ties a spring to carry the whole force mu fn, damping share
        # included, which can stretch it beyond what the corner's motion put in (on a soft,
        # heavily damped table, many times the throw's energy) and is shed again as the
        # force falls; the decided-face lock counts them, which only delays it
        checked = kinetic + mass * g * x2 + spring
        energy = checked + spring_t
        if step == 1:
            e_start = checked
            e_tol = energy_scale_add + kinetic + mass * g * max(0.0, n0 * x0 + n1 * x1 + n2 * x2)
        else:
            e_max = max(e_max, checked)
        if touching > 0 and not was_in_contact and approach > v_rest:
            hits += 1
        was_in_contact = touching > 0
        if energy < lock_max and energy < lock_energy[_face_up_index(qi, n0, n1, n2)]:
            end = DECIDED
            step -= 1
            break
        if stop_at_rest:
            if touching >= 3 and near_rest and fastest < v_rest * v_rest:
                quiet += 1
                if quiet > hold_steps or energy - rest_energy < rest_excess:
                    rest_time[i] = (step - quiet) * dt
                    end = SETTLED
                    step -= 1
                    break
            else:
                quiet = 0
        # 3. centre of mass: velocity first, then position with the new velocity
        dv0, dv1, dv2 = f0 * dt_m, f1 * dt_m, f2 * dt_m
        jump = 1
        if flight and touching == 0:
            spin = math.sqrt(l0 * l0 + l1 * l1 + l2 * l2) * inv_i_min if rotation else 0.0
            # all but the last free step, so the step before a contact is a plain one
            jump = max(1, _free_steps(lowest, n0 * u0 + n1 * u1 + n2 * u2, spin, r_max,
                                      n0 * dv0 + n1 * dv1 + n2 * dv2, dt, n_steps - step + 1) - 1)
        if jump > 1:
            # records falling inside the jump, from the same closed form (the jump itself does
            # not depend on the recording)
            for s in range((step + stride - 1) // stride * stride, step + jump - 1, stride):
                if s // stride > n_rec:
                    break
                j = s - step + 1
                half = 0.5 * j * (j + 1)
                qj = qi.copy()
                if rotation:
                    _torque_free(qj, inv_body, inv_iso, l0, l1, l2, dt, j)
                _record(s // stride - 1, i, x0 + dt * (j * u0 + half * dv0),
                        x1 + dt * (j * u1 + half * dv1), x2 + dt * (j * u2 + half * dv2),
                        u0 + j * dv0, u1 + j * dv1, u2 + j * dv2, l0, l1, l2, qj, inv_body,
                        inv_iso, body, mass, g, rec_x, rec_e, rec_q, rec_nodes,
                        record_e, record_q, record_nodes)
            # `jump` flight steps in closed form: u_j = u + j dv, x_j = x + dt (j u + dv j(j+1)/2)
            half = 0.5 * jump * (jump + 1)
            nx0 = x0 + dt * (jump * u0 + half * dv0)
            nx1 = x1 + dt * (jump * u1 + half * dv1)
            nx2 = x2 + dt * (jump * u2 + half * dv2)
            nu0, nu1, nu2 = u0 + jump * dv0, u1 + jump * dv1, u2 + jump * dv2
        else:
            nu0, nu1, nu2 = u0 + dv0, u1 + dv1, u2 + dv2
            nx0, nx1, nx2 = x0 + dt * nu0, x1 + dt * nu1, x2 + dt * nu2
        # 4. angular momentum, angular velocity, orientation
        nl0, nl1, nl2 = l0, l1, l2
        if rotation:
            nl0, nl1, nl2 = l0 + dt * t0, l1 + dt * t1, l2 + dt * t2
        finite = math.isfinite(nu0 + nu1 + nu2 + nx0 + nx1 + nx2 + nl0 + nl1 + nl2)
        if not finite:
            end = NONFINITE
            step -= 1
            break
        if midpoint:
            pu0, pu1, pu2 = nu0 - dv0, nu1 - dv1, nu2 - dv2
            pw0, pw1, pw2 = w0, w1, w2
        u0, u1, u2, x0, x1, x2, l0, l1, l2 = nu0, nu1, nu2, nx0, nx1, nx2, nl0, nl1, nl2
        if rotation:
            w0, w1, w2 = _torque_free(qi, inv_body, inv_iso, l0, l1, l2, dt, jump)
        step += jump - 1
        if step >= next_record:  # a multiple of the stride reached or jumped over
            if step % stride == 0 and step // stride <= n_rec:
                _record(step // stride - 1, i, x0, x1, x2, u0, u1, u2, l0, l1, l2, qi,
                        inv_body, inv_iso, body, mass, g, rec_x, rec_e, rec_q, rec_nodes,
                        record_e, record_q, record_nodes)
            next_record = (step // stride + 1) * stride
    # a die that stopped early stays where it is for the rest of the record
    for j in range(step // stride, n_rec):
        _record(j, i, x0, x1, x2, u0, u1, u2, l0, l1, l2, qi, inv_body, inv_iso, body, mass, g,
                rec_x, rec_e, rec_q, rec_nodes, record_e, record_q, record_nodes)
    x[i, 0], x[i, 1], x[i, 2] = x0, x1, x2
    u[i, 0], u[i, 1], u[i, 2] = u0, u1, u2
    ang[i, 0], ang[i, 1], ang[i, 2] = l0, l1, l2
    if rotation:
        w[i, 0], w[i, 1], w[i, 2] = w0, w1, w2
    q[i] = qi
    status[i] = end
    unstable[i] = end == NONFINITE
    if end != SETTLED:
        rest_time[i] = step * dt
    steps[i] = step
    max_pen[i] = pen
    impacts[i] = hits
    # (e - e0) / tol is monotone in e, so its largest value is that of the largest e; a die
    # with no energy to measure against (no gravity, no motion) gains infinitely from any
    rise = e_max - e_start
    if e_tol > 0.0:
        rise /= e_tol
    elif rise > 0.0:
        rise = np.inf
    energy_rise[i] = max(energy_rise[i], rise)


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


@njit(cache=True, parallel=True, nogil=True)
def simulate_batch(*args):
    """Advance a batch of dice in place, in parallel over dice.

    ``args`` are those of :func:`_simulate_one` after the die's index:
    ``x, u, ang, q, w, body, mass, inv_body, iso, inv_i_min, normal, stiff, damp, mu, vmin,
    stick, kt, ct, g, dt, gated, rotation, flight, midpoint, n_steps, stop_at_rest, v_rest,
    hold_steps, rest_energy, rest_excess, lock_energy, energy_scale_add, stride, rec_x, rec_e,
    rec_q, rec_nodes, status, unstable, rest_time, impacts, max_pen, energy_rise, steps,
    abort``.

    State (updated in place), batch size B: ``x`` (B, 3) centre of mass; ``u`` (B, 3) its
    velocity; ``ang`` (B, 3) angular momentum about it; ``q`` (B, 3, 3) body-to-world rotation;
    ``w`` (B, 3) angular velocity used for corner velocities.
    Die: ``body`` (8, 3) corners relative to the centre of mass, body frame; ``mass``;
    ``inv_body`` (3, 3) inverse body inertia; ``iso`` the scalar inertia when isotropic, else 0;
    ``inv_i_min`` the inverse of the smallest principal moment.
    Ground: unit ``normal`` (3,), ``stiff``, ``damp``, ``mu``, ``vmin``; ``g`` along -z; ``gated``
    (bool) contact law. ``rotation`` (bool): False translates only. ``flight`` (bool; gated law
    or no damping): jump over contact-free steps. ``midpoint`` (bool): midpoint contact forces
    (see the module docstring). Run ``n_steps`` of ``dt``;
    ``stop_at_rest`` ends a die after ``hold_steps`` quiet steps (at least three corners in
    contact, every corner slower than ``v_rest``), or at a quiet
    step whose total energy is less than ``rest_excess`` above ``rest_energy`` (0: never).
    Whatever ``stop_at_rest``, a die whose total energy falls below ``lock_energy`` (6,) of
    its face up ends decided (``-inf``: never; :func:`dice_env.simulate.lock_energy`).
    ``energy_rise`` gets the largest rise of total energy above its start in units of
    ``KE0 + m g h0 + energy_scale_add`` (``h0`` the start height of the centre above the
    plane); ``unstable`` marks a state that stopped being finite.
    Records every ``stride`` steps into ``rec_x`` (B, n, 3), ``rec_e`` (B, n or 0), ``rec_q``
    (B, n or 0, 3, 3), ``rec_nodes`` (B, n or 0, 8, 3). Outputs per die: ``status``,
    ``unstable``, ``rest_time``, ``impacts``, ``max_pen``, ``energy_rise``, ``steps``.
    ``abort`` (1,) int: set non-zero from another thread, every die still running ends
    ``ABORTED`` within ``ABORT_EVERY`` loop passes (the kernel releases the GIL).
    """
    for i in prange(args[0].shape[0]):
        _simulate_one(i, *args)


@njit(cache=True, nogil=True)
def simulate_serial(*args):
    """:func:`simulate_batch` on the calling thread, with the same results.

    Saves the start of a parallel region: for a single throw or one thread.
    """
    for i in range(args[0].shape[0]):
        _simulate_one(i, *args)

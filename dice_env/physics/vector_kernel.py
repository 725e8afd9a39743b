"""The listing's own scene, stepped across dice at once (SIMD): the paper scene at full speed.

One branch-free pass over a tile of ``TILE`` dice steps them all; the arithmetic is
:func:`dice_env.physics.kernel.simulate_one`'s in the same order, so the results are
bit-identical. It serves the runs :func:`covers` accepts (``docs/performance.md``).
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator

import numpy as np
from numba import njit, prange

from dice_env.physics.kernel import (
    ABORTED,
    DAMP,
    DECIDED,
    MU,
    NONFINITE,
    NX,
    NY,
    NZ,
    RUNNING,
    SERIES,
    SETTLED,
    STIFF,
    UP,
    Body,
    Contact,
    Dice,
    Options,
    Outcome,
    Stops,
    body_frame,
    face_up,
    relative_rise,
    rest_test,
    rodrigues,
    rotate,
    rotation_series,
)

TILE = 16  # dice per tile; a compile-time row stride, so LLVM can prove the lanes independent
X, U, L, W, Q = 0, 3, 6, 9, 12  # centre, velocity, angular momentum, angular velocity, Q (9)
STEP, STATUS, E_START, E_TOL, E_MAX, WAS, PEN, HITS, TURN = 21, 22, 23, 24, 25, 26, 27, 28, 29
QUIET, REST_T = 30, 31  # quiet steps so far; when the rest began
ROWS = 32
CHECK_EVERY = 64  # steps between checks whether every die of a tile has ended


_enabled = True


@contextlib.contextmanager
def disabled() -> Iterator[None]:
    """Within the block every run takes the scalar kernel (to compare the two)."""
    global _enabled
    was, _enabled = _enabled, False
    try:
        yield
    finally:
        _enabled = was


def covers(scene: object, batch: int, flight: bool, records: bool) -> bool:
    """Whether a run of ``batch`` dice in ``scene`` takes this kernel (else the scalar one).

    The paper's law, friction and step on one floor through the origin (no walls: the tile's
    step reads the floor alone), an isotropic rotating hexahedron, no free-flight jumps or
    records, a tile of dice at least; not inside :func:`disabled`.
    """
    return (_enabled and not scene.walls and scene.ground.offset == 0.0
            and scene.ground.contact_law.name == "PAPER"
            and scene.friction_law.name == "REGULARIZED" and scene.scheme.name == "PAPER"
            and scene.rotation and scene.die.is_isotropic and len(scene.die.vertices) == 8
            and len(scene.die.faces) == 6 and batch >= TILE and not flight and not records)


def stop_tests(stops: Stops) -> bool | None:
    """The kernel's ``tests``: True, or None (a loop compiled without stop tests) to the limit."""
    return True if stops.at_rest or stops.lock.max() > -np.inf else None


@njit(cache=True, inline="always")
def _max(a: float, b: float) -> float:
    """``max(a, b)`` as a select (numba's builtin is a call, which stops vectorisation)."""
    return b if b > a else a


@njit(cache=True, inline="always")
def _pick(values: tuple, index: int) -> float:
    """``values[index]`` as selects: a switch, or a load that may alias, stops vectorising."""
    picked = values[0]
    for k in range(1, len(values)):
        picked = values[k] if index == k else picked
    return picked


@njit(cache=True, inline="always")
def _corner(q, x, w, u, b0, b1, b2, ground):
    """One corner's force and torque under the paper's law, without branches (its books too)."""
    q00, q01, q02, q10, q11, q12, q20, q21, q22 = q
    x0, x1, x2 = x
    w0, w1, w2 = w
    u0, u1, u2 = u
    n0, n1, n2, stiff, damp, mu, vmin = ground
    rk0 = q00 * b0 + q01 * b1 + q02 * b2
    rk1 = q10 * b0 + q11 * b1 + q12 * b2
    rk2 = q20 * b0 + q21 * b1 + q22 * b2
    height = n0 * (x0 + rk0) + n1 * (x1 + rk1) + n2 * (x2 + rk2)
    uk0 = u0 + w1 * rk2 - w2 * rk1
    uk1 = u1 + w2 * rk0 - w0 * rk2
    uk2 = u2 + w0 * rk1 - w1 * rk0
    speed2 = uk0 * uk0 + uk1 * uk1 + uk2 * uk2
    dg = _max(0.0, -height)
    un = n0 * uk0 + n1 * uk1 + n2 * uk2
    below = height < 0.0
    spring = 0.5 * stiff * dg * dg if below else 0.0
    approach = -un if below else 0.0
    fn = stiff * dg
    if damp > 0.0:
        fn -= damp * un
    pushes = fn > 0.0
    fk0, fk1, fk2 = fn * n0, fn * n1, fn * n2
    if mu > 0.0:
        cap = mu * _max(fn, 0.0)
        ut0, ut1, ut2 = uk0 - un * n0, uk1 - un * n1, uk2 - un * n2
        scale = cap / (math.sqrt(ut0 * ut0 + ut1 * ut1 + ut2 * ut2) + vmin)
        fk0 -= scale * ut0
        fk1 -= scale * ut1
        fk2 -= scale * ut2
    if not pushes:
        fk0, fk1, fk2 = 0.0, 0.0, 0.0
    return (pushes, fk0, fk1, fk2, rk1 * fk2 - rk2 * fk1, rk2 * fk0 - rk0 * fk2,
            rk0 * fk1 - rk1 * fk0, spring, below, approach, dg, speed2)


@njit(cache=True, inline="always")
def _add(acc, corner):
    """Add a corner's share to the step's sums, in the corners' order (as the kernel does)."""
    f0, f1, f2, t0, t1, t2, spring, touching, approach, pen, fastest = acc
    pushes, fk0, fk1, fk2, tk0, tk1, tk2, spring_k, below, approach_k, dg, speed2 = corner
    fastest = _max(fastest, speed2)
    if below:
        touching += 1
        spring += spring_k
        pen = _max(pen, dg)
        approach = _max(approach, approach_k)
    if pushes:
        f0 += fk0
        f1 += fk1
        f2 += fk2
        t0 += tk0
        t1 += tk1
        t2 += tk2
    return f0, f1, f2, t0, t1, t2, spring, touching, approach, pen, fastest


@njit(cache=True, error_model="numpy")
def _tile_step(t: np.ndarray, body: Body, contact: Contact, options: Options, stops: Stops,
               tests: bool | None) -> None:
    """One step of every die of the tile ``t``; row ``TURN``: a turn too large for the series."""
    planes = contact.planes
    normal = (planes[0, NX], planes[0, NY], planes[0, NZ])
    stiff, damp, mu = planes[0, STIFF], planes[0, DAMP], planes[0, MU]
    vmin, g, dt, mass, inv_iso = contact.vmin, options.gravity, options.dt, body.mass, body.inv_iso
    stop_at_rest, v_rest, hold_steps = stops.at_rest, stops.v_rest, stops.hold_steps
    rest_energy, rest_excess, lock = stops.rest_energy, stops.rest_excess, stops.lock
    energy_scale_add = stops.energy_scale
    vertices = body.vertices
    n0, n1, n2 = normal[0], normal[1], normal[2]
    dt_m = dt / mass
    kinetic_rest = 0.5 * mass * v_rest * v_rest
    # the hexahedron's six faces (covers): outward normals and locks, in label order
    fn = body.faces
    faces = ((fn[0, 0], fn[0, 1], fn[0, 2]), (fn[1, 0], fn[1, 1], fn[1, 2]),
             (fn[2, 0], fn[2, 1], fn[2, 2]), (fn[3, 0], fn[3, 1], fn[3, 2]),
             (fn[4, 0], fn[4, 1], fn[4, 2]), (fn[5, 0], fn[5, 1], fn[5, 2]))
    locks = (lock[0], lock[1], lock[2], lock[3], lock[4], lock[5])
    lock_max = _max(_max(_max(locks[0], locks[1]), _max(locks[2], locks[3])),
                    _max(locks[4], locks[5]))
    reads_down, up = body.reads_down, UP
    b0 = (vertices[0, 0], vertices[0, 1], vertices[0, 2])
    b1 = (vertices[1, 0], vertices[1, 1], vertices[1, 2])
    b2 = (vertices[2, 0], vertices[2, 1], vertices[2, 2])
    b3 = (vertices[3, 0], vertices[3, 1], vertices[3, 2])
    b4 = (vertices[4, 0], vertices[4, 1], vertices[4, 2])
    b5 = (vertices[5, 0], vertices[5, 1], vertices[5, 2])
    b6 = (vertices[6, 0], vertices[6, 1], vertices[6, 2])
    b7 = (vertices[7, 0], vertices[7, 1], vertices[7, 2])
    ground = (n0, n1, n2, stiff, damp, mu, vmin)
    for i in range(TILE):
        x = (t[X * TILE + i], t[(X + 1) * TILE + i], t[(X + 2) * TILE + i])
        u = (t[U * TILE + i], t[(U + 1) * TILE + i], t[(U + 2) * TILE + i])
        w = (t[W * TILE + i], t[(W + 1) * TILE + i], t[(W + 2) * TILE + i])
        x0, x1, x2 = x
        u0, u1, u2 = u
        l0, l1, l2 = t[L * TILE + i], t[(L + 1) * TILE + i], t[(L + 2) * TILE + i]
        q = (t[Q * TILE + i], t[(Q + 1) * TILE + i], t[(Q + 2) * TILE + i],
             t[(Q + 3) * TILE + i], t[(Q + 4) * TILE + i], t[(Q + 5) * TILE + i],
             t[(Q + 6) * TILE + i], t[(Q + 7) * TILE + i], t[(Q + 8) * TILE + i])
        acc = (0.0, 0.0, -mass * g, 0.0, 0.0, 0.0, 0.0, 0, 0.0, t[PEN * TILE + i], 0.0)
        acc = _add(acc, _corner(q, x, w, u, b0[0], b0[1], b0[2], ground))
        acc = _add(acc, _corner(q, x, w, u, b1[0], b1[1], b1[2], ground))
        acc = _add(acc, _corner(q, x, w, u, b2[0], b2[1], b2[2], ground))
        acc = _add(acc, _corner(q, x, w, u, b3[0], b3[1], b3[2], ground))
        acc = _add(acc, _corner(q, x, w, u, b4[0], b4[1], b4[2], ground))
        acc = _add(acc, _corner(q, x, w, u, b5[0], b5[1], b5[2], ground))
        acc = _add(acc, _corner(q, x, w, u, b6[0], b6[1], b6[2], ground))
        acc = _add(acc, _corner(q, x, w, u, b7[0], b7[1], b7[2], ground))
        f0, f1, f2, t0, t1, t2, spring, touching, approach, pen, fastest = acc
        status = t[STATUS * TILE + i]
        alive = status == RUNNING
        step = t[STEP * TILE + i]
        # energy of the state entering this step
        kinetic = 0.5 * mass * (u0 * u0 + u1 * u1 + u2 * u2) + 0.5 * (
            l0 * (l0 * inv_iso) + l1 * (l1 * inv_iso) + l2 * (l2 * inv_iso))
        energy = kinetic + mass * g * x2 + spring
        e_start, e_tol, e_max = t[E_START * TILE + i], t[E_TOL * TILE + i], t[E_MAX * TILE + i]
        first = step == 0.0
        if first:
            e_start = energy
            e_tol = energy_scale_add + kinetic + mass * g * _max(0.0, n0 * x0 + n1 * x1 + n2 * x2)
        else:
            e_max = _max(e_max, energy)
        hits = t[HITS * TILE + i]
        if alive and touching > 0 and not t[WAS * TILE + i] > 0.0 and approach > v_rest:
            hits += 1.0
        end = RUNNING
        quiet, rest_t = t[QUIET * TILE + i], t[REST_T * TILE + i]
        if tests is not None:
            # the decided face and the rest, by the scalar kernel's tests (face_up, rest_test)
            up_body = body_frame(q, up[0], up[1], up[2])
            face_lock = _pick(locks, face_up(faces, reads_down, up_body))
            if energy < lock_max and energy < face_lock:
                end = DECIDED
            elif stop_at_rest:
                near_rest = kinetic < kinetic_rest  # (the scalar kernel's: stop_at_rest holds)
                # quiet: a whole number of steps, kept in a float (rest_test compiles for it)
                quiet, end = rest_test(
                    touching >= 3 and near_rest and fastest < v_rest * v_rest, quiet,
                    hold_steps, energy - rest_energy < rest_excess)
                if end == SETTLED:
                    rest_t = (step + 1.0 - quiet) * dt
        # 3.-4. centre of mass, then angular momentum, angular velocity and orientation
        nu0, nu1, nu2 = u0 + f0 * dt_m, u1 + f1 * dt_m, u2 + f2 * dt_m
        nx0, nx1, nx2 = x0 + dt * nu0, x1 + dt * nu1, x2 + dt * nu2
        nl0, nl1, nl2 = l0 + dt * t0, l1 + dt * t1, l2 + dt * t2
        total = nu0 + nu1 + nu2 + nx0 + nx1 + nx2 + nl0 + nl1 + nl2
        finite = total * 0.0 == 0.0  # (abs(x) < inf would block vectorising)
        moves = alive and end == RUNNING and finite
        nw0, nw1, nw2 = nl0 * inv_iso, nl1 * inv_iso, nl2 * inv_iso
        v0, v1, v2 = nw0 * dt, nw1 * dt, nw2 * dt
        turn = v0 * v0 + v1 * v1 + v2 * v2
        series = turn > 0.0 and turn < SERIES
        a, c = rotation_series(turn)
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = rodrigues(v0, v1, v2, turn, a, c)
        if not moves:  # a die that is done keeps its state (selects, not branches)
            nx0, nx1, nx2, nu0, nu1, nu2, nl0, nl1, nl2 = x0, x1, x2, u0, u1, u2, l0, l1, l2
            nw0, nw1, nw2 = w
        t[STEP * TILE + i] = step + 1.0 if moves else step
        t[X * TILE + i], t[(X + 1) * TILE + i], t[(X + 2) * TILE + i] = nx0, nx1, nx2
        t[U * TILE + i], t[(U + 1) * TILE + i], t[(U + 2) * TILE + i] = nu0, nu1, nu2
        t[L * TILE + i], t[(L + 1) * TILE + i], t[(L + 2) * TILE + i] = nl0, nl1, nl2
        t[W * TILE + i], t[(W + 1) * TILE + i], t[(W + 2) * TILE + i] = nw0, nw1, nw2
        rotates = moves and series
        for j in range(3):
            qa, qb, qc = q[j], q[3 + j], q[6 + j]
            t[(Q + j) * TILE + i] = r00 * qa + r01 * qb + r02 * qc if rotates else qa
            t[(Q + 3 + j) * TILE + i] = r10 * qa + r11 * qb + r12 * qc if rotates else qb
            t[(Q + 6 + j) * TILE + i] = r20 * qa + r21 * qb + r22 * qc if rotates else qc
        t[TURN * TILE + i] = turn if moves and turn >= SERIES else 0.0
        ended = end if end != RUNNING else (RUNNING if finite else NONFINITE)
        t[STATUS * TILE + i] = ended if alive else status
        if not alive:  # selects, not branches
            quiet, rest_t = t[QUIET * TILE + i], t[REST_T * TILE + i]
        t[QUIET * TILE + i], t[REST_T * TILE + i] = quiet, rest_t
        t[E_START * TILE + i], t[E_TOL * TILE + i], t[E_MAX * TILE + i] = e_start, e_tol, e_max
        t[HITS * TILE + i] = hits
        t[WAS * TILE + i] = 1.0 if touching > 0 else 0.0
        t[PEN * TILE + i] = pen


@njit(cache=True)
def _all_ended(t: np.ndarray, lanes: int) -> bool:
    """Whether every used lane of the tile has ended (time limit aside)."""
    for i in range(lanes):
        if t[STATUS * TILE + i] == RUNNING:
            return False
    return True


@njit(cache=True)
def _run_tile(first: int, last: int, dice: Dice, body: Body, contact: Contact, options: Options,
              stops: Stops, tests: bool | None, out: Outcome) -> None:
    """Dice ``first`` to ``last - 1`` (at most ``TILE``) for ``stops.n_steps`` steps, in place."""
    x, u, ang, q, w = dice
    t = np.zeros(ROWS * TILE)
    qi = np.empty((3, 3))
    lanes = last - first
    for i in range(TILE):
        d = first + i if i < lanes else first  # spare lanes repeat the first die, unused
        for a in range(3):
            t[(X + a) * TILE + i] = x[d, a]
            t[(U + a) * TILE + i] = u[d, a]
            t[(L + a) * TILE + i] = ang[d, a]
            t[(W + a) * TILE + i] = w[d, a]
            for c in range(3):
                t[(Q + 3 * a + c) * TILE + i] = q[d, a, c]
        t[E_TOL * TILE + i] = 1.0
        t[E_MAX * TILE + i] = -np.inf
        t[WAS * TILE + i] = 1.0
        t[PEN * TILE + i] = out.max_pen[d]
        t[HITS * TILE + i] = out.impacts[d]
    for step in range(stops.n_steps):
        if step % CHECK_EVERY == 0:
            if out.abort[0] != 0:
                for i in range(lanes):
                    if t[STATUS * TILE + i] == RUNNING:
                        t[STATUS * TILE + i] = ABORTED
                break
            if _all_ended(t, lanes):
                break
        _tile_step(t, body, contact, options, stops, tests)
        for i in range(TILE):  # the rare large turn, exactly as the scalar kernel does it
            if t[TURN * TILE + i] > 0.0:
                for a in range(3):
                    for c in range(3):
                        qi[a, c] = t[(Q + 3 * a + c) * TILE + i]
                rotate(qi, t[W * TILE + i], t[(W + 1) * TILE + i], t[(W + 2) * TILE + i],
                       options.dt)
                for a in range(3):
                    for c in range(3):
                        t[(Q + 3 * a + c) * TILE + i] = qi[a, c]
    for i in range(lanes):
        d = first + i
        for a in range(3):
            x[d, a] = t[(X + a) * TILE + i]
            u[d, a] = t[(U + a) * TILE + i]
            ang[d, a] = t[(L + a) * TILE + i]
            w[d, a] = t[(W + a) * TILE + i]
            for c in range(3):
                q[d, a, c] = t[(Q + 3 * a + c) * TILE + i]
        done = int(t[STEP * TILE + i])
        status = int(t[STATUS * TILE + i])
        out.status[d] = status
        out.unstable[d] = status == NONFINITE
        out.rest_time[d] = t[REST_T * TILE + i] if status == SETTLED else done * options.dt
        out.steps[d] = done
        out.max_pen[d] = t[PEN * TILE + i]
        out.impacts[d] = int(t[HITS * TILE + i])
        out.energy_rise[d] = max(out.energy_rise[d], relative_rise(
            t[E_MAX * TILE + i], t[E_START * TILE + i], t[E_TOL * TILE + i]))


@njit(cache=True, parallel=True, nogil=True)
def simulate_batch(dice: Dice, body: Body, contact: Contact, options: Options, stops: Stops,
                   tests: bool | None, out: Outcome) -> None:
    """:func:`dice_env.physics.kernel.simulate_batch` for :func:`covers`, :func:`stop_tests`'s."""
    n = dice.x.shape[0]
    for tile in prange((n + TILE - 1) // TILE):
        _run_tile(tile * TILE, min(n, (tile + 1) * TILE), dice, body, contact, options, stops,
                  tests, out)


@njit(cache=True, nogil=True)
def simulate_serial(dice: Dice, body: Body, contact: Contact, options: Options, stops: Stops,
                    tests: bool | None, out: Outcome) -> None:
    """:func:`simulate_batch` on the calling thread, with the same results."""
    n = dice.x.shape[0]
    for tile in range((n + TILE - 1) // TILE):
        _run_tile(tile * TILE, min(n, (tile + 1) * TILE), dice, body, contact, options, stops,
                  tests, out)

"""A linearly implicit contact step: is it accurate at several times the explicit step.

    NUMBA_NUM_THREADS=1 python benchmarks/implicit_contact.py            # N = 300 throws
    NUMBA_NUM_THREADS=1 python benchmarks/implicit_contact.py --quick    # N = 60 throws

A self-contained prototype of one die of the default scene (``Scene()``: gated penalty ground,
stick-slip friction) with a linearly implicit theta step. Per step, every corner below the
plane with a positive normal force ``fn = S dg - D un`` contributes a normal spring-damper and,
while it sticks, a tangential spring-damper (``kt, ct = 2/7 S, 2/7 D``) tied to where it
touched; a slipping corner (``|ft| > mu fn``) gets the explicit Coulomb force against its slip
velocity and its tie point follows it. With ``a = (d, r_k x d)`` for each spring direction
``d`` the generalized stiffness and damping are ``K = sum s a a^T``, ``C = sum c a a^T``, and
with ``M = diag(m, m, m, I, I, I)``, ``V = (u, w)``, ``F`` the current generalized force
(gravity included)::

    (M + theta dt C + theta^2 dt^2 K) dV = dt (F - theta dt K V)

which is the force evaluated at ``V_theta = V + theta dV`` and ``x + theta dt V_theta``. The
position and orientation then move with ``V_theta``: ``x += dt u_theta``,
``Q = R(w_theta dt) Q``; ``V += dV``. theta = 1 is backward Euler (``x += dt u_new``),
theta = 0.5 the trapezoidal rule (``x += dt (u + u_new) / 2``, the update that makes the
matrix above consistent; with ``x += dt u_new`` the theta = 0.5 matrix would not be a
second-order scheme).

Onset (an extra variant, not in the brief's two): a corner is felt only from the first step
that starts below the plane, so the step in which it crosses misses its force; with
``onset`` that missed impulse is added explicitly at the next step (see :func:`_advance`).

Written to ``benchmarks/results/implicit_contact.json`` (``--out``) and printed: validation
against the repo's simulator at ``scene.step / 4``, then the table: per
theta and step ``f * critical_dt``, flat-drop restitution at 1 m/s, gentle-throw face
agreement between ``dt`` and ``dt/4`` of the same scheme, agreement with the repo's explicit
simulator at its default step, mean steps (and contact steps) per throw, single-thread CPU
microseconds per throw, and the fractions settled and non-finite.
"""

from __future__ import annotations

import math
import time

import numpy as np
from harness import benchmark_parser, command_line, write_json
from numba import njit

from dice_env.model.defaults import rebound
from dice_env.model.scene import Scene
from dice_env.physics.kernel import rotate
from dice_env.provenance import code_version
from dice_env.simulation.calibration import measured_restitution
from dice_env.simulation.simulate import State, simulate
from dice_env.throws import RELEASES, T_THROW

FACTORS = (0.15, 0.3, 0.6, 1.2, 2.4, 4.8)
# (theta, onset): backward Euler and trapezoid as briefed, then each with the onset impulse
VARIANTS = ((1.0, False), (0.5, False), (1.0, True), (0.5, True))
REFINE = 4  # the same scheme at dt / REFINE is the reference for its own convergence


@njit(cache=False)
def _solve_spd6(a: np.ndarray, b: np.ndarray) -> None:
    """Solve ``a x = b`` for a symmetric positive definite 6x6 ``a``; ``a`` and ``b`` in place.

    Cholesky ``a = L L^T`` (L overwrites the lower triangle), then the two triangular solves;
    the solution is left in ``b``.
    """
    n = 6
    for j in range(n):
        s = a[j, j]
        for k in range(j):
            s -= a[j, k] * a[j, k]
        d = math.sqrt(s)
        a[j, j] = d
        for i in range(j + 1, n):
            s = a[i, j]
            for k in range(j):
                s -= a[i, k] * a[j, k]
            a[i, j] = s / d
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= a[i, k] * b[k]
        b[i] = s / a[i, i]
    for i in range(n - 1, -1, -1):
        s = b[i]
        for k in range(i + 1, n):
            s -= a[k, i] * b[k]
        b[i] = s / a[i, i]


@njit(cache=False)
def _add_spring(kmat: np.ndarray, cmat: np.ndarray, a: np.ndarray, r: np.ndarray,
                d: np.ndarray, s: float, c: float) -> None:
    """Add a spring ``s`` and damper ``c`` along ``d`` at offset ``r``: ``K += s a a^T``, ...

    ``a`` (6,) is scratch space; it is left holding ``(d, r x d)``.
    """
    a[0], a[1], a[2] = d[0], d[1], d[2]
    a[3] = r[1] * d[2] - r[2] * d[1]
    a[4] = r[2] * d[0] - r[0] * d[2]
    a[5] = r[0] * d[1] - r[1] * d[0]
    for i in range(6):
        si, ci = s * a[i], c * a[i]
        for j in range(6):
            kmat[i, j] += si * a[j]
            cmat[i, j] += ci * a[j]


@njit(cache=False)
def _advance(x, u, q, w, body, mass, inertia, stiff, damp, mu, kt, ct, g, dt, theta, onset,
             n_steps, stop_at_rest, v_rest, hold_steps, rec_z, rec_uz):
    """Run one die (``x, u, q, w`` updated in place) for ``n_steps`` or until rest.

    ``onset``: a corner that crossed the plane during the last step (which gave it no force)
    gets, once, the impulse it missed, ``phi dt (S dg / 2 - D un)`` with ``phi`` the fraction of
    that step it spent below the plane (explicit, added to ``F``).

    Records the centre's height and vertical velocity after each step into ``rec_z`` and
    ``rec_uz`` when they are not empty. Returns ``(steps, contact_steps, finite, settled)``.
    """
    ez = np.array([0.0, 0.0, 1.0])
    ex = np.array([1.0, 0.0, 0.0])
    ey = np.array([0.0, 1.0, 0.0])
    heights = np.full(8, -1.0)
    anchors = np.zeros((8, 3))
    tied = np.zeros(8, np.bool_)
    kmat = np.zeros((6, 6))
    cmat = np.zeros((6, 6))
    amat = np.zeros((6, 6))
    force = np.zeros(6)
    vel = np.zeros(6)
    r = np.zeros(3)
    scratch = np.zeros(6)
    minv = np.array([mass, mass, mass, inertia, inertia, inertia])
    kinetic_rest = 0.5 * mass * v_rest * v_rest
    record = rec_z.shape[0] > 0
    quiet = 0
    contact_steps = 0
    step = 0
    settled = False
    finite = True
    while step < n_steps:
        kmat[:, :] = 0.0
        cmat[:, :] = 0.0
        force[:] = 0.0
        force[2] = -mass * g
        kinetic = 0.5 * mass * (u[0] ** 2 + u[1] ** 2 + u[2] ** 2) + 0.5 * inertia * (
            w[0] ** 2 + w[1] ** 2 + w[2] ** 2)
        near_rest = stop_at_rest and kinetic < kinetic_rest
        fastest = 0.0
        touching = 0
        active = 0
        for k in range(8):
            for i in range(3):
                r[i] = q[i, 0] * body[k, 0] + q[i, 1] * body[k, 1] + q[i, 2] * body[k, 2]
            h = x[2] + r[2]
            before = heights[k]
            heights[k] = h
            uk0 = u[0] + w[1] * r[2] - w[2] * r[1]
            uk1 = u[1] + w[2] * r[0] - w[0] * r[2]
            uk2 = u[2] + w[0] * r[1] - w[1] * r[0]
            if near_rest:
                fastest = max(fastest, uk0 * uk0 + uk1 * uk1 + uk2 * uk2)
            if h >= 0.0:
                tied[k] = False
                continue
            touching += 1
            fn = -stiff * h - damp * uk2
            if fn <= 0.0:
                tied[k] = False
                continue
            active += 1
            _add_spring(kmat, cmat, scratch, r, ez, stiff, damp)
            f0, f1, f2 = 0.0, 0.0, fn
            if onset and before > 0.0:
                f2 += h / (h - before) * (-0.5 * stiff * h - damp * uk2)
            if mu > 0.0:
                cap = mu * fn
                p0, p1 = x[0] + r[0], x[1] + r[1]
                if not tied[k]:
                    # tied where it crossed the plane during the last step, if it did
                    tied[k] = True
                    back = dt * h / (before - h) if before > 0.0 else 0.0
                    anchors[k, 0] = p0 + back * uk0
                    anchors[k, 1] = p1 + back * uk1
                e0, e1 = p0 - anchors[k, 0], p1 - anchors[k, 1]
                ft0, ft1 = -kt * e0 - ct * uk0, -kt * e1 - ct * uk1
                size = math.sqrt(ft0 * ft0 + ft1 * ft1)
                if size > cap:
                    # slip (explicit): Coulomb's force against the slip velocity, or along the
                    # spring's pull while the corner is too slow for its direction to count
                    speed = math.sqrt(uk0 * uk0 + uk1 * uk1)
                    if speed > 4.0 * cap * dt / mass:
                        ft0, ft1 = -cap * uk0 / speed, -cap * uk1 / speed
                    else:
                        ft0, ft1 = cap * ft0 / size, cap * ft1 / size
                    anchors[k, 0], anchors[k, 1] = p0 + ft0 / kt, p1 + ft1 / kt
                else:
                    _add_spring(kmat, cmat, scratch, r, ex, kt, ct)
                    _add_spring(kmat, cmat, scratch, r, ey, kt, ct)
                f0, f1 = ft0, ft1
            force[0] += f0
            force[1] += f1
            force[2] += f2
            force[3] += r[1] * f2 - r[2] * f1
            force[4] += r[2] * f0 - r[0] * f2
            force[5] += r[0] * f1 - r[1] * f0
        if stop_at_rest:
            if touching >= 3 and near_rest and fastest < v_rest * v_rest:
                quiet += 1
                if quiet > hold_steps:
                    settled = True
                    break
            else:
                quiet = 0
        step += 1
        if touching > 0:
            contact_steps += 1
        for i in range(3):
            vel[i] = u[i]
            vel[i + 3] = w[i]
        # (M + th dt C + th^2 dt^2 K) dV = dt (F - th dt K V); force becomes dV
        td = theta * dt
        for i in range(6):
            if active > 0:
                kv = 0.0
                for j in range(6):
                    kv += kmat[i, j] * vel[j]
                    amat[i, j] = td * cmat[i, j] + td * td * kmat[i, j]
                force[i] = dt * (force[i] - td * kv)
                amat[i, i] += minv[i]
            else:
                force[i] *= dt / minv[i]
        if active > 0:
            _solve_spd6(amat, force)
        for i in range(3):
            x[i] += dt * (u[i] + theta * force[i])
        rotate(q, w[0] + theta * force[3], w[1] + theta * force[4], w[2] + theta * force[5],
                dt)
        for i in range(3):
            u[i] += force[i]
            w[i] += force[i + 3]
        if not math.isfinite(x[0] + x[1] + x[2] + u[0] + u[1] + u[2] + w[0] + w[1] + w[2]):
            finite = False
            break
        if record:
            rec_z[step - 1] = x[2]
            rec_uz[step - 1] = u[2]
    return step, contact_steps, finite, settled


@njit(cache=False)
def _run_batch(pos, vel, spin, orient, body, mass, inertia, stiff, damp, mu, kt, ct, g, dt,
               theta, onset, n_steps, v_rest, hold_steps, steps, contact, finite, settled):
    """Each throw of the batch to rest, serially; ``orient`` gets the final orientations."""
    empty = np.zeros(0)
    for b in range(pos.shape[0]):
        x, u, w = pos[b].copy(), vel[b].copy(), spin[b].copy()
        q = orient[b].copy()
        s, c, f, done = _advance(x, u, q, w, body, mass, inertia, stiff, damp, mu, kt, ct, g,
                                 dt, theta, onset, n_steps, True, v_rest, hold_steps, empty, empty)
        orient[b] = q
        steps[b], contact[b], finite[b], settled[b] = s, c, f, done


def _constants(scene: Scene) -> tuple:
    die, ground = scene.die, scene.ground
    if not die.is_fair or ground.normal != (0.0, 0.0, 1.0):
        raise ValueError("the prototype handles a fair die on a horizontal table only")
    return (np.ascontiguousarray(die.vertices_body), die.mass, float(die.inertia_body[0, 0]),
            ground.stiffness, ground.damping, ground.friction,
            ground.tangential * ground.stiffness, ground.tangential * ground.damping,
            scene.gravity)


def run_throws(scene: Scene, state: State, dt: float, theta: float, onset: bool = False,
               t_max: float = T_THROW) -> dict[str, np.ndarray | float]:
    """Throw every die of ``state`` to rest (or ``t_max``) with the implicit step.

    Returns ``face`` (the label :meth:`Die.face_read` reads), ``steps``, ``contact_steps``,
    ``finite``, ``settled`` per throw, and ``cpu_s`` (process CPU time of the whole batch).
    """
    b = state.batch_size
    orient = np.array(state.orientation)
    inertia = float(scene.die.inertia_body[0, 0])
    out = {"steps": np.zeros(b, np.int64), "contact_steps": np.zeros(b, np.int64),
           "finite": np.zeros(b, np.bool_), "settled": np.zeros(b, np.bool_)}
    start = time.process_time()
    _run_batch(np.array(state.position), np.array(state.velocity),
               np.array(state.angular_momentum) / inertia, orient, *_constants(scene), dt,
               theta, onset, max(1, round(t_max / dt)), scene.rest.speed,
               math.ceil(scene.rest.hold / dt), out["steps"], out["contact_steps"],
               out["finite"], out["settled"])
    out["cpu_s"] = time.process_time() - start
    out["face"] = scene.die.face_read(orient, np.array([0.0, 0.0, 1.0]))
    return out


def drop_restitution(scene: Scene, dt: float, theta: float, onset: bool = False,
                     speed: float = 1.0) -> float:
    """Restitution of a flat, spin-free landing at ``speed``, as ``measured_restitution``.

    The die starts 1 mm (at most) above the plane, falling so that it meets it at ``speed``;
    the result is the upward speed when the face crosses the plane again (gravity since
    leaving undone) over ``speed``; NaN if it does not leave within the span.
    """
    die, g = scene.die, scene.gravity
    height = float(die.resting_heights[0])  # lying on face 6, showing 1
    gap = min(1e-3, 0.25 * speed**2 / g)
    start = math.sqrt(speed**2 - 2.0 * g * gap)
    span = 10.0 * math.pi * math.sqrt(die.mass / (4.0 * scene.ground.stiffness))
    span += (speed - start) / g
    n_steps = max(40, round(span / dt))
    x, u = np.array([0.0, 0.0, height + gap]), np.array([0.0, 0.0, -start])
    q, w = np.eye(3), np.zeros(3)
    rec_z, rec_uz = np.zeros(n_steps), np.zeros(n_steps)
    _advance(x, u, q, w, *_constants(scene), dt, theta, onset, n_steps, False, 0.0, 0, rec_z,
             rec_uz)
    e = rebound(rec_z, rec_uz, height, g, speed)
    return math.nan if e is None else e


def _warm_up(scene: Scene) -> None:
    """Compile the kernels before anything is timed."""
    one = State.release(scene, np.array([0.0, 0.0, 0.02]), np.zeros(3))
    run_throws(scene, one, scene.critical_dt, 1.0, t_max=0.05)
    drop_restitution(scene, scene.critical_dt, 1.0)


def main() -> None:
    parser = benchmark_parser(__doc__, "implicit_contact", "60 throws instead of 300")
    parser.add_argument("-n", type=int, default=None, help="number of gentle throws")
    args = parser.parse_args()
    n = args.n or (60 if args.quick else 300)
    scene = Scene()
    crit = scene.critical_dt
    gentle = RELEASES[0].sample(scene, n, np.random.default_rng(5))
    wall = time.perf_counter()
    _warm_up(scene)

    start = time.process_time()
    ref = simulate(scene.with_(t_max=T_THROW), gentle, num_threads=1)
    ref_cpu = time.process_time() - start
    fine_ref = simulate(scene.with_(t_max=T_THROW, dt=scene.step / REFINE), gentle,
                        num_threads=1)
    print(f"Scene(): critical_dt = {crit:.4g} s, default step = {scene.step:.4g} s "
          f"(safety {scene.safety}); {n} gentle throws (RELEASES[0], rng 5), t_max = {T_THROW} s")
    print(f"repo explicit: restitution {measured_restitution(scene):.4f} at its step, "
          f"{measured_restitution(scene.with_(dt=scene.step / REFINE)):.4f} at step/{REFINE}; "
          f"faces at step vs step/{REFINE}: {np.mean(ref.face == fine_ref.face):.1%}; "
          f"{ref.steps.mean():.0f} steps and {1e6 * ref_cpu / n:.0f} us per throw "
          f"(with its free-flight jumps), settled {ref.settled.mean():.1%}")
    report = {"command": command_line(), "commit": code_version(), "throws": n,
              "critical_dt_s": crit,
              "default_safety": scene.safety, "timer": "process CPU time, one thread",
              "explicit_restitution_1mps": measured_restitution(scene),
              "validation": [], "rows": []}

    # every step f * crit and f * crit / REFINE, once per variant
    factors = sorted({*FACTORS, *(f / REFINE for f in FACTORS)})
    runs: dict[tuple[float, bool, float], dict] = {}
    for theta, onset in VARIANTS:
        for f in factors:
            runs[theta, onset, f] = run_throws(scene, gentle, f * crit, theta, onset)

    print(f"\nvalidation at dt = scene.step/{REFINE} = {scene.step / REFINE:.4g} s:")
    for theta, onset in VARIANTS:
        run = runs[theta, onset, scene.safety / REFINE]
        e = drop_restitution(scene, scene.step / REFINE, theta, onset)
        report["validation"].append({
            "theta": theta, "onset": onset, "restitution_1mps": e,
            "faces_vs_explicit": float(np.mean(run["face"] == ref.face)),
            "faces_vs_explicit_refined": float(np.mean(run["face"] == fine_ref.face))})
        print(f"  theta {theta}{' + onset' if onset else ''}: restitution {e:.4f} (repo 0.447); "
              f"faces vs repo explicit at its step {np.mean(run['face'] == ref.face):.1%}, "
              f"vs repo explicit at step/{REFINE} {np.mean(run['face'] == fine_ref.face):.1%}")

    head = (f"{'theta':>5} {'onset':>5} {'f':>5} {'dt (s)':>9} {'restit':>7} {'dt~dt/4':>8} "
            f"{'vs expl':>8} {'steps':>8} {'contact':>8} {'us/throw':>9} {'settled':>8} "
            f"{'nonfin':>7}")
    print("\nf: dt = f * critical_dt; restit: flat drop at 1 m/s (repo 0.447); dt~dt/4: same "
          "face at dt and dt/4, same scheme;\nvs expl: same face as the repo's explicit "
          "simulator at its default step; steps, contact: mean per throw (all steps / steps "
          "with a corner below the plane, no flight jumps); us/throw: single-thread CPU;\n"
          "expl.: the repo's explicit simulator (free-flight jumps, its own rest test), same "
          "throws")
    print(head)
    print("-" * len(head))
    for theta, onset in VARIANTS:
        for f in FACTORS:
            run, fine = runs[theta, onset, f], runs[theta, onset, f / REFINE]
            e = drop_restitution(scene, f * crit, theta, onset)
            report["rows"].append({
                "scheme": f"theta {theta:g}" + (" + onset" if onset else ""), "safety": f,
                "restitution_1mps": e,
                "faces_dt_vs_dt4": float(np.mean(run["face"] == fine["face"])),
                "faces_vs_explicit": float(np.mean(run["face"] == ref.face)),
                "us_per_throw": 1e6 * run["cpu_s"] / n, "settled": float(run["settled"].mean()),
                "nonfinite": float(1.0 - run["finite"].mean())})
            print(f"{theta:5.2f} {'yes' if onset else 'no':>5} {f:5.2f} {f * crit:9.3g} {e:7.4f} "
                  f"{np.mean(run['face'] == fine['face']):8.1%} "
                  f"{np.mean(run['face'] == ref.face):8.1%} {run['steps'].mean():8.0f} "
                  f"{run['contact_steps'].mean():8.0f} {1e6 * run['cpu_s'] / n:9.0f} "
                  f"{run['settled'].mean():8.1%} {1.0 - run['finite'].mean():7.1%}")
    # the repo's explicit scheme on the same throws, for the steps it can take
    for f in FACTORS:
        if f > 1.0:
            print(f"expl. {'-':>5} {f:5.2f} {f * crit:9.3g}  (above the critical step)")
            report["rows"].append({"scheme": "explicit", "safety": f, "stable": False})
            continue
        coarse = scene.with_(safety=f, t_max=T_THROW)
        start = time.process_time()
        run = simulate(coarse, gentle, num_threads=1)
        cpu = time.process_time() - start
        fine = simulate(coarse.with_(dt=coarse.step / REFINE), gentle, num_threads=1)
        report["rows"].append({
            "scheme": "explicit", "safety": f, "stable": True,
            "restitution_1mps": measured_restitution(coarse),
            "faces_dt_vs_dt4": float(np.mean(run.face == fine.face)),
            "faces_vs_explicit": float(np.mean(run.face == ref.face)),
            "us_per_throw": 1e6 * cpu / n, "settled": float(run.settled.mean()),
            "unstable": float(run.unstable.mean())})
        print(f"expl. {'-':>5} {f:5.2f} {coarse.step:9.3g} {measured_restitution(coarse):7.4f} "
              f"{np.mean(run.face == fine.face):8.1%} {np.mean(run.face == ref.face):8.1%} "
              f"{run.steps.mean():8.0f} {'-':>8} {1e6 * cpu / n:9.0f} "
              f"{run.settled.mean():8.1%} {run.unstable.mean():7.1%}")
    print(f"\nwall time {time.perf_counter() - wall:.0f} s")
    write_json(args.out, report, indent=1)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()

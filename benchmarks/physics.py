"""Speed of the simulator: kernel, throws to rest, the numpy listing and MuJoCo, in one run.

    python benchmarks/physics.py            # full run, a few minutes on 2 cores
    python benchmarks/physics.py --quick    # smaller sizes, no cold compile, under a minute

Prints a table and writes ``benchmarks/results/physics.json`` (``--out`` to change). Figures:

- kernel die-steps/s in the paper scene (``real_throw_cube`` defaults, dt = 1e-4, no records,
  no stop at rest), batch 1 (scalar kernel) and 1024 (vectorised kernel), 1 and 2 threads,
  the batch through the scalar kernel beside it, and the numpy transcription of the listing
  (``tests/listing_transcription.py``) on the same throw, with the ratios;
- compile time: a fresh process with an empty numba cache (cold) and with the cache (warm),
  each ``import dice_env`` plus a first single throw plus a first batch on 2 threads;
- settled throws/s in the default scene (``Scene()``: whatever the default table is) from a
  seeded set of hand throws (5–15 cm up, 0.5–1 m/s, spin up to 30 rad/s, uniform orientation),
  single throws and batches of 1024, 1 and 2 threads, with plain stepping beside for reference;
  and the same throws ended when their face is decided (``until="decided"``: the face they
  come to rest on, checked here against the runs to rest);
- MuJoCo (optional ``bench`` extra): a free box of the same size, mass and inertia, friction
  ``mu``, thrown from the same states onto a plane at its default 2 ms step, run until the same
  rest rule holds, and until the same decided-face rule holds (its kinetic and potential energy
  below :func:`dice_env.simulation.simulate.lock_energy`), each timed as one ``mj_step(nstep=...)``
  call per throw, with ratios (our decided throws against its decided throws);
- cost against batch size and against simulated time;
- per shape: throws/s to a decided face on 2 threads for each standard die
  (``Die.standard``) on the default table, from the same kind of hand throws, with what the
  die's vertex count and step explain of the cost.

Best of three repeats (MuJoCo's included; one with ``--quick``). One-thread figures are the
process's CPU time (not inflated by other processes on shared cores), two-thread figures
wall-clock time; the machine's load average is recorded beside them, and the printed table
is kept in the JSON too (``table``). ``step_budget`` shows where a throw's steps go and the floor
the contact steps set, at the scalar step's cost and at the vectorised paper step's.
"""

from __future__ import annotations

import contextlib
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np
from harness import benchmark_parser, parse_with_mujoco, timed, write_json

from dice_env import Scene, State, simulate
from dice_env.model.die import STANDARD_SIZES, Die
from dice_env.model.rotations import quaternion_to_matrix, random_rotations
from dice_env.physics import vector_kernel
from dice_env.provenance import code_version
from dice_env.simulation.calibration import table_scene
from dice_env.simulation.paper import paper_scene
from dice_env.simulation.simulate import lock_energy
from dice_env.throws import random_directions

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from listing_transcription import real_throw_cube as listing_throw  # noqa: E402


def best_time(fn, repeats: int, threads: int = 1) -> float:
    """Smallest time of ``repeats`` calls of ``fn`` (s); see :func:`timed`."""
    return timed(fn, repeats, threads)[0]


def paper_throws(n: int, seed: int = 0) -> State:
    """The paper's throw, x0 = (0, 0, 3), u0 = (5, 0, 5), L0 = rand*0.75 + 1e-6, no initial ω."""
    rng = np.random.default_rng(seed)
    return State(position=np.tile([0.0, 0.0, 3.0], (n, 1)), velocity=np.tile([5.0, 0, 5], (n, 1)),
                 angular_momentum=rng.random((n, 3)) * 0.75 + 1e-6,
                 orientation=np.tile(np.eye(3), (n, 1, 1)), angular_velocity=np.zeros((n, 3)))


def hand_throws(scene: Scene, n: int, seed: int = 0) -> State:
    """Seeded hand throws: 5–15 cm up, 0.5–1 m/s, spin up to 30 rad/s, uniform orientation."""
    rng = np.random.default_rng(seed)
    position = np.column_stack([np.zeros((n, 2)), rng.uniform(0.05, 0.15, n)])
    velocity = random_directions(rng, n) * rng.uniform(0.5, 1.0, (n, 1))
    spin = random_directions(rng, n) * rng.uniform(0.0, 30.0, (n, 1))
    return State.release(scene, position, velocity, spin, random_rotations(rng, n))


def subset(state: State, rows: slice) -> State:
    return State(*(a[rows] for a in state._arrays()))


def kernel_speed(quick: bool) -> dict:
    """Die-steps/s in the paper scene, and the numpy listing on the same throw.

    A batch runs in the vectorised kernel (:mod:`dice_env.physics.vector_kernel`); the same batch in
    the scalar kernel is measured beside it.
    """
    out = {}
    runs = [(1, 1, 2.0 if quick else 10.0, False), (1024, 1, 0.05 if quick else 0.3, False),
            (1024, 2, 0.05 if quick else 0.3, False), (1024, 2, 0.05 if quick else 0.3, True)]
    for batch, threads, t_max, scalar in runs:
        scene = paper_scene().with_(t_max=t_max)
        start = paper_throws(batch)
        with vector_kernel.disabled() if scalar else contextlib.nullcontext():
            simulate(scene, start, t_max=1e-3, until="t_max", record=(),
                     num_threads=threads)  # load
            elapsed = best_time(lambda s=scene, st=start, th=threads: simulate(
                s, st, until="t_max", record=(), num_threads=th), 2 if quick else 3,
                threads)
        name = f"batch{batch}_threads{threads}" + ("_scalar_kernel" if scalar else "")
        out[name] = batch * scene.n_steps / elapsed
    steps = 300 if quick else 3000
    l0 = paper_throws(1).angular_momentum[0]
    elapsed = best_time(lambda: listing_throw(l0, clockmax=steps, tmax=steps * 1e-4), 2)
    out["numpy_listing"] = steps / elapsed
    out["ratio_batch1_vs_numpy"] = out["batch1_threads1"] / out["numpy_listing"]
    out["ratio_batch1024_2threads_vs_numpy"] = out["batch1024_threads2"] / out["numpy_listing"]
    out["ratio_vectorised_vs_scalar_kernel"] = (out["batch1024_threads2"]
                                                / out["batch1024_threads2_scalar_kernel"])
    return out


_START_SCRIPT = """
import time
t0 = time.perf_counter()
import numpy as np
from dice_env import Scene, State
from dice_env import simulate
from dice_env.physics import vector_kernel
t1 = time.perf_counter()
scene = Scene()
simulate(scene, State.release(scene, [0, 0, 0.1], [0.5, 0, 0], [10.0, 5, 0]), num_threads=1)
t2 = time.perf_counter()
simulate(scene, State.release(scene, np.tile([0, 0, 0.1], (4, 1)), [0.5, 0, 0]), num_threads=2)
t3 = time.perf_counter()
print(t1 - t0, t2 - t1, t3 - t2)
"""


def start_times(cold: bool) -> dict:
    """Import and first throws in fresh processes: empty numba cache (cold), then warm.

    Without ``cold`` only the warm start, with the project's own cache.
    """
    out = {}
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache} if cold else dict(os.environ)
        for label in ("cold", "warm") if cold else ("warm",):
            line = subprocess.run([sys.executable, "-c", _START_SCRIPT], env=env, check=True,
                                  capture_output=True, text=True, cwd=ROOT).stdout.split()
            imp, first, batch = (float(v) for v in line)
            out[label] = {"import_s": imp, "first_throw_s": first, "first_batch_2threads_s": batch,
                          "import_and_first_throw_s": imp + first}
    return out


# How the throws are run: simulate() keywords. All but the last run to rest; the last ends
# each throw when its face is decided (the same face, not at rest).
MODES = {"plain stepping": {"free_flight": False}, "free flight": {},
         "free flight + early rest": {"until": "early_rest"},
         "free flight + decided face": {"until": "decided"}}
FASTEST = "free flight + early rest"
DECIDED = "free flight + decided face"


def throws_to_rest(scene: Scene, quick: bool) -> tuple[dict, State]:
    """Throws/s in ``scene`` for each of :data:`MODES`; also returns the throws.

    For the decided mode also the fraction of throws whose decided face is the face at rest.
    """
    n = 256 if quick else 1024
    start = hand_throws(scene, n, seed=1)
    simulate(scene, subset(start, slice(0, 2)), t_max=1e-3, num_threads=2)  # load the kernels
    simulate(scene, subset(start, slice(0, 1)), t_max=1e-3)
    out = {"scene": {"edge_m": scene.die.size, "mass_kg": scene.die.mass,
                     "stiffness": scene.ground.stiffness, "damping": scene.ground.damping,
                     "friction": scene.ground.friction, "dt_s": scene.step,
                     "t_max_s": scene.t_max, "rest_speed": scene.rest.speed,
                     "rest_hold_s": scene.rest.hold}, "modes": {}}
    repeats = 1 if quick else 3
    faces = {}
    for mode, kwargs in MODES.items():
        plain = mode == "plain stepping"
        size = n // 8 if plain else n
        batch = subset(start, slice(0, size))
        row = {"batch": size}
        for threads in (1, 2):
            elapsed, res = timed(lambda th=threads, kw=kwargs, b=batch: simulate(
                scene, b, num_threads=th, **kw), repeats, threads)
            row[f"batch_threads{threads}"] = size / elapsed
        singles = (16 if plain else 64) if quick else (32 if plain else 256)
        elapsed = best_time(lambda kw=kwargs, m=singles: [
            simulate(scene, subset(start, slice(k, k + 1)), **kw) for k in range(m)], repeats)
        row.update({"single_throws_per_s": singles / elapsed,
                    "single_throw_ms": 1e3 * elapsed / singles,
                    "settled_fraction": float(res.settled.mean()),
                    "decided_fraction": float(res.decided.mean()),
                    "mean_rest_time_s": float(res.rest_time.mean()),
                    "mean_steps": float(res.steps.mean()),
                    "mean_impacts": float(res.impacts.mean()),
                    "face_counts": np.bincount(res.face, minlength=7)[1:].tolist()})
        out["modes"][mode] = row
        faces[mode] = res.face
    out["modes"][DECIDED]["same_face_as_at_rest"] = float(np.mean(faces[DECIDED]
                                                                 == faces[FASTEST]))
    return out, start


_MJCF = """
<mujoco>
  <option timestep="{dt}" gravity="0 0 -{g}"/>
  <worldbody>
    <geom type="plane" size="1 1 0.1" friction="{mu} 0.005 0.0001"/>
    <body name="die">
      <freejoint/>
      <geom type="box" size="{h} {h} {h}" friction="{mu} 0.005 0.0001"/>
      <inertial pos="0 0 0" mass="{m}" diaginertia="{i} {i} {i}"/>
    </body>
  </worldbody>
</mujoco>
"""


def mujoco_model(scene: Scene, dt: float = 0.002, contact: str = ""):
    """MuJoCo's model of the scene's die on a plane: a free box on a plane.

    ``contact`` (geom attributes such as ``solref``) is set on both geoms, so that MuJoCo's
    mixing of the two geoms' parameters keeps it.
    """
    import mujoco

    die = scene.die
    xml = _MJCF.format(dt=dt, g=scene.gravity, mu=scene.ground.friction, h=die.size / 2,
                       m=die.mass, i=die.inertia_body[0, 0])
    return mujoco.MjModel.from_xml_string(xml.replace("<geom ", f"<geom {contact} "))


def mujoco_to_rest(scene: Scene, start: State, horizon: float, model=None) -> dict:
    """MuJoCo on the same die and throws: steps until the scene's rest rule holds, CPU time.

    ``model`` defaults to :func:`mujoco_model` at MuJoCo's default step and contact.
    """
    import mujoco
    from mujoco import rollout

    die = scene.die
    model = mujoco_model(scene) if model is None else model
    data = mujoco.MjData(model)
    dt = model.opt.timestep
    inertia = die.inertia_body[0, 0]
    n = start.batch_size
    quat = np.zeros((n, 4))
    for k in range(n):
        mujoco.mju_mat2Quat(quat[k], start.orientation[k].ravel())
    spin_body = np.einsum("bji,bj->bi", start.orientation, start.angular_velocity)
    qpos = np.hstack([start.position, quat])
    qvel = np.hstack([start.velocity, spin_body])
    size = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    initial = np.zeros((n, size))
    for k in range(n):
        mujoco.mj_resetData(model, data)
        data.qpos[:], data.qvel[:] = qpos[k], qvel[k]
        mujoco.mj_getState(model, data, initial[k], mujoco.mjtState.mjSTATE_FULLPHYSICS)
    n_steps = round(horizon / dt)
    hold = int(np.ceil(scene.rest.hold / dt))
    v_rest = scene.rest.speed
    rest_steps = np.full(n, n_steps)
    decided_steps = np.full(n, n_steps)
    face = np.zeros(n, np.int64)
    decided_face = np.zeros(n, np.int64)
    lock = lock_energy(scene)
    per_rollout = int(np.clip(2_000_000 // n_steps, 1, 32))  # about 1 GB of states
    for chunk in range(0, n, per_rollout):  # rest steps and faces from rollouts of throws
        rows = slice(chunk, chunk + per_rollout)
        states, _ = rollout.rollout(model, data, initial[rows], nstep=n_steps)
        vel, w_body = states[..., 8:11], states[..., 11:14]
        rot = quaternion_to_matrix(states[..., 4:8])
        corners = np.einsum("btij,cj->btci", rot, die.vertices_body)
        omega = np.einsum("btij,btj->bti", rot, w_body)
        speed = np.linalg.norm(vel[:, :, None] + np.cross(omega[:, :, None], corners),
                               axis=-1).max(axis=-1)
        kinetic = 0.5 * die.mass * (vel**2).sum(-1) + 0.5 * inertia * (w_body**2).sum(-1)
        lowest = (states[..., 3, None] + corners[..., 2]).min(axis=-1)
        quiet = (lowest < 1e-3) & (speed < v_rest) & (kinetic < 0.5 * die.mass * v_rest**2)
        for k in range(quiet.shape[0]):
            run = 0
            for j in range(n_steps):
                run = run + 1 if quiet[k, j] else 0
                if run > hold:
                    rest_steps[chunk + k] = j + 1
                    break
        up = np.array([0.0, 0.0, 1.0])
        last = rot[np.arange(quiet.shape[0]), rest_steps[rows] - 1]
        face[rows] = die.face_read(last, up)
        # the same decision rule as ours, on MuJoCo's kinetic and potential energy
        energy = kinetic + die.mass * scene.gravity * states[..., 3]
        below = energy < lock[die.face_read(rot, up) - 1]
        first = np.where(below.any(axis=1), below.argmax(axis=1) + 1, n_steps)
        decided_steps[rows] = first
        decided_face[rows] = die.face_read(rot[np.arange(quiet.shape[0]), first - 1], up)
    settled = rest_steps < n_steps

    def cpu_time(steps: np.ndarray) -> float:
        """CPU time of exactly ``steps[k]`` steps of each throw, one C call per throw."""
        elapsed = 0.0
        for k in range(n):
            mujoco.mj_resetData(model, data)
            data.qpos[:], data.qvel[:] = qpos[k], qvel[k]
            begin = time.thread_time()
            mujoco.mj_step(model, data, nstep=int(steps[k]))
            elapsed += time.thread_time() - begin
        return elapsed

    repeats = 3  # best of, as for our own figures
    elapsed = min(cpu_time(rest_steps) for _ in range(repeats))
    decided_elapsed = min(cpu_time(decided_steps) for _ in range(repeats))
    return {"version": mujoco.__version__, "timestep_s": dt, "throws": n,
            "settled_fraction": float(settled.mean()),
            "mean_rest_time_s": float(((rest_steps - hold) * dt)[settled].mean()),
            "mean_steps": float(rest_steps.mean()),
            "cpu_per_throw_ms": 1e3 * elapsed / n, "throws_per_s_1thread": n / elapsed,
            "face_counts": np.bincount(face, minlength=7)[1:].tolist(),
            "decided": {"fraction": float((decided_steps < n_steps).mean()),
                        "mean_time_s": float(decided_steps.mean() * dt),
                        "same_face_as_at_rest": float(np.mean(decided_face == face)),
                        "cpu_per_throw_ms": 1e3 * decided_elapsed / n,
                        "throws_per_s_1thread": n / decided_elapsed}}


def step_budget(scene: Scene, start: State, quick: bool, vector_rate: float) -> dict:
    """Where the steps of a throw go, and the cost floor they set for the explicit scheme.

    From a plain-stepped record of some throws: steps with every corner above the table (what
    free flight skips), steps in contact before the rest begins, and the hold. The floor is the
    contact steps at the measured cost of a contact step (a die resting on the table); the
    vectorised floor puts them at the cost of a step of the vectorised paper kernel on one
    thread (``vector_rate`` die-steps/s), the cheapest die-step measured here: the paper law's
    corner work (one square root and one division a corner) without the default table's
    stick-slip and midpoint work.
    """
    n = 8 if quick else 32
    t_max = min(scene.t_max, 1.5)  # the records take memory; most throws rest by 1 s
    flight, contact, hold = [], [], []
    for chunk in range(0, n, 4):
        batch = subset(start, slice(chunk, chunk + 4))
        res = simulate(scene, batch, t_max=t_max, record_every=1, record=("orientations",),
                       free_flight=False, num_threads=2)
        corners = np.einsum("btij,cj->btci", res.orientations, scene.die.vertices_body)
        height = (res.x_cm[:, :, None, :] + corners) @ np.asarray(scene.ground.normal)
        for k in range(batch.batch_size):
            rest = round(res.rest_time[k] / scene.step)
            free = (height[k, :rest].min(axis=-1) >= 0).sum()
            flight.append(free)
            contact.append(rest - free)
            hold.append(res.steps[k] - rest)
    resting = State.release(scene, [0, 0, scene.die.resting_heights[0]], [0, 0, 0])
    resting = subset(resting, np.zeros(64, int))
    steps = round(0.2 / scene.step)
    elapsed = best_time(lambda: simulate(scene, resting, t_max=0.2, until="t_max",
                                         num_threads=1), 2)
    ns_contact = 1e9 * elapsed / (64 * steps)
    floor = float(np.mean(contact)) * ns_contact * 1e-9
    vector_floor = float(np.mean(contact)) / vector_rate
    return {"throws": n, "mean_flight_steps": float(np.mean(flight)),
            "mean_contact_steps_before_rest": float(np.mean(contact)),
            "mean_hold_steps": float(np.mean(hold)), "ns_per_contact_step_1thread": ns_contact,
            "floor_ms_per_throw": 1e3 * floor, "ceiling_throws_per_s_per_core": 1.0 / floor,
            "ns_per_vectorised_paper_step_1thread": 1e9 / vector_rate,
            "vectorised_floor_ms_per_throw": 1e3 * vector_floor,
            "vectorised_ceiling_throws_per_s_2cores": 2.0 / vector_floor}


def batch_scaling(scene: Scene, start: State, quick: bool) -> dict:
    """Settled throws/s against batch size, 2 threads, the fastest mode.

    Batches smaller than the set of throws run one after the other over all of it, so every
    size does the same throws.
    """
    out = {}
    n = start.batch_size
    for size in (1, 16, 256, 1024) if quick else (1, 16, 64, 256, 1024, 4096):
        if size > n:
            batches = [hand_throws(scene, size, seed=2)]
        else:
            batches = [subset(start, slice(k, k + size)) for k in range(0, n, size)]
        total = sum(b.batch_size for b in batches)
        out[size] = total / best_time(lambda bs=batches: [simulate(
            scene, b, num_threads=2, **MODES[FASTEST]) for b in bs], 1, threads=2)
    return out


def time_scaling(scene: Scene, start: State, quick: bool) -> dict:
    """CPU time per throw against simulated time (1 thread, no stop at rest)."""
    batch = subset(start, slice(0, 64 if quick else 256))
    plain_batch = subset(start, slice(0, 16))
    out = {}
    for t_max in (0.1, 0.25, 0.5, 1.0, 2.0, 4.0):
        elapsed = best_time(lambda t=t_max: simulate(scene, batch, t_max=t, until="t_max",
                                                     num_threads=1), 1)
        plain = best_time(lambda t=t_max: simulate(scene, plain_batch, t_max=t,
                                                   until="t_max", num_threads=1,
                                                   free_flight=False), 1)
        out[t_max] = {"ms_per_throw": 1e3 * elapsed / batch.batch_size,
                      "ms_per_throw_plain": 1e3 * plain / plain_batch.batch_size}
    return out


def per_shape(quick: bool) -> dict:
    """Throws/s to a decided face on 2 threads for every standard die on the default table.

    Seeded :func:`hand_throws` (a batch of 256, 64 with ``quick``), best of two (one with
    ``quick``), wall clock. ``explained`` is the die's vertices times its simulated steps to
    the decision (time / step), relative to the d6's; ``cost`` its time per throw relative to
    the d6's: a ratio near 1 means the vertex count and step explain the cost.
    """
    n = 64 if quick else 256
    out = {}
    for name in STANDARD_SIZES:
        scene = Scene(die=Die.standard(name))
        start = hand_throws(scene, n, seed=3)
        simulate(scene, subset(start, slice(0, 2)), t_max=1e-3, num_threads=2)  # load
        elapsed, res = timed(lambda s=scene, st=start: simulate(
            s, st, num_threads=2, until="decided"), 1 if quick else 2, threads=2)
        time_to_face = float(res.rest_time.mean())
        out[name] = {"vertices": len(scene.die.vertices), "faces": scene.die.n_faces,
                     "dt_s": scene.step, "throws": n, "throws_per_s_2threads": n / elapsed,
                     "decided_fraction": float(res.decided.mean()),
                     "mean_time_to_face_s": time_to_face,
                     "vertex_steps": len(scene.die.vertices) * time_to_face / scene.step}
    d6 = out["d6"]
    for row in out.values():
        row["cost_vs_d6"] = d6["throws_per_s_2threads"] / row["throws_per_s_2threads"]
        row["explained_vs_d6"] = row["vertex_steps"] / d6["vertex_steps"]
    return out


def scenes() -> dict[str, Scene]:
    """The default scene, and the realistic table of the calibration if it differs."""
    out = {"Scene()": Scene()}
    if table_scene() != out["Scene()"]:
        out["table_scene()"] = table_scene()
    return out


def main() -> None:
    parser = benchmark_parser(__doc__, "physics",
                              "small sizes and no cold compile: well under a minute")
    parser.add_argument("--per-shape", action="store_true",
                        help="only the per-shape figures, updated in the existing JSON")
    args = parse_with_mujoco(parser)
    if args.per_shape:
        report = json.loads(args.out.read_text()) if args.out.exists() else {}
        report["per_shape_decided"] = {"command": "python benchmarks/physics.py --per-shape",
                                       "load_average": os.getloadavg(),
                                       "dice": per_shape(args.quick)}
        if "table" in report:
            report["table"] = format_report(report)
        write_json(args.out, report)
        print(json.dumps(report["per_shape_decided"], indent=1))
        return
    report = {"command": "python benchmarks/physics.py" + (" --quick" if args.quick else ""),
              "commit": code_version(),
              "machine": {"cpu": _cpu_name(), "cores": os.cpu_count(),
                          "python": platform.python_version(), "numba": numba.__version__,
                          "numpy": np.__version__, "load_average_start": os.getloadavg()}}
    report["start"] = start_times(cold=not args.quick)
    report["paper_scene_die_steps_per_s"] = kernel_speed(args.quick)
    report["throws_to_rest"] = {}
    for name, scene in scenes().items():
        rest, start = throws_to_rest(scene, args.quick)
        report["throws_to_rest"][name] = rest
        rest["step_budget"] = step_budget(
            scene, start, args.quick, report["paper_scene_die_steps_per_s"]["batch1024_threads1"])
        if name == "Scene()":
            report["throws_per_s_vs_batch_2threads"] = batch_scaling(scene, start, args.quick)
            report["cost_vs_simulated_time"] = time_scaling(scene, start, args.quick)
        if not args.no_mujoco:
            mj = mujoco_to_rest(scene, subset(start, slice(0, 128 if args.quick else 512)), 6.0)
            # each mode against MuJoCo run to the same end: rest, or the decided face
            mj["ratios"] = {mode: _ratios(row, (mj["decided"] if mode == DECIDED else mj)[
                "throws_per_s_1thread"]) for mode, row in rest["modes"].items()}
            mj["vectorised_ceiling_vs_mujoco_per_core"] = (
                rest["step_budget"]["vectorised_ceiling_throws_per_s_2cores"]
                / (2 * mj["throws_per_s_1thread"]))
            rest["mujoco"] = mj
    report["per_shape_decided"] = {"command": report["command"],
                                   "load_average": os.getloadavg(),
                                   "dice": per_shape(args.quick)}
    report["machine"]["load_average_end"] = os.getloadavg()
    report["table"] = format_report(report)  # the printed table, quoted by docs/performance.md
    write_json(args.out, report)
    print(report["table"])
    print(f"wrote {args.out}")


def _ratios(row: dict, reference: float) -> dict:
    return {"batch_1thread": row["batch_threads1"] / reference,
            "batch_2threads_vs_2cores": row["batch_threads2"] / (2 * reference),
            "single_throws": row["single_throws_per_s"] / reference}


def _cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def format_report(r: dict) -> str:
    """The report as a plain-text table."""
    k = r["paper_scene_die_steps_per_s"]
    load = r["machine"]
    lines = [f"{r['command']}",
             f"machine: {load['cpu']}, {load['cores']} cores, load average "
             f"{load['load_average_start'][0]:.2f} -> {load['load_average_end'][0]:.2f}",
             "", "paper scene, dt = 1e-4 (die-steps/s)",
             f"  batch 1, 1 thread        {k['batch1_threads1'] / 1e6:8.2f} M",
             f"  batch 1024, 1 thread     {k['batch1024_threads1'] / 1e6:8.2f} M",
             f"  batch 1024, 2 threads    {k['batch1024_threads2'] / 1e6:8.2f} M   "
             f"(scalar kernel: {k['batch1024_threads2_scalar_kernel'] / 1e6:.2f} M, vectorised "
             f"{k['ratio_vectorised_vs_scalar_kernel']:.2f}x)",
             f"  numpy listing            {k['numpy_listing'] / 1e6:8.4f} M   "
             f"(kernel batch 1: {k['ratio_batch1_vs_numpy']:.0f}x, batch 1024 on 2 threads: "
             f"{k['ratio_batch1024_2threads_vs_numpy']:.0f}x)", ""]
    for label, s in r["start"].items():
        lines.append(f"start, {label} cache: import {s['import_s']:.2f} s + first throw "
                     f"{s['first_throw_s']:.2f} s = {s['import_and_first_throw_s']:.2f} s; "
                     f"first 2-thread batch {s['first_batch_2threads_s']:.2f} s")
    for name, d in r["throws_to_rest"].items():
        sc = d["scene"]
        lines += ["", f"{name}: S={sc['stiffness']:g}, D={sc['damping']:.4g}, "
                  f"mu={sc['friction']:g}, dt={sc['dt_s']:.3g} s; settled throws/s",
                  "  mode                       batch  1 thread  2 threads   single  ms/single"
                  "  rest s  steps"]
        for mode, row in d["modes"].items():
            lines.append(f"  {mode:<25} {row['batch']:6d} {row['batch_threads1']:9.0f} "
                         f"{row['batch_threads2']:10.0f} {row['single_throws_per_s']:8.0f} "
                         f"{row['single_throw_ms']:10.3f} {row['mean_rest_time_s']:7.3f} "
                         f"{row['mean_steps']:6.0f}")
        row, decided = d["modes"][FASTEST], d["modes"][DECIDED]
        lines.append(f"  settled {row['settled_fraction']:.3f}, impacts "
                     f"{row['mean_impacts']:.1f}, faces {row['face_counts']}")
        lines.append(f"  {DECIDED}: decided {decided['decided_fraction']:.3f} (column 'rest s':"
                     f" when), the same face as at rest {decided['same_face_as_at_rest']:.4f}")
        b = d["step_budget"]
        lines.append(f"  steps per throw ({b['throws']} throws, plain stepping): flight "
                     f"{b['mean_flight_steps']:.0f}, contact before rest "
                     f"{b['mean_contact_steps_before_rest']:.0f}, hold "
                     f"{b['mean_hold_steps']:.0f}; a resting die's step costs "
                     f"{b['ns_per_contact_step_1thread']:.0f} ns, so the contact steps alone "
                     f"take about {b['floor_ms_per_throw']:.3f} ms: about "
                     f"{b['ceiling_throws_per_s_per_core']:.0f} throws/s per core at most")
        lines.append(f"  at the vectorised paper step's cost "
                     f"({b['ns_per_vectorised_paper_step_1thread']:.0f} ns) the contact steps "
                     f"would still take {b['vectorised_floor_ms_per_throw']:.3f} ms: at most "
                     f"{b['vectorised_ceiling_throws_per_s_2cores']:.0f} throws/s on 2 cores")
        mj = d.get("mujoco")
        if mj:
            ratio = mj["ratios"][FASTEST]
            lines += [f"  MuJoCo {mj['version']} (dt {mj['timestep_s']} s, {mj['throws']} of "
                      f"these throws): {mj['throws_per_s_1thread']:.0f} throws/s on 1 thread "
                      f"({mj['cpu_per_throw_ms']:.3f} ms per throw), settled "
                      f"{mj['settled_fraction']:.3f}, rest {mj['mean_rest_time_s']:.3f} s, "
                      f"faces {mj['face_counts']}",
                      f"  ours ({FASTEST}) / MuJoCo: 1 thread {ratio['batch_1thread']:.2f}x, "
                      f"2 threads vs 2 cores {ratio['batch_2threads_vs_2cores']:.2f}x, single "
                      f"throws {ratio['single_throws']:.2f}x; the vectorised ceiling above / "
                      f"MuJoCo: {mj['vectorised_ceiling_vs_mujoco_per_core']:.2f}x per core"]
            md, ratio = mj["decided"], mj["ratios"][DECIDED]
            lines += [f"  MuJoCo to the same decided-face rule: {md['throws_per_s_1thread']:.0f} "
                      f"throws/s on 1 thread, decided at {md['mean_time_s']:.3f} s, same face "
                      f"as at rest {md['same_face_as_at_rest']:.3f}",
                      f"  ours ({DECIDED}) / MuJoCo decided: 1 thread "
                      f"{ratio['batch_1thread']:.2f}x, 2 threads vs 2 cores "
                      f"{ratio['batch_2threads_vs_2cores']:.2f}x, single throws "
                      f"{ratio['single_throws']:.2f}x"]
    lines += ["", f"Scene(), {FASTEST}: batch size -> settled throws/s (2 threads)"]
    lines += [f"  {size:>6} {rate:10.0f}" for size, rate in
              r["throws_per_s_vs_batch_2threads"].items()]
    lines += ["", "every standard die on the default table: throws/s to a decided face "
              "(2 threads)", "  die   vertices  dt (us)  throws/s  decided  to face (s)  "
              "cost/d6  vertices x steps/d6"]
    lines += [f"  {name:<5} {row['vertices']:8d} {row['dt_s'] * 1e6:8.2f} "
              f"{row['throws_per_s_2threads']:9.0f} {row['decided_fraction']:8.3f} "
              f"{row['mean_time_to_face_s']:11.3f} {row['cost_vs_d6']:8.2f} "
              f"{row['explained_vs_d6']:20.2f}"
              for name, row in r["per_shape_decided"]["dice"].items()]
    lines += ["", "Scene(): simulated time -> ms of CPU per throw (1 thread, no stop at rest)",
              "       t_max   free flight   plain stepping"]
    lines += [f"  {float(t):8.2f} s {v['ms_per_throw']:10.3f} {v['ms_per_throw_plain']:14.3f}"
              for t, v in r["cost_vs_simulated_time"].items()]
    return "\n".join(lines)


if __name__ == "__main__":
    main()

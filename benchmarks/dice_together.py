"""Cost of a throw against the number of dice thrown together: groups of 1, 2, 6 and 12 d6.

    python benchmarks/dice_together.py                  # 1, 2, 6, 12 dice, about 3 minutes
    python benchmarks/dice_together.py --dice 1 2 --throws 256 --repeats 3
    python benchmarks/dice_together.py --throws 240 --mujoco 2 12 --die-friction regularized
    python benchmarks/dice_together.py --lockstep --dice 2 6 12 --out lockstep.json

Each group is thrown from the pairs study's hand (``dice_env.throws.group_throws``: the
dice side by side 3 cm apart in rows of four, one hand velocity plus each die's noise) into
the tray (``Scene(walls=tray())``), seeded, each throw until every face is decided
(``simulate_group(..., until="decided")``, 10 s at most). Timed on one thread as this
process's CPU time (other processes on the shared cores inflate it less than wall-clock
time), best of ``--repeats`` (default 1), after a warm-up that compiles the kernels.
``--throws`` is the number of throws of the single die; a group of N dice gets
``ceil(throws / N)`` (at least 4), so a few throws of the large groups set their rate. Beside the
group of one, the same throws through the single-die path (``simulate``) with its free-flight
shortcut (flights between contacts in one step) and without it (every step, as the group
kernel steps each die), for reference; die-steps count a shortcut flight's steps as taken.
Prints a table and writes ``benchmarks/results/dice_together.json``.

Then a pair whose dice (almost) never meet: two d6 from the same hand but :data:`APART` apart,
as a pair (``simulate_group``) and as its two dice thrown alone one after the other
(``simulate``), on one thread, CPU time: the pair's cost over its dice's.

Groups step in islands (``DieContact``'s default: dice that cannot meet for a while step
apart, each island at its own step, and an island at rest sleeps); ``--lockstep`` steps every
die of a group together (``DieContact(islands=False)``).

``--mujoco 2 6 12`` adds MuJoCo on the same throws of those groups (``pip install mujoco``): N
free boxes of the die's size, mass and inertia in the same tray (a plane floor and four plane
walls), every geom with the table's friction (MuJoCo takes the larger of a pair's), once at
its default contact and 2 ms step, once with a contact that bounces like the table's (the
``solref`` time constant and damping ratio of our landing's spring, at a quarter of that time
constant as its step, as ``benchmarks/step_limit.py`` found it needs). Each group runs twice
on both sides: to decided faces, until the group rule of ``dice_env.physics.group_kernel`` holds
on MuJoCo's energies (no energy left in the throw can change any die's face: the total less the
other dice's resting energy below each die's lock); and to rest, until every corner of every
die has stayed slower than the scene's rest speed, and each die's kinetic energy below
``0.5 m v_rest**2``, for the rest hold (ours also asks three corners of each die in contact;
MuJoCo's contacts are not counted). MuJoCo's rule is checked every millisecond of simulated
time, for at most 10 s; timed as the CPU time of its ``mj_step`` calls.
"""

from __future__ import annotations

import math
import os
import platform
import time
from dataclasses import replace

import numba
import numpy as np
from harness import benchmark_parser, timed, write_json

from dice_env import Scene, simulate
from dice_env.markdown import markdown_table
from dice_env.model.defaults import RESTITUTION, damping_ratio
from dice_env.model.die import Die
from dice_env.provenance import code_version
from dice_env.simulation.group import DieContact, GroupState, group_step, simulate_group
from dice_env.simulation.simulate import UP, lock_energy
from dice_env.throws import HAND, group_throws, tray_scene

APART = 0.12  # m between the dice of the pair that never meets


UNTIL = ("decided", "rest")  # the two ends of a throw compared with MuJoCo


def ours_in_tray(n_dice: int, throws: int, repeats: int, seed: int, group: dict,
                 until: str = "decided") -> tuple:
    """The tray, ``n_dice`` d6, their seeded throws, our least CPU time and the result.

    ``group``: ``simulate_group``'s keywords (``contact``).
    """
    scene = tray_scene()
    dice = (Die(),) * n_dice
    state = group_throws(scene, dice, throws, np.random.default_rng(seed))
    seconds, res = timed(lambda: simulate_group(scene, dice, state, until=until, **group,
                                                   num_threads=1), repeats)
    return scene, dice, state, seconds, res


def measure(n_dice: int, throws: int, repeats: int, seed: int, group: dict) -> list[dict]:
    """The rows of ``n_dice`` d6 run with ``group`` (and the single-die path for one die)."""
    scene, dice, state, seconds, res = ours_in_tray(n_dice, throws, repeats, seed, group)
    steps = float(res.steps.sum())
    row = {"path": "simulate_group", "dice": n_dice, "throws": throws, "cpu_s": seconds,
           "throws_per_s": throws / seconds, "die_steps_per_s": steps * n_dice / seconds,
           "decided": float((res.decided | res.settled).mean()),
           "all_read": float(res.read.all(axis=1).mean()),
           "met": float((res.overlap > 0).mean()),
           "sim_s": float(res.steps.mean() * group_step(scene, dice))}
    rows = [row]
    if n_dice == 1:
        alone = state.die(0)
        for flight in (True, False):
            seconds, one = timed(lambda f=flight: simulate(
                scene, alone, until="decided", free_flight=f, num_threads=1), repeats)
            rows.append({"path": f"simulate(free_flight={flight})", "dice": 1, "throws": throws,
                         "cpu_s": seconds, "throws_per_s": throws / seconds,
                         "die_steps_per_s": float(one.steps.sum()) / seconds,
                         "decided": float((one.decided | one.settled).mean()),
                         "all_read": 1.0, "met": 0.0,
                         "sim_s": float(one.steps.mean() * scene.step)})
    return rows


def apart_pair(throws: int, repeats: int, seed: int, group: dict) -> dict:
    """Two d6 :data:`APART` apart in the tray: as a pair, and as its two dice thrown alone."""
    scene = tray_scene()
    dice = (Die(),) * 2
    state = group_throws(scene, dice, throws, np.random.default_rng(seed),
                         replace(HAND, spacing=APART))
    pair_s, pair = timed(lambda: simulate_group(scene, dice, state, until="decided", **group,
                                                num_threads=1), repeats)
    alone_s = [timed(lambda i=i: simulate(scene, state.die(i), until="decided", num_threads=1),
                     repeats)[0] for i in range(2)]
    return {"throws": throws, "spacing_m": APART, "met": float((pair.overlap > 0).mean()),
            "pair_cpu_s": pair_s, "alone_cpu_s": alone_s,
            "pair_per_alone": pair_s / sum(alone_s),
            "decided": float(pair.decided.mean())}


_TRAY_MJCF = """
<mujoco>
  <option timestep="{dt}" gravity="0 0 -{g}"/>
  <default><geom friction="{mu} 0.005 0.0001" {contact}/></default>
  <worldbody>
{planes}
{boxes}
  </worldbody>
</mujoco>
"""
# MuJoCo's decision check: every this many seconds of simulated time.
CHECK_EVERY = 1e-3


def mujoco_tray(scene: Scene, n_dice: int, dt: float, contact: str = ""):
    """MuJoCo's model of ``n_dice`` of ``scene``'s d6 in ``scene``'s planes (floor and walls)."""
    import mujoco

    die = scene.die
    planes = "\n".join(
        f'    <geom type="plane" size="1 1 0.1" pos="{_xyz(np.multiply(p.normal, p.offset))}" '
        f'zaxis="{_xyz(p.normal)}"/>' for p in (scene.ground, *scene.walls))
    boxes = "\n".join(
        f'    <body name="die{k}"><freejoint/><geom type="box" size="{die.size / 2} '
        f'{die.size / 2} {die.size / 2}"/><inertial pos="0 0 0" mass="{die.mass}" '
        f'diaginertia="{die.inertia_body[0, 0]} {die.inertia_body[1, 1]} '
        f'{die.inertia_body[2, 2]}"/></body>' for k in range(n_dice))
    return mujoco.MjModel.from_xml_string(_TRAY_MJCF.format(
        dt=dt, g=scene.gravity, mu=scene.ground.friction, contact=contact, planes=planes,
        boxes=boxes))


def _xyz(v: object) -> str:
    """A 3-vector as MJCF writes it."""
    return " ".join(f"{c:.9g}" for c in np.asarray(v, float))


def bouncing_contact(scene: Scene) -> tuple[str, float]:
    """MuJoCo's ``solref`` for a landing like the table's, and the step it needs."""
    zeta = damping_ratio(RESTITUTION)
    time_constant = 1.0 / (zeta * math.sqrt(4 * scene.ground.stiffness / scene.die.mass))
    return f'solref="{time_constant:.6g} {zeta:.6g}"', time_constant / 4


class _Decided:
    """The group rule on MuJoCo's energies: no energy left can change any die's face."""

    def __init__(self, scene: Scene, n: int) -> None:
        die = scene.die
        self.lock, self.weight, self.n = lock_energy(scene), die.mass * scene.gravity, n
        self.floor = self.weight * float(die.resting_heights.min())  # a die's least energy
        self.inertia, self.die = np.diag(die.inertia_body), die

    def __call__(self, data, t: float) -> bool:
        n, die = self.n, self.die
        vel = data.qvel.reshape(n, 6)
        energy = float(0.5 * die.mass * (vel[:, :3] ** 2).sum()
                       + 0.5 * (self.inertia * vel[:, 3:] ** 2).sum()
                       + self.weight * data.qpos.reshape(n, 7)[:, 2].sum())
        read = die.face_read(data.xmat[1:].reshape(n, 3, 3), UP)
        return bool(np.all(energy - (n - 1) * self.floor < self.lock[read - 1]))


class _AtRest:
    """Every corner slower than the rest speed, and the kinetic energy low, for the hold."""

    def __init__(self, scene: Scene, n: int) -> None:
        self.corners, self.n, self.rest = scene.die.vertices_body, n, scene.rest
        self.mass, self.inertia = scene.die.mass, np.diag(scene.die.inertia_body)
        self.quiet_since: float | None = None

    def __call__(self, data, t: float) -> bool:
        vel = data.qvel.reshape(self.n, 6)
        rot = data.xmat[1:].reshape(self.n, 3, 3)
        # a corner's velocity: v + R (w_body x r_body); the free joint's spin is in body axes
        corner = vel[:, None, :3] + np.einsum("nij,nkj->nki", rot,
                                              np.cross(vel[:, None, 3:], self.corners))
        v2 = self.rest.speed ** 2
        kinetic = 0.5 * (self.mass * (vel[:, :3] ** 2).sum(axis=1)
                         + (self.inertia * vel[:, 3:] ** 2).sum(axis=1))
        if (corner ** 2).sum(axis=2).max() >= v2 or kinetic.max() >= 0.5 * self.mass * v2:
            self.quiet_since = None
            return False
        self.quiet_since = t if self.quiet_since is None else self.quiet_since
        return t - self.quiet_since >= self.rest.hold


STOPS = {"decided": _Decided, "rest": _AtRest}


def mujoco_run(scene: Scene, state: GroupState, model, until: str) -> dict:
    """MuJoCo on the throws ``state`` until each throw ends by ``until`` (:data:`STOPS`)."""
    import mujoco

    die = scene.die
    b, n = state.batch_size, state.n_dice
    data = mujoco.MjData(model)
    block = max(1, round(CHECK_EVERY / model.opt.timestep))
    n_blocks = math.ceil(scene.t_max / (block * model.opt.timestep))
    cpu, steps, ended, faces = 0.0, np.zeros(b, np.int64), np.zeros(b, bool), []
    for k in range(b):
        mujoco.mj_resetData(model, data)
        for i in range(n):
            q = state.orientation[k, i]
            data.qpos[7 * i:7 * i + 3] = state.position[k, i]
            mujoco.mju_mat2Quat(data.qpos[7 * i + 3:7 * i + 7], q.ravel())
            data.qvel[6 * i:6 * i + 6] = np.concatenate(
                [state.velocity[k, i], q.T @ state.angular_velocity[k, i]])
        stop = STOPS[until](scene, n)
        for _ in range(n_blocks):
            begin = time.thread_time()
            mujoco.mj_step(model, data, nstep=block)
            cpu += time.thread_time() - begin
            steps[k] += block
            if stop(data, steps[k] * model.opt.timestep):
                ended[k] = True
                break
        faces.append(die.face_read(data.xmat[1:].reshape(n, 3, 3), UP))
    return {"version": mujoco.__version__, "dt_s": model.opt.timestep, "throws": b,
            "cpu_s": cpu, "throws_per_s": b / cpu, "ended": float(ended.mean()),
            "sim_s": float(steps.mean() * model.opt.timestep),
            "face_counts": np.bincount(np.concatenate(faces), minlength=7)[1:].tolist()}


def compare_mujoco(n_dice: int, throws: int, seed: int, group: dict, until: str) -> dict:
    """Ours and MuJoCo (default and bouncing contact) on the same ``throws``, to ``until``."""
    scene, dice, state, seconds, ours = ours_in_tray(n_dice, throws, 1, seed, group, until)
    bounce, dt = bouncing_contact(scene)
    rows = {"ours": {"throws_per_s": throws / seconds, "cpu_s": seconds,
                     "ended": float((ours.settled | (ours.decided & (until == "decided"))
                                     ).mean()),
                     "sim_s": float(ours.steps.mean() * group_step(scene, dice))},
            "mujoco_default": mujoco_run(scene, state, mujoco_tray(scene, n_dice, 0.002), until),
            "mujoco_bouncing": mujoco_run(scene, state,
                                          mujoco_tray(scene, n_dice, dt, bounce), until)}
    for name in ("mujoco_default", "mujoco_bouncing"):
        rows[name]["ours_vs_mujoco"] = rows["ours"]["throws_per_s"] / rows[name]["throws_per_s"]
    return {"dice": n_dice, "until": until, "throws": throws, **rows}


def main() -> None:
    parser = benchmark_parser(__doc__, "dice_together")
    parser.add_argument("--dice", type=int, nargs="+", default=[1, 2, 6, 12])
    parser.add_argument("--throws", type=int, default=96,
                        help="throws of the single die (a group of N gets throws / N)")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--mujoco", type=int, nargs="*", default=[],
                        help="groups to run through MuJoCo as well, e.g. 2 6 12")
    parser.add_argument("--die-friction", choices=["stick_slip", "regularized"],
                        default=DieContact().friction_law.name.lower(),
                        help="the die–die friction law (DieContact.friction_law)")
    parser.add_argument("--lockstep", action="store_true",
                        help="DieContact(islands=False): every die of a group steps together")
    args = parser.parse_args()
    contact = DieContact(friction_law=args.die_friction, islands=not args.lockstep)
    group = {"contact": contact}
    for name in ("throws", "repeats"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be >= 1, got {getattr(args, name)}")
    for name in ("dice", "mujoco"):
        if getattr(args, name) and (min(getattr(args, name)) < 1
                                    or max(getattr(args, name)) > 64):
            parser.error(f"--{name} must be 1 to 64 dice, got {getattr(args, name)}")
    for n_dice in (1, 2):
        measure(n_dice, 2, 1, args.seed, group)  # compile both paths' kernels, untimed
    rows = []
    for n_dice in args.dice:
        rows += measure(n_dice, max(4, math.ceil(args.throws / n_dice)), args.repeats, args.seed,
                        group)
        print(f"{n_dice} dice done", flush=True)
    base = next(r for r in rows if r["path"] == "simulate_group" and r["dice"] == min(args.dice))
    print(f"\nOne thread, CPU time, best of {args.repeats}, {contact.law} die–die friction"
          f"{', lockstep' if args.lockstep else ', islands'}; "
          f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores.\n")
    print(markdown_table(
        "path | dice | throws | throws/s | cost per throw / smallest group | die-steps/s | "
        "decided | all dice read | dice met | simulated s per throw",
        ((f"`{r['path']}`", r["dice"], r["throws"], f"{r['throws_per_s']:.2f}",
          f"{base['throws_per_s'] / r['throws_per_s']:.2f}", f"{r['die_steps_per_s']:,.0f}",
          f"{r['decided']:.0%}", f"{r['all_read']:.0%}", f"{r['met']:.0%}", f"{r['sim_s']:.2f}")
         for r in rows)))
    apart = apart_pair(max(4, math.ceil(args.throws / 2)), args.repeats, args.seed, group)
    alone = apart["alone_cpu_s"]
    print(f"\nTwo d6 {APART * 100:.0f} cm apart (met in {apart['met']:.0%} of "
          f"{apart['throws']} throws): the pair {apart['pair_cpu_s']:.3f} s, its dice alone "
          f"{alone[0]:.3f} + {alone[1]:.3f} s: {apart['pair_per_alone']:.2f}x their CPU time")
    mujoco_rows = []
    for until in UNTIL:
        mujoco_rows += [compare_mujoco(n_dice, max(4, math.ceil(args.throws / n_dice)),
                                       args.seed, group, until) for n_dice in args.mujoco]
    if mujoco_rows:
        print("\nThe same throws in MuJoCo, one thread, CPU time:\n")
        print(markdown_table(
            "dice | to | throws | ours throws/s | MuJoCo default (2 ms) throws/s | ours / it | "
            "MuJoCo bouncing (step) throws/s | ours / it | simulated s: ours, default, bouncing | "
            "ended: ours, default, bouncing",
            ((r["dice"], r["until"], r["throws"], f"{o['throws_per_s']:.2f}",
              f"{d['throws_per_s']:.2f}", f"{d['ours_vs_mujoco']:.3f}",
              f"{c['throws_per_s']:.2f} ({c['dt_s'] * 1e6:.0f} us)",
              f"{c['ours_vs_mujoco']:.2f}", f"{o['sim_s']:.2f}, {d['sim_s']:.2f}, {c['sim_s']:.2f}",
              f"{o['ended']:.0%}, {d['ended']:.0%}, {c['ended']:.0%}")
             for r in mujoco_rows
             for o, d, c in [(r["ours"], r["mujoco_default"], r["mujoco_bouncing"])])))
    write_json(args.out, {"mujoco": mujoco_rows, "apart_pair": apart,
        "command": "python benchmarks/dice_together.py " + " ".join(
            f"--{k.replace('_', '-')}" + ("" if isinstance(v, bool) else
                                         f" {' '.join(map(str, v)) if isinstance(v, list) else v}")
            for k, v in vars(args).items() if k != "out" and v is not False),
        "commit": code_version(), "threads": 1, "timer": "process CPU time",
        "repeats": args.repeats,
        "die_friction": contact.law,
        "islands": contact.islands,
        "load_average": os.getloadavg()[0], "cpu_count": os.cpu_count(),
        "numba": numba.__version__, "python": platform.python_version(), "rows": rows},
        indent=1)


if __name__ == "__main__":
    main()

"""What bounds the default scene's throws/s: the step its accuracy allows, and MuJoCo's contact.

    python benchmarks/step_limit.py            # full run, about 6 minutes on 2 cores
    python benchmarks/step_limit.py --quick    # smaller sizes, a couple of minutes

Prints two tables and writes ``benchmarks/results/step_limit.json`` (``--out`` to change).

1. **Our explicit step, from the default up to the stability limit.** For each step
   ``safety * critical_dt``: the gentle release's face agreement between dt and dt/4 (the
   realistic table's requirement is >= 98 %, ``docs/error-vs-runtime.md``) beside its chaos
   floor, the flat-landing restitution at 1 m/s (converged: that of dt/4 at the default), the
   deepest corner sink, and the hand throws of ``benchmarks/physics.py`` to early rest on
   2 threads: throws/s, steps, unstable throws. It shows how much speed a longer step buys and
   what it costs in accuracy while the scheme is still stable.
2. **MuJoCo's contact against ours** (optional ``bench`` extra): a flat, spin-free landing of
   the die (restitution, deepest sink) at MuJoCo's default contact and step, the setting
   ``benchmarks/physics.py`` times, and with a stiff contact made to bounce like our table
   (``solref`` time constant and damping ratio from our stiffness and restitution, set on both
   geoms) at the steps it needs; and the same hand throws to rest on 1 thread in each.
"""

from __future__ import annotations

import math
import os

import numpy as np
from harness import benchmark_parser, parse_with_mujoco, timed, write_json
from physics import hand_throws, mujoco_model, mujoco_to_rest

from dice_env import Scene, State, simulate
from dice_env.model.defaults import RESTITUTION, damping_ratio, rebound
from dice_env.provenance import code_version
from dice_env.simulation.calibration import measured_restitution
from dice_env.throws import RELEASES, face_agreement

SAFETIES = (0.15, 0.3, 0.45, 0.6, 0.9)
DROP_SPEEDS = (0.3, 1.0)


def our_landing(scene: Scene, speed: float) -> dict:
    """Restitution and deepest corner sink (fraction of the edge) of a flat landing."""
    h = scene.die.resting_heights[0]  # lying on face 6, showing 1
    state = State.release(scene, [0.0, 0.0, h + 1e-4], [0.0, 0.0, -speed])
    sink = simulate(scene, state, t_max=0.01, until="t_max").max_penetration[0]
    return {"restitution": measured_restitution(scene, speed), "sink": sink / scene.die.size}


def step_sweep(quick: bool) -> list[dict]:
    """Accuracy and speed of the default scheme at longer and longer steps."""
    scene = Scene()
    gentle = RELEASES[0].sample(scene, 100 if quick else 500, np.random.default_rng(5))
    throws = hand_throws(scene, 256 if quick else 1024)
    rows = []
    for safety in SAFETIES:
        at = scene.with_(dt=safety * scene.critical_dt)
        agree = face_agreement(at, gentle)
        timing, result = timed(lambda s=at: simulate(s, throws, until="early_rest", num_threads=2),
                               1 if quick else 2, threads=2)
        rows.append({
            "safety": safety, "dt_s": at.step,
            "gentle_agreement": float(agree["step"].mean()),
            "gentle_agreement_se": float(agree["step"].std() / math.sqrt(gentle.batch_size)),
            "chaos_floor": float(agree["floor"].mean()),
            "restitution_1mps": measured_restitution(at, 1.0),
            "deepest_sink_of_edge": float(result.max_penetration.max() / scene.die.size),
            "throws_per_s_2threads": throws.batch_size / timing,
            "mean_steps": float(result.steps.mean()),
            "unstable_fraction": float(result.unstable.mean()),
            "settled_fraction": float(result.settled.mean())})
    rows[0]["converged_restitution_1mps"] = measured_restitution(
        scene.with_(dt=scene.step / 4), 1.0)
    return rows


def mujoco_landing(model, scene: Scene, speed: float) -> dict:
    """Restitution and deepest sink (fraction of the edge) of MuJoCo's flat landing."""
    import mujoco

    data = mujoco.MjData(model)
    h, g = scene.die.resting_heights[0], scene.gravity
    data.qpos[:] = [0.0, 0.0, h + 1e-4, 1.0, 0.0, 0.0, 0.0]
    data.qvel[:] = [0.0, 0.0, -math.sqrt(speed**2 + 2 * g * 1e-4), 0.0, 0.0, 0.0]
    z, vz = [], []
    for _ in range(round(0.05 / model.opt.timestep)):
        mujoco.mj_step(model, data)
        z.append(data.qpos[2])
        vz.append(data.qvel[2])
    z = np.array(z)
    e = rebound(z, np.array(vz), h, g, speed)
    return {"restitution": 0.0 if e is None else e, "sink": float((h - z.min()) / scene.die.size)}


def contact_comparison(quick: bool) -> dict | None:
    """Landings and throws to rest, ours and MuJoCo's, default and stiff contact."""
    try:
        import mujoco
    except ImportError:
        return None
    scene = Scene()
    throws = hand_throws(scene, 32 if quick else 128)
    ours, result = timed(lambda: simulate(scene, throws, until="early_rest", num_threads=1), 2)
    # our flat-landing mode, (m/4) x'' = -S x - D x': its period and damping ratio
    zeta = damping_ratio(RESTITUTION)
    omega = math.sqrt(4 * scene.ground.stiffness / scene.die.mass)
    time_constant = 1.0 / (zeta * omega)  # MuJoCo's stiffness is 1 / (timeconst dampratio)^2
    stiff = f'solref="{time_constant:.6g} {zeta:.6g}"'
    settings = {"default contact, dt 2 ms": (0.002, "")}
    for divisor in (4, 8, 16):
        settings[f"stiff contact, dt timeconst/{divisor}"] = (time_constant / divisor, stiff)
    out = {"version": mujoco.__version__, "throws": throws.batch_size,
           "ours": {"landing": {v: our_landing(scene, v) for v in DROP_SPEEDS},
                    "throws_per_s_1thread": throws.batch_size / ours, "dt_s": scene.step,
                    "mean_rest_time_s": float(result.rest_time.mean())},
           "stiff_solref": {"timeconst_s": time_constant, "dampratio": zeta}, "mujoco": {}}
    for name, (dt, contact) in settings.items():
        model = mujoco_model(scene, dt, contact)
        row = {"dt_s": dt, "landing": {v: mujoco_landing(model, scene, v) for v in DROP_SPEEDS}}
        rest = mujoco_to_rest(scene, throws, 6.0 if dt >= 1e-3 else 2.0, model)
        row.update({k: rest[k] for k in ("settled_fraction", "mean_rest_time_s",
                                         "throws_per_s_1thread", "mean_steps")})
        row["ours_vs_mujoco"] = out["ours"]["throws_per_s_1thread"] / row["throws_per_s_1thread"]
        out["mujoco"][name] = row
    return out


def format_report(r: dict) -> str:
    """The two tables as plain text."""
    sweep = r["step_sweep"]
    lines = [r["command"], "", "Scene(): the explicit step from the default to the stability "
             f"limit (converged restitution {sweep[0]['converged_restitution_1mps']:.3f})",
             "  safety    dt us  gentle dt vs dt/4  chaos floor   e(1 m/s)  sink/edge"
             "  throws/s (2 thr)   steps  unstable"]
    for row in sweep:
        lines.append(
            f"  {row['safety']:6.2f} {1e6 * row['dt_s']:8.2f} "
            f"{100 * row['gentle_agreement']:9.1f} ± {100 * row['gentle_agreement_se']:.1f} % "
            f"{100 * row['chaos_floor']:10.1f} % {row['restitution_1mps']:10.3f} "
            f"{100 * row['deepest_sink_of_edge']:8.2f} % {row['throws_per_s_2threads']:14.0f} "
            f"{row['mean_steps']:9.0f} {100 * row['unstable_fraction']:7.1f} %")
    c = r.get("contact")
    if c:
        sr = c["stiff_solref"]
        lines += ["", f"MuJoCo {c['version']} against ours ({c['throws']} hand throws to rest, "
                  f"1 thread; stiff solref = {sr['timeconst_s']:.3g} s, {sr['dampratio']:.3f})",
                  "  model                                   dt s   e(0.3)  e(1.0)  sink(1.0)"
                  "  throws/s  rest s  ours/it"]
        landing = c["ours"]["landing"]
        lines.append(f"  {'ours (Scene(), early rest)':<36} {'':>9} "
                     f"{landing[0.3]['restitution']:7.3f} {landing[1.0]['restitution']:7.3f} "
                     f"{100 * landing[1.0]['sink']:8.2f} % "
                     f"{c['ours']['throws_per_s_1thread']:9.0f}")
        for name, row in c["mujoco"].items():
            land = row["landing"]
            lines.append(f"  {name:<36} {row['dt_s']:9.3g} {land[0.3]['restitution']:7.3f} "
                         f"{land[1.0]['restitution']:7.3f} {100 * land[1.0]['sink']:8.2f} % "
                         f"{row['throws_per_s_1thread']:9.1f} {row['mean_rest_time_s']:7.3f} "
                         f"{row['ours_vs_mujoco']:7.1f}x")
    return "\n".join(lines)


def main() -> None:
    args = parse_with_mujoco(benchmark_parser(__doc__, "step_limit", "smaller sizes"))
    report = {"command": "python benchmarks/step_limit.py" + (" --quick" if args.quick else ""),
              "commit": code_version(),
              "load_average_start": os.getloadavg(), "step_sweep": step_sweep(args.quick)}
    if not args.no_mujoco:
        report["contact"] = contact_comparison(args.quick)
    report["load_average_end"] = os.getloadavg()
    write_json(args.out, report)
    print(format_report(report))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()

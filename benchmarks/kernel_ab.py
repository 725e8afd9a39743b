"""The kernel of this tree against another commit's, alternating processes on the same throws.

    python benchmarks/kernel_ab.py BASE_TREE            # e.g. a `git worktree` of the base
    python benchmarks/kernel_ab.py BASE_TREE --this THIS_TREE --rounds 5
    python benchmarks/kernel_ab.py BASE_TREE --groups   # the group kernel (several dice)

Each round runs one child process per tree (base, then this one) that times, on one thread
(its own CPU time, so other processes on shared cores inflate it less), three figures of the
same seeded throws: the paper scene (``real_throw_cube`` defaults, dt = 1e-4, 1024 dice,
0.5 s, the vectorised kernel) and the same through the scalar kernel, in die-steps/s; and
the default scene's hand throws to a decided face (1024 dice), in throws/s. The table gives
each figure's median over the rounds per tree and the ratio this/base per round (the machine
drifts by ±25 % over minutes; alternating keeps the two trees within a round close in time).
Writes ``benchmarks/results/kernel_ab.json``.

``--groups`` times the group kernel instead (``simulate_group``, one thread, throws/s to
decided faces): twelve ``drilled16`` d6 from the Weldon study's cup onto the table (8 throws),
two d6 from the pairs study's hand into the tray (64 throws), and a d20, a d8 and a d6 from
that hand into the tray (64 throws); each tree's outcomes are hashed (faces, steps, final
states) to tell a bit-identical change from one at round-off. Writes
``benchmarks/results/kernel_ab_groups.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from harness import RESULTS, command_line, write_json

from dice_env.provenance import code_version

ROOT = Path(__file__).resolve().parents[1]
CHILD = r"""
import inspect, json, time
import numpy as np
from pathlib import Path
import dice_env
from dice_env import Scene, State, simulate
if (Path(dice_env.__file__).parent / "physics").is_dir():
    from dice_env.physics import vector_kernel
    from dice_env.simulation.paper import paper_scene
    from dice_env.model.rotations import random_rotations
else:  # a base tree from before the layers (model, physics, simulation)
    from dice_env import vector_kernel
    from dice_env.paper import paper_scene
    from dice_env.rotations import random_rotations
if "until" in inspect.signature(simulate).parameters:
    TO_T_MAX, DECIDED = {"until": "t_max"}, {"until": "decided"}
else:  # a base tree from before simulate's until
    TO_T_MAX, DECIDED = {"stop_at_rest": False}, {"stop_when_decided": True}

def cpu(fn):
    fn()  # compiled and warm
    best = np.inf
    for _ in range(3):
        start = time.process_time()
        fn()
        best = min(best, time.process_time() - start)
    return best

rng = np.random.default_rng(0)
n = 1024
paper = paper_scene()
spin = (rng.random((n, 3)) * 0.75 + 1e-6) / paper.die.inertia_body[0, 0]
start = State.release(paper, [0.0, 0.0, 3.0], [5.0, 0.0, 5.0], spin)
steps = n * round(0.5 / paper.step)
run = lambda: simulate(paper, start, t_max=0.5, **TO_T_MAX, num_threads=1)
vector = steps / cpu(run)
with vector_kernel.disabled():
    scalar = steps / cpu(run)
scene = Scene()
rng = np.random.default_rng(1)
d = rng.normal(size=(2, n, 3))
d /= np.linalg.norm(d, axis=2, keepdims=True)
hand = State.release(scene, np.column_stack([np.zeros((n, 2)), rng.uniform(0.05, 0.15, n)]),
                     d[0] * rng.uniform(0.5, 1.0, (n, 1)), d[1] * rng.uniform(0, 30, (n, 1)),
                     random_rotations(rng, n))
faces = simulate(scene, hand, **DECIDED, num_threads=1).face
decided = n / cpu(lambda: simulate(scene, hand, **DECIDED, num_threads=1))
print(json.dumps({"paper_vector": vector, "paper_scalar": scalar, "decided": decided,
                  "faces": int(faces.sum())}))
"""
FIGURES = {"paper_vector": "paper scene, vectorised kernel (die-steps/s)",
           "paper_scalar": "paper scene, scalar kernel (die-steps/s)",
           "decided": "default scene to a decided face (throws/s)"}
GROUP_CHILD = r"""
import hashlib, inspect, json, time
import numpy as np
from dice_env import Die, Scene
from pathlib import Path
import dice_env
try:  # the hands in the library
    from dice_env.throws import cup_throws, group_throws
except ImportError:  # a base tree from before dice_env.throws
    from dice_env.studies.pairs import hand_throws as group_throws
    from dice_env.studies.weldon import cup_throws
if (Path(dice_env.__file__).parent / "physics").is_dir():
    from dice_env.simulation.group import GroupState, simulate_group
    from dice_env.model.surroundings import tray
else:  # a base tree from before the layers (model, physics, simulation)
    from dice_env.group import GroupState, simulate_group
    from dice_env.surroundings import tray
if "until" in inspect.signature(simulate_group).parameters:
    DECIDED = {"until": "decided"}
else:  # a base tree from before simulate_group's until
    DECIDED = {"stop_when_decided": True}

def cpu(fn):
    fn()  # compiled and warm
    start = time.process_time()
    result = fn()
    return time.process_time() - start, result

def digest(res):
    h = hashlib.sha1()
    for a in (res.face, res.steps, res.final.position, res.final.orientation):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:12]

out = {}
table = Scene(die=Die.standard("d6", pips="drilled16"))
cups = GroupState.of(cup_throws(table, 8, np.random.default_rng(3)))
seconds, res = cpu(lambda: simulate_group(table, (table.die,) * 12, cups, t_max=2.0,
                                          **DECIDED, num_threads=1))
out["twelve"], out["twelve_hash"] = 8 / seconds, digest(res)
scene = Scene(walls=tray())
for key, dice in (("two", (scene.die,) * 2),
                  ("mixed", (Die.standard("d20"), Die.standard("d8"), scene.die))):
    state = group_throws(scene, dice, 64, np.random.default_rng(4))
    seconds, res = cpu(lambda: simulate_group(scene, dice, state, t_max=3.0,
                                              **DECIDED, num_threads=1))
    out[key], out[key + "_hash"] = 64 / seconds, digest(res)
print(json.dumps(out))
"""
GROUP_FIGURES = {"twelve": "twelve drilled d6 from a cup onto the table (throws/s)",
                 "two": "two d6 from a hand into the tray (throws/s)",
                 "mixed": "d20, d8 and d6 from a hand into the tray (throws/s)"}


def measure(tree: Path, child: str = CHILD) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", child], cwd=tree, env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def _rate(x: float) -> str:
    """A rate for the table: whole numbers from 1,000 up, else three significant figures."""
    return f"{x:,.0f}" if x >= 1000 else f"{x:.3g}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("base", type=Path, help="the other tree (a checkout of the base commit)")
    parser.add_argument("--this", type=Path, default=ROOT,
                        help="the tree to compare (default: this one)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--groups", action="store_true",
                        help="time the group kernel (several dice) instead")
    parser.add_argument("--out", type=Path, default=None,
                        help="default: benchmarks/results/kernel_ab.json (kernel_ab_groups.json)")
    args = parser.parse_args()
    child, figures = (GROUP_CHILD, GROUP_FIGURES) if args.groups else (CHILD, FIGURES)
    out = args.out or RESULTS / ("kernel_ab_groups.json" if args.groups else "kernel_ab.json")
    runs = {"base": [], "this": []}
    for r in range(args.rounds):
        for name, tree in (("base", args.base.resolve()), ("this", args.this.resolve())):
            runs[name].append(measure(tree, child))
            print(f"round {r + 1}, {name}: {runs[name][-1]}", flush=True)
    if args.groups:
        same = {k: {run[k + "_hash"] for run in runs["base"] + runs["this"]} for k in figures}
        same = {k: len(v) == 1 for k, v in same.items()}
        print(f"\nbit-identical outcomes: {same}\n")
    else:
        same = len({run["faces"] for run in runs["base"] + runs["this"]}) == 1
        print(f"\nsame decided faces in every run: {same}\n")
    print("| figure | base (median) | this (median) | this/base per round |")
    print("|---|---|---|---|")
    table = {}
    for key, label in figures.items():
        base = [run[key] for run in runs["base"]]
        this = [run[key] for run in runs["this"]]
        ratios = [t / b for t, b in zip(this, base, strict=True)]
        table[key] = {"base": base, "this": this, "ratios": ratios}
        print(f"| {label} | {_rate(np.median(base))} | {_rate(np.median(this))} | "
              f"{', '.join(f'{x:.3f}' for x in ratios)} |")
    write_json(out, {"command": command_line({args.base: "BASE"}),
                     "commit": code_version(args.this),
                     "base": str(args.base), "base_commit": code_version(args.base),
                     "this": str(args.this),
                     "same_faces" if not args.groups else "bit_identical": same,
                     "figures": table}, indent=1)


if __name__ == "__main__":
    main()

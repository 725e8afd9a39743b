"""The kernel of this tree against another commit's, alternating processes on the same throws.

    python benchmarks/kernel_ab.py BASE_TREE            # e.g. a `git worktree` of the base
    python benchmarks/kernel_ab.py BASE_TREE --this THIS_TREE --rounds 5

Each round runs one child process per tree (base, then this one) that times, on one thread
(its own CPU time, so other processes on shared cores inflate it less), three figures of the
same seeded throws: the paper scene (``real_throw_cube`` defaults, dt = 1e-4, 1024 dice,
0.5 s, the vectorised kernel) and the same through the scalar kernel, in die-steps/s; and
the default scene's hand throws to a decided face (1024 dice), in throws/s. The table gives
each figure's median over the rounds per tree and the ratio this/base per round (the machine
drifts by ±25 % over minutes; alternating keeps the two trees within a round close in time).
Writes ``benchmarks/results/kernel_ab.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CHILD = r"""
import json, time
import numpy as np
from dice_env import Scene, State, simulate, vector_kernel
from dice_env.paper import paper_scene
from dice_env.rotations import random_rotations

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
run = lambda: simulate(paper, start, t_max=0.5, stop_at_rest=False, num_threads=1)
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
faces = simulate(scene, hand, stop_when_decided=True, num_threads=1).face
decided = n / cpu(lambda: simulate(scene, hand, stop_when_decided=True, num_threads=1))
print(json.dumps({"paper_vector": vector, "paper_scalar": scalar, "decided": decided,
                  "faces": int(faces.sum())}))
"""
FIGURES = {"paper_vector": "paper scene, vectorised kernel (die-steps/s)",
           "paper_scalar": "paper scene, scalar kernel (die-steps/s)",
           "decided": "default scene to a decided face (throws/s)"}


def measure(tree: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", CHILD], cwd=tree, env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("base", type=Path, help="the other tree (a checkout of the base commit)")
    parser.add_argument("--this", type=Path, default=ROOT,
                        help="the tree to compare (default: this one)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks/results/kernel_ab.json")
    args = parser.parse_args()
    runs = {"base": [], "this": []}
    for r in range(args.rounds):
        for name, tree in (("base", args.base.resolve()), ("this", args.this.resolve())):
            runs[name].append(measure(tree))
            print(f"round {r + 1}, {name}: {runs[name][-1]}", flush=True)
    same = len({run["faces"] for run in runs["base"] + runs["this"]}) == 1
    print(f"\nsame decided faces in every run: {same}\n")
    print("| figure | base (median) | this (median) | this/base per round |")
    print("|---|---|---|---|")
    table = {}
    for key, label in FIGURES.items():
        base = [run[key] for run in runs["base"]]
        this = [run[key] for run in runs["this"]]
        ratios = [t / b for t, b in zip(this, base, strict=True)]
        table[key] = {"base": base, "this": this, "ratios": ratios}
        print(f"| {label} | {np.median(base):,.0f} | {np.median(this):,.0f} | "
              f"{', '.join(f'{x:.3f}' for x in ratios)} |")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"base": str(args.base), "this": str(args.this),
                                    "same_faces": same,
                                    "figures": table}, indent=1))


if __name__ == "__main__":
    main()

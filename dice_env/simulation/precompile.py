"""Compile the CPU kernels into numba's cache ahead of use, two at a time.

    python -m dice_env.simulation.precompile          # every kernel; quiet when the cache is warm

A tiny throw through each kernel, each in its own process (up to one per core), so that a
cold cache fills in the time of the longest compile rather than their sum (``.ci/setup``).
"""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numba
import numpy as np

from dice_env.model.scene import Scene
from dice_env.model.surroundings import tray
from dice_env.physics.vector_kernel import TILE
from dice_env.simulation.group import GroupState, simulate_group
from dice_env.simulation.paper import paper_scene
from dice_env.simulation.simulate import SERIAL_FIRST, State, simulate

THREADS = min(2, numba.config.NUMBA_NUM_THREADS)  # 2 runs the parallel loop, 1 the serial
BATCH = SERIAL_FIRST + TILE  # throws of a batch that takes the parallel loop, tiles whole


def _die() -> None:
    """The one-die kernel, parallel and serial (every scene that is not the paper's)."""
    scene = Scene(t_max=0.01)
    for n in (BATCH, 1):
        simulate(scene, State.release(scene, np.tile([0.0, 0.0, 0.05], (n, 1)), [1.0, 0, 0]),
                 num_threads=THREADS)


def _paper() -> None:
    """The paper scene's vector kernel, parallel and serial, with and without the stop tests."""
    scene = paper_scene().with_(t_max=0.01)
    for threads in (THREADS, 1):
        for until in ("rest", "t_max"):
            simulate(scene, State.release(scene, np.tile([0.0, 0.0, 3.0], (BATCH, 1)),
                                          [1.0, 0, 0]), until=until, num_threads=threads)


def _group() -> None:
    """The kernel of several dice, parallel and serial."""
    scene = Scene(walls=tray(), t_max=0.01)
    for n in (BATCH, 1):
        state = GroupState.of([State.release(scene, np.tile([0.0, y, 0.05], (n, 1)),
                                             [1.0, 0, 0]) for y in (-0.02, 0.02)])
        simulate_group(scene, (scene.die, scene.die), state, num_threads=THREADS)


KERNELS = {"die": _die, "several dice": _group, "paper": _paper}  # the longest first


def _compile(name: str) -> tuple[str, float]:
    start = time.perf_counter()
    KERNELS[name]()
    return name, time.perf_counter() - start


def main() -> None:
    """Fill numba's cache with every CPU kernel, in parallel processes; print the times."""
    workers = max(1, min(len(KERNELS), os.cpu_count() or 1))
    start = time.perf_counter()
    with ProcessPoolExecutor(workers) as pool:
        times = dict(pool.map(_compile, KERNELS))
    print("dice_env.simulation.precompile: " + ", ".join(f"{k} {s:.0f} s" for k, s in times.items())
          + f"; {time.perf_counter() - start:.0f} s in all on {workers} process(es)",
          file=sys.stderr)


if __name__ == "__main__":
    main()

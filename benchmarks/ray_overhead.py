"""Throws per second of the chunked runner in this process and on 1 and 2 local Ray workers.

    python benchmarks/ray_overhead.py                     # 20,000 d6 throws, a few minutes
    python benchmarks/ray_overhead.py --throws 8000 --chunk 1000

The same throws each time: ``dice_env.simulation.runner.run_throws`` of the default scene's d6
(vigorous hand throws, each until its face is decided), ``--throws`` in chunks of ``--chunk``.
Rows: the chunks one after the other in this process on one thread (``throw_chunk(...,
num_threads=1)``, the work of one Ray task) and on all numba threads (``run_throws`` without
Ray), then on a local Ray instance of ``num_cpus=2`` with one chunk at a time
(``workers=1``) and two. Wall-clock time (Ray's work runs in other processes), after a
warm-up that compiles the kernel here and loads it in each Ray worker; the instance's start
is timed apart. Every row must give the same tally bit for bit. Prints a markdown table and
writes ``benchmarks/results/ray_overhead.json``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numba
import numpy as np
import ray
from harness import RESULTS, write_json

from dice_env.markdown import markdown_table
from dice_env.model.scene import Scene
from dice_env.provenance import code_version
from dice_env.simulation.runner import Spec, Tally, run_throws, throw_chunk


def timed(fn: object) -> tuple[float, Tally]:
    """Wall-clock seconds of ``fn()`` and its tally."""
    start = time.perf_counter()
    tally = fn()
    return time.perf_counter() - start, tally


def one_thread(spec: Spec) -> Tally:
    """The chunks of ``spec`` one after the other on one thread of this process."""
    return Tally.merge(Tally.of(spec.scene, throw_chunk(spec, i, num_threads=1))
                       for i in range(spec.n_chunks))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--throws", type=int, default=20_000)
    parser.add_argument("--chunk", type=int, default=2_000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    scene = Scene()
    spec = Spec(scene, args.throws, args.chunk, args.seed)
    warm_up = Spec(scene, 2 * args.chunk, args.chunk, args.seed)
    one_thread(warm_up)  # compile (or load) both kernels here: serial and parallel
    run_throws(scene, warm_up.throws, chunk=args.chunk)
    kwargs = {"chunk": args.chunk, "seed": args.seed}
    rows = []

    def row(path: str, workers: int, seconds: float, tally: Tally) -> None:
        rows.append({"path": path, "workers": workers, "throws": args.throws,
                     "seconds": seconds, "throws_per_s": args.throws / seconds,
                     "same_tally": tally.same_as(reference)})

    seconds, reference = timed(lambda: one_thread(spec))
    row("this process, 1 thread", 1, seconds, reference)
    row(f"this process, {numba.config.NUMBA_NUM_THREADS} threads", 1,
        *timed(lambda: run_throws(scene, args.throws, **kwargs)))
    start_s, _ = timed(lambda: ray.init(address="local", num_cpus=2, include_dashboard=False))
    try:
        # load the kernel in both workers: one chunk each, two at a time
        run_throws(scene, 2 * args.chunk, ray="auto", workers=2, **kwargs)
        for workers in (1, 2):
            row(f"Ray, {workers} worker{'s' * (workers > 1)}", workers,
                *timed(lambda w=workers: run_throws(scene, args.throws, ray="auto", workers=w,
                                                    **kwargs)))
    finally:
        ray.shutdown()
    result = {
        "command": f"python benchmarks/ray_overhead.py --throws {args.throws} --chunk "
                   f"{args.chunk} --seed {args.seed}",
        "commit": code_version(), "timer": "wall clock", "ray_start_s": start_s,
        "ray": ray.__version__,
        "numba_threads": numba.config.NUMBA_NUM_THREADS, "cpu_count": os.cpu_count(),
        "load_average": os.getloadavg()[0], "numba": numba.__version__,
        "numpy": np.__version__, "python": platform.python_version(), "rows": rows,
    }
    write_json(RESULTS / "ray_overhead.json", result, indent=1)
    base = rows[0]["throws_per_s"]
    print(f"{result['command']}: {args.throws} default-d6 throws to a decided face, chunks of "
          f"{args.chunk}; Ray start {start_s:.1f} s (not counted); load average "
          f"{result['load_average']:.2f} on {os.cpu_count()} CPUs\n")
    print(markdown_table("path | throws/s | vs 1 thread here | same tally", (
        (r["path"], f"{r['throws_per_s']:.0f}", f"{r['throws_per_s'] / base:.2f}x",
         "yes" if r["same_tally"] else "NO") for r in rows)))


if __name__ == "__main__":
    main()

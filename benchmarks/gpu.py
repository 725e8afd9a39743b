"""The GPU kernel against the CPU kernel: die-steps/s and throws/s over batch sizes.

    python benchmarks/gpu.py                                  # GPU to 1e6 dice, CPU to 8192
    python benchmarks/gpu.py --max-batch 100000 --cpu-max-batch 2048 --budget 30

Two figures, as ``benchmarks/kernel_ab.py`` measures them: the paper scene
(``paper_scene()``, dt = 1e-4, the listing's throw with random spin, 0.5 s without a rest
stop) in die-steps/s, and the default scene's hand throws to a decided face
(``until="decided"``) in throws/s. Each at batch sizes 1000, 10^4, ... up to
``--max-batch`` on the GPU (``simulate(..., device="cuda")``) and up to ``--cpu-max-batch``
on the CPU (numba's threads: every core of this machine); a device stops growing its batch once
a run takes longer than ``--budget`` seconds. Wall-clock time of the whole ``simulate`` call
(the GPU's copies included), the best of ``--repeats`` after a warm-up run that compiles.
Without a GPU (or numba-cuda) it says so and measures the CPU side only. Prints a markdown
table and writes ``benchmarks/results/gpu.json``.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from functools import partial

import numba
from harness import benchmark_parser, command_line, write_json
from physics import hand_throws, paper_throws

from dice_env import Scene, State, simulate
from dice_env.provenance import code_version
from dice_env.simulation.paper import paper_scene

PAPER_T = 0.5  # s of the paper throw
FIGURES = {"paper": "paper scene (die-steps/s)", "decided": "default scene to a decided face "
                                                           "(throws/s)"}


def paper_case(n: int) -> tuple[Scene, State, int]:
    """The paper scene, ``n`` of its throws (physics.paper_throws), the die-steps of a run."""
    scene = paper_scene()
    return scene, paper_throws(n), n * round(PAPER_T / scene.step)


def decided_case(n: int) -> tuple[Scene, State, int]:
    """The default scene, ``n`` hand throws (physics.hand_throws), and the throws."""
    scene = Scene()
    return scene, hand_throws(scene, n, seed=1), n


CASES: dict[str, tuple[Callable, dict]] = {
    "paper": (paper_case, {"t_max": PAPER_T, "until": "t_max"}),
    "decided": (decided_case, {"until": "decided"}),
}


def best_rate(run: Callable[[], object], work: int, repeats: int) -> tuple[float, float]:
    """``work`` per second of ``run`` (the best of ``repeats``), and the slowest run's time."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return work / min(times), max(times)


def measure(device: str, batches: list[int], repeats: int, budget: float) -> dict:
    """Each figure's rate at each batch size on ``device``, until a run exceeds ``budget`` s."""
    table = {}
    for name, (make, kwargs) in CASES.items():
        scene, start, _ = make(min(64, batches[0]))
        simulate(scene, start, device=device, **kwargs)  # compiled (and warm) before timing
        table[name] = {}
        for n in batches:
            scene, start, work = make(n)
            rate, slowest = best_rate(partial(simulate, scene, start, device=device, **kwargs),
                                      work, repeats)
            table[name][n] = rate
            print(f"{device} {name} batch {n:,}: {rate:,.0f}/s ({slowest:.2f} s a run)",
                  flush=True)
            if slowest > budget:
                break
    return table


def gpu_missing() -> str | None:
    """Why ``device="cuda"`` cannot run here, or None when it can."""
    scene, start, _ = decided_case(1)
    try:
        simulate(scene, start, t_max=scene.step, device="cuda")
    except (ImportError, RuntimeError) as error:
        return str(error)
    return None


def sizes(top: int) -> list[int]:
    """1000, 10^4, ... below ``top``, then ``top``."""
    out = [n for n in (10**k for k in range(3, 7)) if n < top]
    return [*out, top]


def main() -> None:
    parser = benchmark_parser(__doc__, "gpu")
    parser.add_argument("--max-batch", type=int, default=1_000_000)
    parser.add_argument("--cpu-max-batch", type=int, default=8192)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--budget", type=float, default=60.0,
                        help="seconds a run may take before a device's batch stops growing")
    args = parser.parse_args()
    for name in ("max_batch", "cpu_max_batch", "repeats"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be >= 1")
    missing = gpu_missing()
    if missing:
        print(f"no GPU: {missing}\nmeasuring the CPU side only", flush=True)
    results = {"cpu": measure("cpu", sizes(args.cpu_max_batch), args.repeats, args.budget)}
    if not missing:
        results["cuda"] = measure("cuda", sizes(args.max_batch), args.repeats, args.budget)
    device_name = None
    if not missing:
        from numba import cuda

        device_name = getattr(cuda.get_current_device(), "name", "the CUDA simulator")
        device_name = device_name.decode() if isinstance(device_name, bytes) else device_name
    print(f"\nCPU: {numba.config.NUMBA_NUM_THREADS} numba threads ({os.cpu_count()} cores); "
          f"GPU: {device_name or 'none'}\n")
    columns = sorted({n for table in results.values() for rows in table.values() for n in rows})
    print("| figure | device | " + " | ".join(f"batch {n:,}" for n in columns) + " |")
    print("|---|---|" + "---|" * len(columns))
    for name, label in FIGURES.items():
        for device, table in results.items():
            cells = [f"{table[name][n]:,.0f}" if n in table[name] else "" for n in columns]
            print(f"| {label} | {device} | " + " | ".join(cells) + " |")
    write_json(args.out, {
        "command": command_line(), "commit": code_version(),
        "cpu_threads": numba.config.NUMBA_NUM_THREADS, "gpu": device_name,
        "no_gpu_reason": missing, "figures": FIGURES,
        "rates": {device: {name: {str(n): r for n, r in rows.items()}
                           for name, rows in table.items()}
                  for device, table in results.items()}}, indent=1)


if __name__ == "__main__":
    main()

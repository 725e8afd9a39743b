"""A user's first throws: import and each entry point's first call, cold and warm.

    python benchmarks/cold_start.py             # cold (an empty numba cache), then warm
    python benchmarks/cold_start.py --warm-only # the cache as it is
    python benchmarks/cold_start.py --suite     # also: precompile, then the README's tests
    python benchmarks/cold_start.py --suite --slow  # and then the slow suite, as CI runs it

Each run is a fresh process that imports ``dice_env`` and calls, one after another, the entry
points below, timing each first call; the cold run gets an empty ``NUMBA_CACHE_DIR`` (every
kernel a call needs compiles then), the warm run the cache the cold run left. The parallel
loops' first calls (2 threads, :data:`THREADED`) and a new user's first throw, import included
(:data:`FIRST_THROWS`), are timed each in a process and an empty cache of its own. ``--suite``
then times, in a second empty cache, ``python -m dice_env.simulation.precompile`` and the README's
test command after it (``pytest -n auto``), and with ``--slow`` CI's slow suite after that
(``pytest -n auto -m slow``). Prints a table and writes
``benchmarks/results/cold_start.json`` (``--out`` to change); a cold run also writes each CPU
kernel's first-call time into ``dice_env/simulation/compile_times.json``, which the compile
notice quotes (:func:`compile_times`).
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness import benchmark_parser, command_line, write_json

from dice_env.provenance import code_version
from dice_env.simulation.compile_notice import TIMES

ROOT = Path(__file__).resolve().parents[1]

# (name, code) run in order in one process; each code may use what the earlier ones set
ENTRY_POINTS = (
    ("import dice_env", "import numpy as np; import dice_env; from dice_env import Scene, "
     "State, simulate; scene = Scene(); rng = np.random.default_rng(0); "
     "hand = State.release(scene, np.tile([0.0, 0.0, 0.1], (64, 1)), "
     "rng.normal(0, 0.5, (64, 3)), rng.normal(0, 30, (64, 3)))"),
    ("simulate to rest (64 throws)", "simulate(scene, hand)"),
    ("simulate to a decided face", "simulate(scene, hand, until='decided')"),
    ("the paper scene (vector kernel)", "from dice_env.simulation.paper import paper_scene; "
     "ps = paper_scene().with_(t_max=1.0); simulate(ps, State.release(ps, np.tile([0.0, 0.0, "
     "3.0], (64, 1)), rng.normal(0, 1, (64, 3)), rng.normal(0, 3, (64, 3))))"),
    ("gym.make + env.step", "import gymnasium as gym; env = gym.make('DiceThrow-v0'); "
     "env.reset(seed=0); env.step(env.action_space.sample())"),
    ("make_vec + step (8 envs)", "venv = gym.make_vec('DiceThrow-v0', num_envs=8, "
     "vectorization_mode=None); venv.reset(seed=0); venv.step(venv.action_space.sample())"),
    ("simulate_group (two d6 in the tray)", "from dice_env.simulation.group import GroupState, "
     "simulate_group; from dice_env.model.surroundings import tray; ts = Scene(walls=tray(), "
     "t_max=2.0); simulate_group(ts, (dice_env.Die(),) * 2, GroupState.of([State.release("
     "ts, np.tile([0.0, y, 0.1], (4, 1)), rng.normal(0, 0.5, (4, 3)), rng.normal(0, 30, "
     "(4, 3))) for y in (-0.015, 0.015)]), until='decided')"),
)

# the parallel loops (2 threads, batches above ``simulate.SERIAL_FIRST``), each the first
# call in a process and an empty cache of its own
THREADED = (
    ("simulate on 2 threads (1024 throws)", "simulate(scene, State.release(scene, np.tile("
     "[0.0, 0.0, 0.1], (1024, 1)), rng.normal(0, 0.5, (1024, 3)), rng.normal(0, 30, "
     "(1024, 3))), until='decided', num_threads=2)"),
    ("the paper scene on 2 threads", "from dice_env.simulation.paper import paper_scene; "
     "ps = paper_scene().with_(t_max=0.2); simulate(ps, State.release(ps, np.tile([0.0, 0.0, "
     "3.0], (1024, 1)), rng.normal(0, 1, (1024, 3)), rng.normal(0, 3, (1024, 3))), num_threads=2)"),
    ("simulate_group on 2 threads (512 throws)",
     "from dice_env.simulation.group import GroupState, simulate_group; "
     "from dice_env.model.surroundings import tray; ts = Scene(walls=tray(), "
     "t_max=0.05); simulate_group(ts, (dice_env.Die(),) * 2, GroupState.of([State.release("
     "ts, np.tile([0.0, y, 0.1], (512, 1)), rng.normal(0, 0.5, (512, 3)), rng.normal(0, 30, "
     "(512, 3))) for y in (-0.015, 0.015)]), num_threads=2)"),
)
# a new user's first throw, each in its own process and empty cache (import included)
FIRST_THROWS = (
    ("import + first simulate", ENTRY_POINTS[0][1] + "; " + ENTRY_POINTS[1][1]),
    ("import + gym.make + first step", "import gymnasium as gym; import dice_env; "
     "env = gym.make('DiceThrow-v0'); env.reset(seed=0); env.step(env.action_space.sample())"),
)

PROBE = """
import json, sys, time
times = []
for name, code in json.loads(sys.argv[1]):
    start = time.perf_counter()
    exec(code)
    times.append(time.perf_counter() - start)
print(json.dumps(times))
"""


def run(cache: Path, entry_points: tuple = ENTRY_POINTS) -> tuple[list[float], list[str]]:
    """Seconds of each entry point's first call in a fresh process with ``cache``.

    Also the compile notices the process wrote on stderr
    (:mod:`dice_env.simulation.compile_notice`).
    """
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "DICE_ENV_QUIET_COMPILE": ""}
    done = subprocess.run([sys.executable, "-c", PROBE, json.dumps(entry_points)], cwd=ROOT,
                          env=env, capture_output=True, text=True, check=True)
    notices = [line for line in done.stderr.splitlines() if line.startswith("dice_env: ")]
    return json.loads(done.stdout.strip().splitlines()[-1]), notices


def alone(entry_points: tuple, setup: tuple = ()) -> tuple[dict[str, list], list[str]]:
    """Each entry point's first call in a process and an empty cache of its own.

    After the entry points ``setup`` (untimed). Returns the names and seconds, and the
    compile notices.
    """
    seconds, notices = [], []
    for entry_point in entry_points:
        with tempfile.TemporaryDirectory(prefix="numba-cache-") as folder:
            times, said = run(Path(folder), (*setup, entry_point))
        seconds.append(times[-1])
        notices += said
    return {"entry_points": [name for name, _ in entry_points], "seconds": seconds}, notices


def suite(cache: Path, slow: bool) -> dict[str, object]:
    """Seconds of the precompile, then the tests (and the ``slow`` suite), ``cache`` empty first.

    The summaries are pytest's last lines, one per suite run.
    """
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    seconds, summaries = {}, []
    tests = ["-m", "pytest", "-n", "auto", "-p", "no:cacheprovider"]
    commands = [("precompile", ["-m", "dice_env.simulation.precompile"]), ("tests", tests)]
    for name, command in commands + ([("slow", [*tests, "-m", "slow"])] if slow else []):
        start = time.perf_counter()
        done = subprocess.run([sys.executable, *command], cwd=ROOT, env=env,
                              capture_output=True, text=True)
        seconds[name] = time.perf_counter() - start
        if name != "precompile":
            summaries.append(done.stdout.strip().splitlines()[-1])
        if done.returncode != 0:  # the times still count; the summary says what failed
            print(done.stdout[-4000:], done.stderr[-2000:], file=sys.stderr)
            break
    return {"seconds": seconds, "summary": summaries[0] if summaries else "",
            "slow_summary": summaries[1] if len(summaries) > 1 else None,
            "returncode": done.returncode}


# Each CPU kernel (its name in the compile notice) and the first call that compiles it: the run
# ("cold" or "threads") and the entry point's index there
KERNEL_FIRST_CALLS = {
    "the die's kernel": ("cold", 1),
    "the paper scene's kernel": ("cold", 3),
    "the kernel of several dice": ("cold", 6),
    "the die's kernel on threads": ("threads", 0),
    "the paper scene's kernel on threads": ("threads", 1),
    "the kernel of several dice on threads": ("threads", 2),
}


def compile_times(record: dict) -> dict:
    """The compile notice's times (s, one decimal) from a cold run's ``record``."""
    seconds = {"cold": record["seconds"]["cold"], "threads": record["threads"]["seconds"]}
    return {"command": record["command"], "cores": record["cpus"],
            "seconds": {what: round(seconds[run][i], 1)
                        for what, (run, i) in KERNEL_FIRST_CALLS.items()}}


def main() -> None:
    parser = benchmark_parser(__doc__, "cold_start")
    parser.add_argument("--warm-only", action="store_true",
                        help="time with the cache as it is (NUMBA_CACHE_DIR or numba's own)")
    parser.add_argument("--suite", action="store_true",
                        help="also time precompile and the test suite in an empty cache")
    parser.add_argument("--slow", action="store_true",
                        help="with --suite: then the slow suite too (as CI runs it)")
    args = parser.parse_args()
    if args.slow and not args.suite:
        parser.error("--slow times the slow suite after the tests: it needs --suite")
    runs, notices = {}, {}
    started = time.time()
    if args.warm_only:
        cache = Path(os.environ.get("NUMBA_CACHE_DIR", ROOT / "dice_env" / "__pycache__"))
        runs["warm"], notices["warm"] = run(cache)
    else:
        with tempfile.TemporaryDirectory(prefix="numba-cache-") as folder:
            runs["cold"], notices["cold"] = run(Path(folder))
            runs["warm"], notices["warm"] = run(Path(folder))
        threads, notices["threads"] = alone(THREADED, (("set-up", ENTRY_POINTS[0][1]),))
        first, _ = alone(FIRST_THROWS)
    tests = None
    if args.suite:
        with tempfile.TemporaryDirectory(prefix="numba-cache-") as folder:
            tests = suite(Path(folder), args.slow)
    names = [name for name, _ in ENTRY_POINTS]
    print(f"{'entry point':40s}" + "".join(f"{kind:>10s}" for kind in runs))
    for i, name in enumerate(names):
        print(f"{name:40s}" + "".join(f"{times[i]:9.1f}s" for times in runs.values()))
    print(f"{'all, one after another':40s}" + "".join(f"{sum(t):9.1f}s" for t in runs.values()))
    if not args.warm_only:
        for part in (threads, first):
            for name, seconds in zip(part["entry_points"], part["seconds"], strict=True):
                print(f"{name:40s}{seconds:9.1f}s")
    for kind, lines in notices.items():
        print(f"{kind}: {len(lines)} compile notice(s)" + "".join(f"\n  {line}" for line in lines))
    if tests is not None:
        print(f"{'precompile, empty cache':40s}{tests['seconds']['precompile']:9.1f}s")
        print(f"{'then pytest -n auto':40s}{tests['seconds']['tests']:9.1f}s  "
              f"({tests['summary']})")
        if "slow" in tests["seconds"]:
            print(f"{'then pytest -n auto -m slow':40s}{tests['seconds']['slow']:9.1f}s  "
                  f"({tests['slow_summary']})")
    commit = code_version()
    record = {"command": command_line(),
              "commit": commit, "entry_points": names, "seconds": runs, "notices": notices,
              "threads": None if args.warm_only else threads,
              "first_throw": None if args.warm_only else first,
              "suite": tests, "cpus": os.cpu_count(),
              "load_average": os.getloadavg(), "python": platform.python_version(),
              "started": time.strftime("%Y-%m-%d %H:%M", time.gmtime(started))}
    write_json(args.out, record)
    print(f"wrote {args.out}")
    if not args.warm_only:
        write_json(TIMES, compile_times(record))
        print(f"wrote {TIMES}")


if __name__ == "__main__":
    main()

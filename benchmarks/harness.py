"""What the benchmarks share: their command line, a timer, the command run, the JSON written."""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

from dice_env.disk import write_atomically

RESULTS = Path(__file__).resolve().parent / "results"
# The benchmarks run as scripts from a checkout (``python benchmarks/NAME.py``), which puts
# benchmarks/ on the path: the checkout's root too, for the agents/ that some of them import.
ROOT = str(RESULTS.parents[1])
if ROOT not in sys.path:
    sys.path.insert(1, ROOT)


def benchmark_parser(doc: str, name: str, quick: str | None = None) -> argparse.ArgumentParser:
    """A parser with ``--out`` (default ``results/NAME.json``) and, given its help, ``--quick``."""
    made = argparse.ArgumentParser(description=doc.split("\n")[0])
    if quick is not None:
        made.add_argument("--quick", action="store_true", help=quick)
    made.add_argument("--out", type=Path, default=RESULTS / f"{name}.json")
    return made


def parse_with_mujoco(parser: argparse.ArgumentParser) -> argparse.Namespace:
    """``parser``'s arguments with ``--no-mujoco``; without it, MuJoCo must be installed."""
    parser.add_argument("--no-mujoco", action="store_true", help="skip the MuJoCo comparison")
    args = parser.parse_args()
    if not args.no_mujoco and importlib.util.find_spec("mujoco") is None:
        parser.error("mujoco is not installed (pip install -e '.[bench]'); --no-mujoco leaves "
                     "the MuJoCo comparison out")
    return args


def command_line(placeholders: dict[Path, str] | None = None) -> str:
    """The command line that ran this benchmark, from the repository root.

    An argument naming a path in ``placeholders`` is written as its placeholder (``BASE`` for
    the other tree of ``kernel_ab.py``): a path on this machine means nothing elsewhere.
    """
    named = {path.resolve(): name for path, name in (placeholders or {}).items()}
    args = [named.get(Path(arg).resolve(), arg) for arg in sys.argv[1:]]
    return " ".join(["python", f"benchmarks/{Path(sys.argv[0]).name}", *args])


def timed(fn: Callable[[], object], repeats: int, threads: int = 1) -> tuple[float, object]:
    """Smallest time of ``repeats`` calls of ``fn`` (s), and the last call's result.

    Work on one thread (``threads=1``) is timed by this process's CPU time, which other
    processes on shared cores do not inflate (not the calling thread's: a long ``simulate``
    runs its kernel on a worker thread while the caller waits); parallel work by the wall clock.
    """
    clock = time.process_time if threads == 1 else time.perf_counter
    times = []
    for _ in range(repeats):
        start = clock()
        result = fn()
        times.append(clock() - start)
    return min(times), result


def write_json(out: Path, record: dict, indent: int = 2) -> None:
    """Write ``record`` to ``out`` as JSON, whole or not at all, creating its folder."""
    out.parent.mkdir(parents=True, exist_ok=True)
    write_atomically(out, (json.dumps(record, indent=indent) + "\n").encode())

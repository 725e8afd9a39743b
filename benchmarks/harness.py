"""What the benchmarks share: their command line, the command that ran, the JSON they write."""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


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


def command_line() -> str:
    """The command line that ran this benchmark, from the repository root."""
    return " ".join(["python", f"benchmarks/{Path(sys.argv[0]).name}", *sys.argv[1:]])


def write_json(out: Path, record: dict, indent: int = 2) -> None:
    """Write ``record`` to ``out`` as JSON, creating its folder."""
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(record, indent=indent) + "\n")

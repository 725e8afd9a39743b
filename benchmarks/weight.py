"""Lines of ``dice_env/`` per layer, in this tree and at another commit.

    python benchmarks/weight.py                 # this tree only
    python benchmarks/weight.py --against REV   # and at REV (any git revision)
    python benchmarks/weight.py --against REV --features 'dice_env/viewer/*' ...

Counts as ``wc -l`` does, over the tracked ``dice_env/**/*.py``. ``--features`` names (as
globs) the modules that features added since REV brought, so that a refactor's weight can be
compared without them; ``git log --follow --diff-filter=A -- PATH`` tells which commit added a
module. Writes ``benchmarks/results/weight.json``.
"""

from __future__ import annotations

import fnmatch
import subprocess
from collections import Counter
from pathlib import Path

from harness import benchmark_parser, command_line, write_json

from dice_env.provenance import code_version

ROOT = Path(__file__).resolve().parent.parent


def _git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, check=True, capture_output=True,
                          text=True).stdout


def lines(rev: str | None = None) -> dict[str, int]:
    """Lines of each tracked ``dice_env/**/*.py`` in the work tree, or at ``rev``."""
    if rev is None:
        paths = _git("ls-files", "dice_env/*.py").split()
        return {p: len((ROOT / p).read_bytes().splitlines()) for p in paths}
    paths = [p for p in _git("ls-tree", "-r", "--name-only", rev, "dice_env").split()
             if p.endswith(".py")]
    return {p: len(_git("show", f"{rev}:{p}").encode().splitlines()) for p in paths}


def _layer(path: str) -> str:
    parts = path.split("/")
    return parts[1] if len(parts) > 2 else "(top level)"


def main(argv: list[str] | None = None) -> None:
    """Print the table and write the JSON."""
    parser = benchmark_parser(__doc__, "weight")
    parser.add_argument("--against", metavar="REV", help="a git revision to compare with")
    parser.add_argument("--features", nargs="*", default=[], metavar="GLOB",
                        help="modules added by features since REV, counted apart")
    args = parser.parse_args(argv)
    now = lines()
    result: dict[str, object] = {"command": command_line(), "commit": code_version(ROOT),
                                 "total": sum(now.values()),
                                 "layers": dict(sorted(_by_layer(now).items()))}
    print(f"{'layer':<14}{'lines':>8}")
    for layer, n in result["layers"].items():
        print(f"{layer:<14}{n:>8}")
    print(f"{'total':<14}{result['total']:>8}")
    if args.against:
        then = lines(args.against)
        added = {p: n for p, n in now.items()
                 if any(fnmatch.fnmatch(p, glob) for glob in args.features)}
        base, rest = sum(then.values()), sum(now.values()) - sum(added.values())
        result["against"] = {"rev": _git("rev-parse", "--short", args.against).strip(),
                             "total_then": base, "without_features": rest, "features": added}
        print(f"{'at ' + args.against:<28}{base:>8}")
        print(f"{'this tree':<28}{sum(now.values()):>8} {sum(now.values()) / base - 1:+.1%}")
        if added:
            print(f"{'  without the features':<28}{rest:>8} {rest / base - 1:+.1%}")
            print(f"{'  features (' + str(len(added)) + ' modules)':<28}{sum(added.values()):>8}")
    write_json(args.out, result)


def _by_layer(counts: dict[str, int]) -> Counter:
    totals: Counter = Counter()
    for path, n in counts.items():
        totals[_layer(path)] += n
    return totals


if __name__ == "__main__":
    main()

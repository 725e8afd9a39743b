"""Tampered, truncated and crafted recordings: ``--replay`` of each ends in 0, 1 or 2 with a reason.

Seeded: a few hundred files made from a page of one die, a ``.glb`` of two dice and a ``.json``
of both: cut short, bytes overwritten, a value of the recordings replaced (wrong types, sizes,
NaN, infinities, extremes, deep nesting) or deleted, and files crafted whole. Each is replayed
in this process through the command line's own ``main``, within :data:`BOUND_S` seconds:
exit 0 (faces as recorded), 1 (a face differs) or 2 with a one-line reason, never a traceback;
the first file of each status is replayed from a shell too.
"""

from __future__ import annotations

import json
import math
import os
import re
import struct
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dice_env import Die, Scene, State
from dice_env.model.surroundings import walls
from dice_env.simulation.group import GroupState
from dice_env.viewer import record, save, write_html
from dice_env.viewer.__main__ import main

CASES = 300
SEED = 47
BOUND_S = 30.0  # s a file's replay may take at most (a crafted scene may run the step limit)
USAGE = "python -m dice_env.viewer: error: argument --replay: "
DEEP = "__deep__"  # a value replaced by 100,000 nested lists in the file's text
VALUES = [None, True, "", "x", 0, -1, 7, 1e-300, 5e-324, 1e308, math.nan, math.inf, -math.inf,
          2**70, [], {}, [[[]]], {"type": "Scene"}, DEEP]


@pytest.fixture(scope="module")
def originals(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """The files tampered with: a page of one d6, a ``.glb`` of two dice, a ``.json`` of both."""
    gltf = pytest.importorskip("dice_env.viewer.gltf")
    folder = tmp_path_factory.mktemp("originals")
    scene = Scene(walls=walls("tray"))
    one = State.release(scene, np.array([0.0, 0.0, 0.05]), np.array([0.5, 0.2, 0.0]),
                        np.array([10.0, 5.0, 3.0]))
    other = State.release(scene, np.array([0.0, 0.03, 0.05]), np.array([0.4, -0.2, 0.0]),
                          np.array([-8.0, 5.0, 3.0]))
    single = record(scene, scene.die, one, fps=20.0)[0]
    pair = record(scene, (Die(), Die.standard("d8")), GroupState.of([one, other]), fps=20.0)[0]
    paths = [write_html(single, folder / "one.html"), gltf.write_glb(pair, folder / "two.glb"),
             save([single, pair], folder / "both.json")]
    return {path.suffix: path.read_bytes() for path in paths}


def test_every_tampered_file_ends_in_0_1_or_2_with_a_reason(originals, tmp_path, capsys):
    rng = np.random.default_rng(SEED)
    statuses, slowest, first = Counter(), 0.0, {}
    for k in range(CASES):
        suffix, content, how = _tampered(rng, originals)
        path = tmp_path / f"case{k}{suffix}"
        path.write_bytes(content)
        start = time.perf_counter()
        status = _replay(path)
        took = time.perf_counter() - start
        error = capsys.readouterr().err
        what = f"case {k} ({how}, {path.name})"
        assert status in (0, 1, 2), f"{what}: exit {status}"
        assert took < BOUND_S, f"{what}: {took:.1f} s"
        if status == 1:
            assert error.startswith("the replay landed other faces: "), what
        if status == 2:
            assert error.splitlines()[-1].startswith(USAGE), f"{what}: {error}"
        statuses[status] += 1
        slowest = max(slowest, took)
        first.setdefault(status, path)
        if first[status] != path:
            path.unlink()
    print(f"{CASES} files: exit statuses {dict(statuses)}, slowest {slowest:.2f} s")
    assert statuses[2] > CASES // 2 and statuses[0] + statuses[1] > 10  # both reached
    for status, path in first.items():  # the same status from a shell
        run = subprocess.run([sys.executable, "-m", "dice_env.viewer", "--replay", str(path)],
                             capture_output=True, text=True, timeout=120, env=os.environ)
        assert run.returncode == status and "Traceback" not in run.stderr, run.stderr


def _replay(path: Path) -> int:
    """The exit status of ``python -m dice_env.viewer --replay path``, in this process."""
    try:
        return main(["--replay", str(path)])
    except SystemExit as exit_info:
        return exit_info.code


def _tampered(rng: np.random.Generator, originals: dict[str, bytes]) -> tuple[str, bytes, str]:
    """A file suffix, its content and how it was made."""
    suffix = str(rng.choice(sorted(originals)))
    whole = originals[suffix]
    how = str(rng.choice(["cut", "bytes", "value", "value", "value", "delete", "crafted"]))
    if how == "cut":
        return suffix, whole[:int(rng.integers(len(whole)))], how
    if how == "bytes":
        content = bytearray(whole)
        for at in rng.integers(len(whole), size=int(rng.integers(1, 8))):
            content[at] = int(rng.integers(256))
        return suffix, bytes(content), how
    if how == "crafted":
        return _crafted(rng)
    data = _data(suffix, whole)
    item = data[int(rng.integers(len(data)))]
    where, key = _somewhere(rng, item)
    if how == "delete" and isinstance(where, dict):
        del where[key]
    else:
        where[key] = _value(rng, where[key])
        how = f"value {key!r}"
    return suffix, _with(suffix, whole, data), how


def _somewhere(rng: np.random.Generator, item: Any) -> tuple[Any, Any]:
    """A container within ``item`` and one of its keys (or indices), picked level by level."""
    where, key = item, None
    while True:
        keys = list(where) if isinstance(where, dict) else list(range(len(where)))
        key = keys[int(rng.integers(len(keys)))]
        inner = where[key]
        if not isinstance(inner, (dict, list)) or not inner or rng.random() < 0.3:
            return where, key
        where = inner


def _value(rng: np.random.Generator, old: Any) -> Any:
    """A value in place of ``old``: one of :data:`VALUES`, or ``old`` one shorter or longer."""
    if isinstance(old, list) and old and rng.random() < 0.3:
        return old[:-1] if rng.random() < 0.5 else [*old, old[-1]]
    if isinstance(old, (int, float)) and not isinstance(old, bool) and rng.random() < 0.3:
        return old * float(rng.choice([-1.0, 0.5, 2.0, 1e6]))
    return VALUES[int(rng.integers(len(VALUES)))]


def _crafted(rng: np.random.Generator) -> tuple[str, bytes, str]:
    """A file made whole: empty, random, deeply nested, a bare glTF header and the like."""
    deep = b"[" * 100_000 + b"]" * 100_000
    noise = rng.integers(256, size=int(rng.integers(1, 4096)), dtype=np.uint8).tobytes()
    header = b"glTF" + struct.pack("<II", 2, 12)
    made = {".json": [b"", b"[]", b"{}", b"null", b'"x"', b"[1]", b"[[]]", deep, noise,
                      b"\xff\xfe[]"],
            ".glb": [b"", header, header + b"\0" * 8, b"glTF" + struct.pack("<III", 2, 28, 8)
                     + b"JSON{}      ", noise, b"glTF" + noise],
            ".html": [b"", noise, b"<html></html>",
                      b'<script type="application/json" id="dice-env-throws">' + deep
                      + b"</script>",
                      b'<script type="application/json" id="dice-env-throws">[]</script>']}
    suffix = str(rng.choice(sorted(made)))
    return suffix, made[suffix][int(rng.integers(len(made[suffix])))], "crafted"


def _data(suffix: str, whole: bytes) -> list[dict[str, Any]]:
    """The recordings' data in a file's content."""
    if suffix == ".json":
        return json.loads(whole)
    if suffix == ".html":
        return json.loads(_PAGE.search(whole.decode()).group(1))["recordings"]
    gltf = json.loads(whole[20:20 + struct.unpack_from("<I", whole, 12)[0]])
    return json.loads(gltf["asset"]["extras"]["recordings"])


def _with(suffix: str, whole: bytes, data: list[dict[str, Any]]) -> bytes:
    """``whole`` with its recordings' data replaced by ``data``."""
    text = _deepened(json.dumps(data))
    if suffix == ".json":
        return text.encode()
    if suffix == ".html":
        page = whole.decode()
        match = _PAGE.search(page)
        view = json.dumps({"recordings": "@"}).replace('"@"', text).replace("<", "\\u003c")
        return (page[:match.start(1)] + view + page[match.end(1):]).encode()
    size = struct.unpack_from("<I", whole, 12)[0]
    gltf = json.loads(whole[20:20 + size])
    gltf["asset"]["extras"]["recordings"] = text
    chunk = json.dumps(gltf).encode()
    chunk += b" " * (-len(chunk) % 4)
    rest = whole[20 + size:]
    return (b"glTF" + struct.pack("<III", 2, 20 + len(chunk) + len(rest), len(chunk)) + b"JSON"
            + chunk + rest)


def _deepened(text: str) -> str:
    """``text`` with every :data:`DEEP` value as 100,000 nested lists."""
    return text.replace(json.dumps(DEEP), "[" * 100_000 + "]" * 100_000)


_PAGE = re.compile(r'<script type="application/json" id="dice-env-throws">(.*?)</script>', re.S)

"""The wheel works on its own: built from the tracked files, installed in a fresh virtualenv.

Without extras it throws dice (the README's "Throw dice"), steps every registered task and
writes a viewer page from a folder outside the checkout, with no torch, SB3 or matplotlib and
no top-level name but ``dice_env``; with the ``train`` extra, ``train.py`` trains from the
checkout. Slow: it installs packages (from pip's cache or the package index).
"""

import os
import re
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TORCH = "torch==2.13.0"  # as .ci/setup: the CPU build on this machine's disk

pytestmark = pytest.mark.slow


def run(*cmd: object, cwd: Path, env: dict | None = None, timeout: float = 900) -> str:
    done = subprocess.run(list(map(str, cmd)), cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, env=env)
    assert done.returncode == 0, f"{cmd}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return done.stdout


def readme_snippet(title: str) -> str:
    """The first python block after ``title`` in the README."""
    text = (ROOT / "README.md").read_text()
    return re.search(r"```python\n(.*?)```", text[text.index(title):], re.S).group(1)


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    """A fresh virtualenv holding the wheel built from a copy of the tracked files."""
    base = tmp_path_factory.mktemp("wheel")
    tracked = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True,
                             check=True).stdout.decode().split("\0")
    source = base / "source"
    for name in filter(None, tracked):
        if (ROOT / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            (source / name).write_bytes((ROOT / name).read_bytes())
    run(sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
        "-w", base / "dist", source, cwd=base)
    (wheel,) = (base / "dist").glob("dice_env-*.whl")
    run(sys.executable, "-m", "venv", base / "venv", cwd=base)
    python = base / "venv" / "bin" / "python"
    run(python, "-m", "pip", "install", "-q", wheel, cwd=base)
    outside = base / "user"
    outside.mkdir()
    return python, wheel, outside


def test_the_wheel_installs_only_dice_env(venv):
    _, wheel, _ = venv
    with zipfile.ZipFile(wheel) as archive:
        top = {name.split("/")[0] for name in archive.namelist()}
    assert {t for t in top if not t.endswith(".dist-info")} == {"dice_env"}


def test_throw_step_and_page_without_extras(venv):
    python, _, outside = venv
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    run(python, "-c", readme_snippet("**Throw dice**"), cwd=outside, env=env)
    run(python, "-c", textwrap.dedent("""
        import importlib.util, sys
        import gymnasium as gym
        import numpy as np
        import dice_env
        from dice_env.envs import TASKS
        assert dice_env.__file__.startswith(sys.prefix), dice_env.__file__
        for task in TASKS:
            env = gym.make(task.id)
            env.reset(seed=0)
            env.step(np.zeros(env.action_space.shape))
        absent = [m for m in ("torch", "stable_baselines3", "matplotlib", "agents", "studies")
                  if importlib.util.find_spec(m) is not None]
        assert not absent, absent
    """), cwd=outside, env=env)
    run(python, "-m", "dice_env.viewer", "--out", "page.html", cwd=outside, env=env)
    assert (outside / "page.html").stat().st_size > 100_000
    assert not list(Path(sys.prefix).glob("runs")) and not (outside / "docs").exists()


def test_train_extra_trains_from_the_checkout(venv, tmp_path):
    python, wheel, _ = venv
    run(python, "-m", "pip", "install", "-q", TORCH, cwd=tmp_path)
    run(python, "-m", "pip", "install", "-q", f"dice_env[train] @ {wheel.as_uri()}",
        cwd=tmp_path)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env |= {"NUMBA_NUM_THREADS": "1", "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    out = run(python, ROOT / "train.py", "--total-timesteps", 256, "--runs", tmp_path,
              "--name", "wheel", "--n-envs", 64, "--eval-freq", 128, "--eval-episodes", 64,
              "--eval-throws", 60, "--oracle-observations", 1, "--robustness-throws", 12,
              "--gifs", 0, "--no-progress", cwd=tmp_path, env=env)
    assert (tmp_path / "wheel" / "report.md").exists(), out

"""The compile notice: a line on stderr when a kernel compiles, none when the cache is warm."""

import json
import os
import pickle
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from dice_env import Scene, State, simulate
from dice_env.physics import group_kernel, kernel, vector_kernel
from dice_env.simulation import precompile
from dice_env.simulation import simulate as simulate_module
from dice_env.simulation.compile_notice import QUIET, TIMES, measured_times
from dice_env.simulation.simulate import COMPILES

ROOT = Path(__file__).resolve().parents[1]

KERNEL = textwrap.dedent("""
    from numba import njit

    @njit(cache=True)
    def double(x):
        return 2 * x
""")
CALL = textwrap.dedent("""
    import sys
    sys.path.insert(0, sys.argv[1])
    from dice_env.simulation.compile_notice import announce
    from tiny_kernel import double
    for _ in range(2):  # said once per process
        announce(double, (3,), "the tiny kernel", 120.0)
        assert double(3) == 6
    announce(double, (4,), "the tiny kernel, compiled", 120.0)  # compiled here: quiet
    announce(double, (0.5,), "the tiny kernel for floats", 120.0)  # another signature
    assert double(0.5) == 1.0
""")


def first_calls(folder, cache, **env):
    """stderr of a fresh process that announces and calls a cached kernel in ``folder``."""
    done = subprocess.run([sys.executable, "-c", CALL, str(folder)], capture_output=True,
                          text=True, check=True, env={
                              **os.environ, "NUMBA_CACHE_DIR": str(cache), QUIET: "", **env})
    return done.stderr


def test_a_kernel_is_announced_once_when_it_compiles_and_not_when_cached(tmp_path):
    (tmp_path / "tiny_kernel.py").write_text(KERNEL)
    cold = first_calls(tmp_path, tmp_path / "cache")
    assert cold.count("dice_env: compiling") == 2, cold
    assert "compiling the tiny kernel (first use with this numba cache: about 2 min on 2 " \
           f"cores, then cached; {QUIET}=1 silences this)" in cold
    assert "compiling the tiny kernel for floats" in cold
    assert first_calls(tmp_path, tmp_path / "cache") == ""  # the cache is warm


@pytest.mark.parametrize("quiet", ["1", "yes"])
def test_the_notice_is_silenced_by_the_environment(tmp_path, quiet):
    (tmp_path / "tiny_kernel.py").write_text(KERNEL)
    assert first_calls(tmp_path, tmp_path / "cache", **{QUIET: quiet}) == ""


def test_every_cpu_kernel_is_cached_and_has_a_time():
    cores, seconds = measured_times()
    assert cores >= 1
    for loop, what in COMPILES.items():
        assert loop.py_func.__module__.startswith("dice_env.")
        assert loop._cache._cache_file is not None, what
        assert seconds[what] > 2.0, what


def test_precompile_compiles_every_cpu_kernel_parallel_and_serial():
    for compile_kernel in precompile.KERNELS.values():
        compile_kernel()
    loops = (kernel.simulate_serial, vector_kernel.simulate_serial,
             group_kernel.simulate_groups_serial, *COMPILES)
    if precompile.THREADS < 2:
        loops = loops[:3]  # one thread never starts the parallel loops
    for loop in loops:
        assert loop.overloads, loop
    for loop in COMPILES:  # compiled in this process, or loaded from the cache with another
        assert loop.overloads or loop._cache._cache_file._load_index(), loop  # loop: on disk


def test_the_announced_times_are_the_measured_ones():
    """The notice's times are ``benchmarks/cold_start.py``'s cold run, one per CPU kernel."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from cold_start import compile_times

    measured = json.loads((ROOT / "benchmarks/results/cold_start.json").read_text())
    assert json.loads(TIMES.read_text()) == compile_times(measured)
    assert set(measured_times()[1]) == set(COMPILES.values())


CUT = textwrap.dedent("""
    import sys
    sys.path.insert(0, sys.argv[1])
    from dice_env.simulation.compile_notice import cache_hint
    from tiny_kernel import double
    with cache_hint(double):
        double(3)
""")


@pytest.mark.parametrize("suffix", [".nbc", ".nbi"])
def test_a_cache_file_cut_short_names_the_folder_to_delete(tmp_path, suffix):
    (tmp_path / "tiny_kernel.py").write_text(KERNEL)
    first_calls(tmp_path, tmp_path / "cache")  # compiled into the cache
    cached = sorted((tmp_path / "cache").rglob(f"*{suffix}"))[0]  # .1.nbc: the ints' code
    cached.write_bytes(cached.read_bytes()[:len(cached.read_bytes()) // 2])
    done = subprocess.run([sys.executable, "-c", CUT, str(tmp_path)], capture_output=True,
                          text=True, env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")})
    last = done.stderr.splitlines()[-1]
    assert done.returncode == 1 and last.startswith("RuntimeError: numba could not read its "
                                                    "cached double (pickle data was truncated)")
    assert f"delete the folder {cached.parent} " in last


def test_simulate_names_the_cache_folder_of_a_kernel_it_cannot_load(monkeypatch):
    def cut(*args, **kwargs):
        raise pickle.UnpicklingError("pickle data was truncated")

    monkeypatch.setattr(simulate_module, "_run_interruptibly", cut)
    scene = Scene(t_max=0.01)
    with pytest.raises(RuntimeError, match="numba could not read its cached simulate_serial") \
            as error:
        simulate(scene, State.release(scene, [0.0, 0.0, 0.05], [1.0, 0.0, 0.0]), num_threads=1)
    assert f"delete the folder {kernel.simulate_serial._cache._cache_path} " in str(error.value)

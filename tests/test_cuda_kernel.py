"""The GPU kernel (``simulate(..., device="cuda")``) against the CPU kernel.

Without a GPU, numba's CUDA simulator runs the CUDA kernel in a child process
(``NUMBA_ENABLE_CUDASIM`` must be set before ``numba.cuda`` is first imported, and
``NUMBA_DISABLE_JIT`` makes the shared pieces of ``dice_env.physics.kernel`` plain Python there
too): the kernel's indexing, its per-thread scratch and the copies to and from the device, on the
physics' own source. Python floats are IEEE doubles, stepped in the same operations and order
as the compiled CPU kernel (which fuses no multiply-add) with the same ``libm``, so the two
agree bit for bit (:data:`SIM_TOLERANCE`), and the outcomes must be equal. On a real GPU
(:func:`test_on_the_gpu`, run only where one is) FMAs and libdevice's ``sin`` differ from the
CPU in the last bit, which contacts amplify: :data:`GPU_TOLERANCE` on the same short runs, a
bound not yet measured on a GPU. :func:`test_compiles_for_a_gpu` (slow) compiles the kernel to
PTX, which needs the CUDA toolkit's NVVM but no GPU.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from dice_env import Die, Scene, State, simulate
from dice_env.model.rotations import random_rotations
from dice_env.model.surroundings import tray
from dice_env.simulation import paper

pytestmark = pytest.mark.skipif(importlib.util.find_spec("numba_cuda") is None,
                                reason="numba-cuda is not installed (pip install 'dice_env[cuda]')")

OUTCOMES = ("face", "settled", "decided", "impacts", "unstable", "sunk", "steps")
SIM_TOLERANCE = 0.0  # simulator against CPU, relative to each state array's largest value
GPU_TOLERANCE = 1e-6  # a real GPU against CPU, short runs (FMA round-off grown by contacts)
ROOT = Path(__file__).resolve().parents[1]


def hand(scene: Scene, n: int, seed: int, height: tuple[float, float]) -> State:
    """``n`` throws from the hand, low above the table so they meet it within a short run."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(2, n, 3))
    d /= np.linalg.norm(d, axis=2, keepdims=True)
    return State.release(scene, np.column_stack([np.zeros((n, 2)), rng.uniform(*height, n)]),
                         d[0] * rng.uniform(0.3, 0.8, (n, 1)), d[1] * rng.uniform(0, 30, (n, 1)),
                         random_rotations(rng, n))


def cases() -> dict[str, tuple[Scene, State, dict]]:
    """Few dice each: the default scene to a decided face, a loaded d20 in a small tray
    (several planes, a die that is not isotropic) and the paper's scheme, law and friction."""
    d6, d20 = Scene(), Scene(die=Die.standard("d20").load(face=20), walls=tray(0.04, 0.04))
    listing = paper.paper_scene().with_(t_max=0.3)
    spin = np.random.default_rng(3).random((2, 3)) * 0.75 + 1e-6
    return {
        "decided": (d6, hand(d6, 3, 0, (0.012, 0.016)), {"until": "decided"}),
        "tray-d20": (d20, hand(d20, 2, 1, (0.014, 0.016)), {"t_max": 6000 * d20.step}),
        "paper": (listing, State.release(listing, [0.0, 0.0, 0.6], [2.0, 0.0, -1.0],
                                         spin / listing.die.inertia_body[0, 0]),
                  {"until": "t_max"}),
    }


def results(device: str) -> dict[str, np.ndarray]:
    """Every case on ``device``: the outcomes and the final state, by ``case.field``."""
    out = {}
    for name, (scene, start, kwargs) in cases().items():
        result = simulate(scene, start, device=device, **kwargs)
        out |= {f"{name}.{field}": np.asarray(getattr(result, field)) for field in OUTCOMES}
        out |= {f"{name}.state{j}": a for j, a in enumerate(result.final._arrays())}
    return out


def save_results(path: str) -> None:
    """The child's side: :func:`results` on the (simulated) GPU, saved to ``path``."""
    np.savez(path, **results("cuda"))


def assert_agree(gpu: dict, cpu: dict, tolerance: float) -> None:
    """Outcomes equal, states within ``tolerance`` of each array's largest value."""
    assert gpu.keys() == cpu.keys()
    for key, expected in cpu.items():
        if ".state" in key:
            scale = max(np.abs(expected).max(), 1e-300)
            np.testing.assert_allclose(gpu[key], expected, rtol=0, atol=tolerance * scale,
                                       err_msg=key)
        else:
            np.testing.assert_array_equal(gpu[key], expected, err_msg=key)


def test_simulator_agrees_with_the_cpu_kernel(tmp_path):
    path = tmp_path / "gpu.npz"
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1", NUMBA_DISABLE_JIT="1",
               PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests")]))
    code = f"from test_cuda_kernel import save_results; save_results({str(path)!r})"
    subprocess.run([sys.executable, "-c", code], env=env, check=True, timeout=300)
    with np.load(path) as saved:
        gpu = dict(saved)
    assert_agree(gpu, results("cpu"), SIM_TOLERANCE)
    assert gpu["decided.decided"].all()  # the decided case ran to its end


def test_device_is_checked():
    with pytest.raises(ValueError, match="device must be one of 'cpu', 'cuda'"):
        simulate(Scene(), hand(Scene(), 1, 0, (0.02, 0.03)), device="gpu")


def test_refusals_before_the_gpu():
    from dice_env.physics import cuda_kernel
    from dice_env.simulation.simulate import _records, pack_run, pack_scene

    scene = Scene(walls=tray())
    body, contact = pack_scene(scene)
    options, stops = pack_run(scene, n_steps=10)
    groups = (None, body, contact, options, stops)
    with pytest.raises(ValueError, match="record_every must be 0 with device='cuda'"):
        cuda_kernel.run(*groups, _records(("energy",), 1, 1, 10, 8), None)
    many = contact._replace(planes=np.tile(contact.planes, (2, 1)))
    with pytest.raises(ValueError, match="at most 8 planes"):
        cuda_kernel.run(None, body, many, options, stops, _records((), 0, 1, 10, 8), None)


def test_no_gpu_says_what_is_missing():
    from numba import cuda

    if cuda.is_available():
        pytest.skip("a GPU is here")
    with pytest.raises(RuntimeError, match="no usable CUDA GPU"):
        simulate(Scene(), hand(Scene(), 1, 0, (0.02, 0.03)), device="cuda")


def test_on_the_gpu():
    from numba import cuda

    if not cuda.is_available():
        pytest.skip("no CUDA GPU")
    assert_agree(results("cuda"), results("cpu"), GPU_TOLERANCE)


@pytest.mark.slow
def test_compiles_for_a_gpu(monkeypatch):
    """The CUDA kernel compiles to PTX for an H100/H200 (about a minute on 2 cores)."""
    import numba
    from numba import cuda
    from numba.cuda import dispatcher
    from numba.cuda.cudadrv import nvvm

    from dice_env.physics import cuda_kernel, kernel
    from dice_env.simulation.simulate import _records, pack_run, pack_scene

    if not nvvm.is_available():
        pytest.skip("no NVVM (the CUDA toolkit: pip install 'dice_env[cuda]')")
    if not cuda.is_available():  # numba-cuda compiles the device functions for the current
        # device's compute capability: without a GPU, the one asked for below
        monkeypatch.setattr(dispatcher, "get_current_device",
                            lambda: types.SimpleNamespace(compute_capability=(9, 0)))
    scene, start = Scene(walls=tray()), hand(Scene(), 2, 0, (0.02, 0.03))
    options, stops = pack_run(scene, n_steps=10)
    b = start.batch_size
    groups = (kernel.Dice(*start._arrays()), *pack_scene(scene), options, stops,
              _records((), 0, b, 10, 8),
              kernel.Outcome(np.zeros(b, np.int8), np.zeros(b, np.bool_), np.zeros(b),
                             np.zeros(b, np.int64), np.zeros(b), np.zeros(b),
                             np.zeros(b, np.int64), np.zeros(1, np.int64)))
    # typed as cuda_kernel.run's copies on the device: C-contiguous and writable
    signature = tuple(numba.typeof(type(group)(*(
        np.array(value, order="C") if isinstance(value, np.ndarray) else value
        for value in group))) for group in groups)
    ptx, _ = cuda.compile_ptx(cuda_kernel.simulate_cuda.py_func, signature, cc=(9, 0))
    assert ".visible .entry" in ptx


def test_importing_dice_env_leaves_numba_cuda_alone():
    code = ("import sys, dice_env, dice_env.envs; "
            "print(sorted(m for m in sys.modules if m.startswith(('numba.cuda', 'numba_cuda'))))")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True,
                         text=True, timeout=120).stdout
    assert out.strip() == "[]"

"""The one-die kernel on an NVIDIA GPU: one die per CUDA thread (numba-cuda).

:func:`dice_env.physics.kernel.advance` as device functions, its scratch in local memory. Not
bit for bit the CPU's (FMA, libdevice's ``sin``); no records, no interrupt, compiled at the first
run in each process. Without a GPU: ``NUMBA_ENABLE_CUDASIM=1`` with ``NUMBA_DISABLE_JIT=1``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import cuda

from dice_env.physics.kernel import (
    Body,
    Contact,
    Dice,
    Options,
    Outcome,
    PlaneContacts,
    Records,
    Scratch,
    Stops,
    advance,
)

GPU_MAX_VERTICES = 32  # the most vertices of a die on the GPU (a d12 has 20)
MAX_PLANES = 8  # the most planes (a tray has 5)
BLOCK = 128  # threads per block


@cuda.jit  # no disk cache: it would not see a change in physics/kernel.py, whose code it runs
def simulate_cuda(dice: Dice, body: Body, contact: Contact, options: Options, stops: Stops,
                  records: Records, out: Outcome) -> None:
    """:func:`dice_env.physics.kernel.simulate_batch` on the GPU, die ``i`` on thread ``i``."""
    i = cuda.grid(1)
    if i < dice.x.shape[0]:
        advance(i, dice, body, contact, options, stops, records, out, Scratch(
            cuda.local.array((3, 3), np.float64), cuda.local.array((3, 3), np.float64),
            PlaneContacts(
                cuda.local.array((GPU_MAX_VERTICES, 3), np.float64),
                cuda.local.array((MAX_PLANES, GPU_MAX_VERTICES), np.float64),
                cuda.local.array((MAX_PLANES, GPU_MAX_VERTICES, 3), np.float64),
                cuda.local.array((MAX_PLANES, GPU_MAX_VERTICES), np.bool_),
                cuda.local.array((1, MAX_PLANES), np.float64))))


def run(dice: Dice, body: Body, contact: Contact, options: Options, stops: Stops,
        records: Records, out: Outcome) -> None:
    """:func:`dice_env.physics.kernel.simulate_batch` on the GPU, in the host arrays.

    ``ValueError`` for records, more than :data:`GPU_MAX_VERTICES` vertices or :data:`MAX_PLANES`.
    """
    if records.x.shape[1] > 0:
        raise ValueError("record_every must be 0 with device='cuda': records are kept on the "
                         "CPU only")
    n_vertices, n_planes = body.vertices.shape[0], contact.planes.shape[0]
    if n_vertices > GPU_MAX_VERTICES or n_planes > MAX_PLANES:
        raise ValueError(f"scene must have a die of at most {GPU_MAX_VERTICES} vertices and at "
                         f"most {MAX_PLANES} planes with device='cuda', got {n_vertices} vertices "
                         f"and {n_planes} planes")
    on_device = [_to_device(group) for group in (dice, body, contact, options, stops, records, out)]
    simulate_cuda[math.ceil(dice.x.shape[0] / BLOCK), BLOCK](*on_device)
    for host, device in ((dice, on_device[0]), (out, on_device[-1])):
        for host_array, device_array in zip(host, device, strict=True):
            if isinstance(host_array, np.ndarray):
                host_array[...] = device_array.copy_to_host()  # whatever its layout


def _to_device(group: tuple) -> tuple:
    """The named tuple ``group`` with each of its arrays copied to the GPU."""
    return type(group)(*(cuda.to_device(np.ascontiguousarray(value))
                         if isinstance(value, np.ndarray) else value for value in group))

"""The paper's two scripts, step for step: ``real_throw_cube.m`` and ``ground_cube.m``.

Both run the kernel with the paper's die, contact law and listing defaults for exactly
``clockmax`` steps; the quirks kept and how far the runs match the listings are in
``docs/model.md`` (paper mode). ``L0 = 0`` gives ``R = I`` where the listing gives NaN.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dice_env.model.checks import as_batch, check_int, check_positive
from dice_env.model.die import Die
from dice_env.model.scene import ContactLaw, FrictionLaw, Ground, Scene, Scheme
from dice_env.simulation.simulate import Result, State, simulate


@dataclass
class PaperRun:
    """A paper script's run: per-step ``t``, ``x_cm``, ``energy``, ``nodes`` (or None); ``L0``."""

    t: np.ndarray
    x_cm: np.ndarray
    energy: np.ndarray
    nodes: np.ndarray | None
    L0: np.ndarray
    result: Result


def real_throw_cube(L0: np.ndarray | None = None, *, seed: int | None = None, D: float = 0.1,
                    mu: float = 0.1, clockmax: int = 100000, **listing: object) -> PaperRun:
    """Run ``real_throw_cube.m``.

    ``L0`` defaults to the listing's ``rand(3,1)*0.75 + 1e-6`` drawn from
    ``numpy.random.default_rng(seed)``. ``listing``: the listing's other values, as
    keywords of :func:`paper_scene` (``r``, ``total_mass``, ``normal``, ``S``, ``g``,
    ``umin`` (default ``1e-6 * r``)) or of the run (``tmax`` = 10, ``x0`` = (0, 0, 3),
    ``u0`` = (5, 0, 5), ``record_nodes`` = False), and the scene's ``contact_law`` (default
    the paper's) and ``allow_unstable`` (default False).
    """
    if L0 is None:
        L0 = np.random.default_rng(seed).random(3) * 0.75 + 1e-6
    return _run(L0, True, D=D, mu=mu, clockmax=clockmax, **listing)


def ground_cube(*, D: float = 0.2, mu: float = 0.075, clockmax: int = 10000,
                **listing: object) -> PaperRun:
    """Run ``ground_cube.m``: the cube translating; ``listing`` as :func:`real_throw_cube`'s."""
    return _run(np.zeros(3), False, D=D, mu=mu, clockmax=clockmax, **listing)


def paper_scene(*, r: float = 1.0, total_mass: float = 1.0,
                normal: tuple[float, float, float] = (0, 0, 1), S: float = 1e4, D: float = 0.1,
                mu: float = 0.1, dt: float | None = 1e-4, g: float = 9.8,
                umin: float | None = None, rotation: bool = True) -> Scene:
    """The paper's scene (real throw defaults: its listing's values, 10 s) as a :class:`Scene`."""
    return Scene(die=Die.paper(r, total_mass),
                 ground=Ground(stiffness=S, damping=D, friction=mu, normal=normal,
                               contact_law=ContactLaw.PAPER),
                 gravity=g, dt=dt, t_max=10.0, rotation=rotation,
                 friction_vmin=1e-6 * r if umin is None else umin,
                 scheme=Scheme.PAPER, friction_law=FrictionLaw.REGULARIZED)


def _run(L0: object, rotation: bool, *, clockmax: int, tmax: float = 10.0,
         x0: object = (0.0, 0.0, 3.0), u0: object = (5.0, 0.0, 5.0), record_nodes: bool = False,
         contact_law: ContactLaw = ContactLaw.PAPER, allow_unstable: bool = False,
         **listing: object) -> PaperRun:
    """Either listing's run; ``listing``: :func:`paper_scene`'s other keywords."""
    check_int("clockmax", clockmax, 1)
    check_positive("tmax", tmax)
    # built at its own step, then checked once with the run's step, time and law
    listing_scene = paper_scene(**listing, dt=None, rotation=rotation)
    scene = listing_scene.with_(
        dt=tmax / clockmax, t_max=tmax, allow_unstable=allow_unstable,
        ground=listing_scene.ground.with_(contact_law=contact_law))
    L0 = _vector("L0", L0)
    position, upright = _vector("x0", x0), np.eye(3)[None]
    sink = float(scene.sink(position, upright)[0])
    if sink > 0.0:
        raise ValueError(f"x0 must hold every corner above the ground, got {x0} with a corner "
                         f"{sink:.4g} below it")
    state = State(position=position, velocity=_vector("u0", u0), angular_momentum=L0,
                  orientation=upright, angular_velocity=np.zeros((1, 3)))
    record = ("energy", "nodes") if record_nodes else ("energy",)
    result = simulate(scene, state, until="t_max", record_every=1, record=record)
    return PaperRun(t=result.t, x_cm=result.x_cm[0], energy=result.energy[0],
                    nodes=result.nodes[0] if record_nodes else None, L0=L0[0], result=result)


def _vector(name: str, value: object) -> np.ndarray:
    """``value`` as a finite (1, 3) array: one vector (3,) of the listing, never a batch."""
    array = np.asarray(value, dtype=np.float64)
    if array.shape != (3,):
        raise ValueError(f"{name} must be one vector of shape (3,), got shape {array.shape}")
    return as_batch(name, array, (3,))

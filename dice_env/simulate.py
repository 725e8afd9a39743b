"""Throw dice: the state of a batch, one call to the compiled kernel, and the outcomes."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba
import numpy as np

from dice_env import kernel, vector_kernel
from dice_env.die import face_up
from dice_env.rotations import orthonormality_error
from dice_env.scene import ContactLaw, FrictionLaw, Scene, Scheme
from dice_env.validation import as_batch, check_positive, check_range


@dataclass
class State:
    """State of a batch of B dice (world frame, SI units in the default scene).

    ``position`` (B, 3) centre of mass; ``velocity`` (B, 3) its velocity; ``angular_momentum``
    (B, 3) about it; ``orientation`` (B, 3, 3) body-to-world rotation; ``angular_velocity``
    (B, 3), the ω used for corner velocities (``I_world^-1 L`` except where a paper script starts
    its corners without spin).
    """

    position: np.ndarray
    velocity: np.ndarray
    angular_momentum: np.ndarray
    orientation: np.ndarray
    angular_velocity: np.ndarray

    @classmethod
    def release(
        cls,
        scene: Scene,
        position: np.ndarray,
        velocity: np.ndarray,
        angular_velocity: np.ndarray | None = None,
        orientation: np.ndarray | None = None,
    ) -> State:
        """Dice released at ``position`` with ``velocity`` and ``angular_velocity`` (rad/s).

        Each argument is (3,) or (B, 3) (orientation (3, 3) or (B, 3, 3)) and is broadcast to
        the batch; ``angular_velocity`` defaults to zero, ``orientation`` to the identity.
        """
        position = as_batch("position", position, (3,))
        velocity = as_batch("velocity", velocity, (3,))
        spin = as_batch("angular_velocity",
                        np.zeros(3) if angular_velocity is None else angular_velocity, (3,))
        rot = as_batch("orientation", np.eye(3) if orientation is None else orientation, (3, 3))
        if orthonormality_error(rot).max() > 1e-9:
            raise ValueError("orientation must be rotation matrices (R R^T = I, det R = +1, "
                             "to 1e-9)")
        size = _batch_size(position, velocity, spin, rot)
        position, velocity, spin = (np.broadcast_to(a, (size, 3)) for a in (position, velocity,
                                                                               spin))
        rot = np.broadcast_to(rot, (size, 3, 3))
        world_inertia = rot @ scene.die.inertia_body @ rot.transpose(0, 2, 1)
        momentum = np.einsum("bij,bj->bi", world_inertia, spin)
        return cls(*(np.array(a) for a in (position, velocity, momentum, rot, spin)))

    @property
    def batch_size(self) -> int:
        """Number of dice B."""
        return self.position.shape[0]

    def copy(self) -> State:
        """An independent copy."""
        return State(*(np.array(a) for a in self._arrays()))

    def _arrays(self) -> tuple[np.ndarray, ...]:
        return (self.position, self.velocity, self.angular_momentum, self.orientation,
                self.angular_velocity)


@dataclass
class Result:
    """Outcome of a batch of throws (arrays over the batch, B).

    - ``face``: 1–6, the face up relative to the ground normal at the end;
    - ``settled``: came to rest; ``rest_time``: when the rest began (s; the time simulated if
      not settled);
    - ``decided``: ended by ``stop_when_decided`` with too little energy left to change face;
    - ``impacts``: airborne-to-contact transitions;
    - ``unstable``: energy rose beyond the scene's tolerance, or the state stopped being finite;
      ``energy_rise``: the largest rise above the start in units of that tolerance;
    - ``max_penetration``: deepest corner below the plane (m); ``steps``: steps taken;
    - ``final``: the state at the end.

    With recording: ``t`` (n,), ``x_cm`` (B, n, 3), ``energy`` (B, n) as the listing computes
    it (kinetic + m g z, no ground springs), ``orientations`` (B, n, 3, 3), ``nodes``
    (B, n, 8, 3).
    """

    face: np.ndarray
    settled: np.ndarray
    decided: np.ndarray
    rest_time: np.ndarray
    impacts: np.ndarray
    unstable: np.ndarray
    energy_rise: np.ndarray
    max_penetration: np.ndarray
    steps: np.ndarray
    final: State
    t: np.ndarray | None = None
    x_cm: np.ndarray | None = None
    energy: np.ndarray | None = None
    orientations: np.ndarray | None = None
    nodes: np.ndarray | None = None


def simulate(
    scene: Scene,
    state: State,
    *,
    t_max: float | None = None,
    stop_at_rest: bool = True,
    record_every: int = 0,
    record: tuple[str, ...] = ("energy",),
    num_threads: int | None = None,
    free_flight: bool = True,
    early_rest: bool = False,
    stop_when_decided: bool = False,
) -> Result:
    """Run a batch of throws; ``state`` is not modified.

    ``t_max`` overrides the scene's time limit. ``record_every`` > 0 stores the centre of mass
    every that many steps, plus what ``record`` names among "energy", "orientations", "nodes".
    ``num_threads`` caps numba's threads for this call (default: all cores); a single throw or
    one thread runs on the calling thread. ``free_flight`` takes the contact-free steps in
    analytic jumps (gated law, or no damping, where the paper law is the same); False steps them
    one by one. ``early_rest`` ends a quiet die as soon as its energy proves it stays at rest
    (fair die on a horizontal table): the same outcome (face, rest time, impacts) without the
    cost of the hold, but the final state is taken then, still vibrating within the rest
    thresholds. By default the hold ``scene.rest.hold`` is waited out. ``stop_when_decided``
    ends a die as soon as its face up is decided: its total energy (kinetic, potential and
    ground springs), which the ground can only store or dissipate, is below the least energy
    of any orientation in which its face up ties with another (:func:`lock_energy`;
    horizontal table, fair or loaded die). Its face is the one it would rest on, at a fraction
    of the cost; the final state, rest time and impacts are those of that moment, and it is
    not ``settled``.
    """
    t_max = scene.t_max if t_max is None else t_max
    check_positive("t_max", t_max)
    unknown = set(record) - {"energy", "orientations", "nodes"}
    if unknown:
        raise ValueError(f"record must name only 'energy', 'orientations', 'nodes', "
                         f"got {sorted(unknown)}")
    if not isinstance(record_every, (int, np.integer)) or record_every < 0:
        raise ValueError(f"record_every must be an int >= 0, got {record_every!r}")
    dt, body, inv_inertia, iso, inv_i_min, normal = _scene_constants(scene)
    n_steps = max(1, round(t_max / dt))
    out = state.copy()
    b = out.batch_size
    n_rec = n_steps // record_every if record_every else 0
    stride = record_every or n_steps + 1
    rec = {
        "x_cm": np.zeros((b, n_rec, 3)),
        "energy": np.zeros((b, n_rec if "energy" in record else 0)),
        "orientations": np.zeros((b, n_rec if "orientations" in record else 0, 3, 3)),
        "nodes": np.zeros((b, n_rec if "nodes" in record else 0, 8, 3)),
    }
    status = np.zeros(b, np.int8)
    unstable = np.zeros(b, np.bool_)
    rest_time = np.zeros(b)
    impacts = np.zeros(b, np.int64)
    max_pen = np.zeros(b)
    energy_rise = np.zeros(b)
    steps = np.zeros(b, np.int64)
    die, ground = scene.die, scene.ground
    gated = ground.contact_law == ContactLaw.GATED
    stick = scene.friction_law == FrictionLaw.STICK_SLIP
    flight = free_flight and (gated or ground.damping == 0)
    lock = lock_energy(scene) if stop_when_decided else _NEVER
    rest_energy, rest_excess = _rest_energy(scene, early_rest)
    hold_steps = math.ceil(scene.rest.hold / dt)
    threads = numba.get_num_threads()
    numba.set_num_threads(num_threads or numba.config.NUMBA_NUM_THREADS)
    try:
        if vector_kernel.covers(scene, b, flight, stride <= n_steps):
            vector_kernel.simulate_batch(
                out.position, out.velocity, out.angular_momentum, out.orientation,
                out.angular_velocity, body, die.mass, 1.0 / iso, normal, ground.stiffness,
                ground.damping, ground.friction, scene.friction_vmin, scene.gravity, dt, n_steps,
                stop_at_rest, scene.rest.speed, hold_steps, rest_energy, rest_excess, lock,
                die.mass * scene.gravity * die.edge,
                status, unstable, rest_time, impacts, max_pen, energy_rise, steps,
            )
        else:
            serial = b == 1 or numba.get_num_threads() == 1
            (kernel.simulate_serial if serial else kernel.simulate_batch)(
                out.position, out.velocity, out.angular_momentum, out.orientation,
                out.angular_velocity, body, die.mass, inv_inertia, iso, inv_i_min, normal,
                ground.stiffness, ground.damping, ground.friction, scene.friction_vmin, stick,
                ground.tangential * ground.stiffness, ground.tangential * ground.damping,
                scene.gravity, dt, gated, scene.rotation, flight, scene.scheme == Scheme.MIDPOINT,
                n_steps, stop_at_rest, scene.rest.speed, hold_steps, rest_energy, rest_excess,
                lock, die.mass * scene.gravity * die.edge,
                stride, rec["x_cm"], rec["energy"], rec["orientations"], rec["nodes"],
                status, unstable, rest_time, impacts, max_pen, energy_rise, steps,
            )
    finally:
        numba.set_num_threads(threads)
    energy_rise /= scene.energy_tol
    unstable |= energy_rise > 1.0
    settled = status == kernel.SETTLED
    recorded = {}
    if record_every:
        recorded = {"t": np.arange(1, n_rec + 1) * (stride * dt), "x_cm": rec["x_cm"]}
        recorded.update({name: rec[name] for name in record})
    return Result(
        face=face_up(out.orientation, normal),
        settled=settled, decided=status == kernel.DECIDED, rest_time=rest_time,
        impacts=impacts, unstable=unstable, energy_rise=energy_rise, max_penetration=max_pen,
        steps=steps, final=out, **recorded,
    )


def _scene_constants(scene: Scene) -> tuple:
    """Kernel constants of ``scene``, computed once per (frozen, hashable) scene.

    The step, corners, inverse inertia, isotropic inertia (or 0), inverse smallest principal
    moment and ground normal.
    """
    try:
        return _cached_constants(scene)
    except TypeError:  # a scene holding something unhashable
        return _cached_constants.__wrapped__(scene)


@functools.lru_cache(maxsize=64)
def _cached_constants(scene: Scene) -> tuple:
    die = scene.die
    inertia = die.inertia_body
    return (scene.step, die.corners_body, np.linalg.inv(inertia),
            float(inertia[0, 0]) if die.is_isotropic else 0.0,
            1.0 / np.linalg.eigvalsh(inertia)[0], np.asarray(scene.ground.normal))


def _rest_energy(scene: Scene, early_rest: bool) -> tuple[float, float]:
    """Lowest total energy of the die and the excess above it that proves rest (0: none).

    For a fair die on a horizontal table the lowest energy is flat on a face, each corner
    carrying a quarter of the weight: ``m g h - (m g)^2 / (8 S)``. With less than
    ``(m g)^2 / (8 S)`` above it the die cannot lift off, and with kinetic energy below
    ``v^2 / (2 (1/m + r_max^2 / I))`` no corner moves at ``v`` (Cauchy-Schwarz on
    ``|u| + |w| r_max``). Half the smaller of the two allows for the scheme's energy wobble.
    """
    die, ground = scene.die, scene.ground
    if not early_rest or not die.is_fair or ground.normal != (0.0, 0.0, 1.0):
        return -math.inf, 0.0
    weight = die.mass * scene.gravity
    lift = weight**2 / (8.0 * ground.stiffness)
    r_max2 = float((die.corners_body**2).sum(axis=1).max())
    move = scene.rest.speed**2 / (2.0 * (1.0 / die.mass + r_max2 / die.inertia_body[0, 0]))
    return weight * die.half_edge - lift, 0.5 * min(lift, move)


LOCK_MARGIN = 0.25  # the energy's rise after a decision: <= 0.04 of the barrier at the
# default step, 0.18 at safety 0.9 (tests/test_decided.py, slow)
_NEVER = np.full(6, -math.inf)


def lock_energy(scene: Scene, margin: float = LOCK_MARGIN) -> np.ndarray:
    """Total energy (J) below which each face up (1–6) can no longer change, (6,).

    A die stops showing ``F`` up only through an orientation in which ``F`` ties with an
    adjacent face, with the centre of mass at least ``Die.tipping_heights[F]`` above the
    lowest corner; that corner sinks ``d`` into the ground at a spring energy of ``S d^2 / 2``,
    so such an orientation holds at least ``E_tie = m g h_tip - (m g)^2 / (2 S)`` (potential
    energy above the plane, the minimum over ``d``). Every ground force stores energy in a
    spring or dissipates it, so a die below ``E_tie`` keeps its face for good. The threshold is
    lowered by ``margin`` of the barrier ``m g (h_tip - h_rest)`` against the scheme's energy
    wobble. ``-inf`` (never) unless the table is horizontal (on a slope gravity does work as
    the die slides), with gravity and rotation.
    """
    check_range("margin", margin, 0.0, 1.0)
    die, ground = scene.die, scene.ground
    if ground.normal != (0.0, 0.0, 1.0) or scene.gravity == 0 or not scene.rotation:
        return np.full(6, -math.inf)
    weight = die.mass * scene.gravity
    tip, rest = die.tipping_heights, die.resting_heights
    return weight * (tip - margin * (tip - rest)) - weight**2 / (2.0 * ground.stiffness)


def _batch_size(*arrays: np.ndarray) -> int:
    sizes = {a.shape[0] for a in arrays} - {1}
    if len(sizes) > 1:
        raise ValueError(f"batch sizes of the release arguments disagree: {sorted(sizes)}")
    return sizes.pop() if sizes else 1

"""A scene: a die, a ground, gravity and the integrator settings, with the stable step.

Units are SI in the default scene; the paper's scenes use its unit-free numbers (r = m = 1).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from enum import IntEnum
from typing import Self

import numpy as np

from dice_env.model import defaults
from dice_env.model.checks import (
    as_enum,
    as_shaped,
    check_bool,
    check_finite,
    check_nonnegative,
    check_positive,
    check_range,
    check_type,
)
from dice_env.model.die import Die

MAX_STEPS = 10**9  # steps of one throw to t_max: more is refused (about a minute a die)


class ContactLaw(IntEnum):
    """How a corner feels the ground (``docs/model.md``).

    ``GATED`` (default): only corners below the plane feel ``max(0, S*dg - D*un)``.
    ``PAPER``: the listing's ``max(0, S*max(0, dg) - D*un)`` on every corner (an air drag).
    """

    GATED = 0
    PAPER = 1


class Scheme(IntEnum):
    """How a step treats the contact forces (``docs/model.md``, "Midpoint step").

    ``MIDPOINT`` (default): damping and friction from the corner velocity at the middle of the
    step's kick. ``PAPER``: the listing's step, first order.
    """

    PAPER = 0
    MIDPOINT = 1


class FrictionLaw(IntEnum):
    """How a corner in contact feels friction (``docs/model.md``, "Stick-slip friction").

    ``STICK_SLIP`` (default): a corner is tied by a spring and damper (``tangential`` times the
    plane's S and D) to where it touched, slipping at ``mu fn``. ``REGULARIZED``: the
    listing's ``-mu fn Ut / (|Ut| + vmin)``.
    """

    REGULARIZED = 0
    STICK_SLIP = 1


@dataclass(frozen=True)
class Plane:
    """A penalty half-space: the die stays on the side ``normal . x >= offset``.

    ``normal`` (normalised when given) points into the free side; ``offset`` (m) is the plane's
    signed distance from the origin along it. ``stiffness`` S (N/m per vertex), ``damping`` D
    (N s/m per vertex), sliding ``friction`` mu; ``tangential``: the stick-slip spring and
    damper as a fraction of S and D, in (0, 1]. Defaults: the wooden table of
    :mod:`dice_env.model.defaults` for the default die.
    """

    stiffness: float = defaults.STIFFNESS
    damping: float = defaults.DAMPING
    friction: float = defaults.FRICTION
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
    offset: float = 0.0
    tangential: float = 2.0 / 7.0

    def __post_init__(self) -> None:
        check_material(self.stiffness, self.damping, self.friction, self.tangential)
        check_finite("offset", self.offset)
        normal = as_shaped("normal", self.normal, (3,))
        norm = float(np.linalg.norm(normal))
        if norm == 0.0:
            raise ValueError("normal must be a non-zero vector (it is normalised), got (0, 0, 0)")
        object.__setattr__(self, "normal", tuple(float(v) for v in normal / norm))
        object.__setattr__(self, "offset", float(self.offset))

    def height(self, points: np.ndarray) -> np.ndarray:
        """Signed distance (m) of ``points`` (..., 3) from the plane, > 0 on the free side."""
        return np.asarray(points) @ np.asarray(self.normal) - self.offset

    def with_(self, **changes: object) -> Self:
        """A copy with some fields changed (validated again); an unchanged ``normal`` to the bit."""
        plane = replace(self, **changes)
        if "normal" not in changes:
            object.__setattr__(plane, "normal", self.normal)
        return plane


@dataclass(frozen=True)
class Ground(Plane):
    """The floor: a :class:`Plane` pointing up, whose ``contact_law`` every plane follows."""

    contact_law: ContactLaw = ContactLaw.GATED

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.normal[2] <= 0:
            raise ValueError(f"normal must point upward (n_z > 0) so the table holds the die, "
                             f"got {self.normal}")
        object.__setattr__(self, "contact_law",
                           as_enum("contact_law", ContactLaw, self.contact_law))

    @classmethod
    def tilted(cls, angle_deg: float, **kwargs: float) -> Ground:
        """A table tilted by ``angle_deg`` about the y axis (0 ≤ angle < 90)."""
        check_range("angle_deg", angle_deg, 0.0, 90.0, high_open=True)
        a = math.radians(angle_deg)
        return cls(normal=(math.sin(a), 0.0, math.cos(a)), **kwargs)


@dataclass(frozen=True)
class Wall(Plane):
    """A wall: a :class:`Plane` with its own material; ``normal`` points into the room."""

    normal: tuple[float, float, float] = (1.0, 0.0, 0.0)

    @classmethod
    def through(cls, point: tuple[float, float, float], normal: tuple[float, float, float],
                **material: float) -> Wall:
        """The wall through ``point`` facing ``normal`` (any length), with ``material``."""
        point = as_shaped("point", point, (3,))
        n = np.asarray(normal, dtype=np.float64)
        length = float(np.linalg.norm(n)) if n.shape == (3,) else 0.0
        if length == 0.0 or not math.isfinite(length):
            raise ValueError(f"normal must be a finite non-zero vector (3,), got {normal!r}")
        return cls(normal=tuple(n / length), offset=float(point @ n) / length, **material)


@dataclass(frozen=True)
class Rest:
    """When a die counts as settled.

    At least three corners in contact (a die pausing on an edge or corner is not at rest),
    every corner slower than ``speed`` (m/s) and kinetic energy below ``0.5 * mass * speed**2``,
    continuously for ``hold`` seconds. The rest time is when that quiet interval began.
    """

    speed: float = 4e-3
    hold: float = 0.1

    def __post_init__(self) -> None:
        check_positive("speed", self.speed)
        check_nonnegative("hold", self.hold)


@dataclass(frozen=True)
class Scene:
    """Everything that stays fixed during a throw: the die, the planes, gravity, the integrator.

    ``dt=None`` picks ``safety * critical_dt`` (``safety`` in (0, 1], ``docs/model.md``); a
    ``dt`` above :attr:`critical_dt` raises unless ``allow_unstable``. ``rotation=False`` is
    the paper's ground_cube.m (translation only). ``friction_vmin``: the listing's ``umin`` of
    the ``REGULARIZED`` :class:`FrictionLaw`. A throw is flagged unstable when its energy
    (kinetic + potential + normal springs) exceeds its start by more than ``energy_tol`` times
    ``KE0 + m*g*(h0 + size)``, and ``sunk`` when a vertex sinks more than ``sink_limit`` times
    the die's size into a plane. Every field is checked when built, and the step (at most
    ``t_max`` and :data:`MAX_STEPS` steps).
    """

    die: Die = field(default_factory=Die)
    ground: Ground = field(default_factory=Ground)
    walls: tuple[Wall, ...] = ()
    gravity: float = 9.81
    dt: float | None = None
    safety: float = 0.15
    t_max: float = 10.0
    rotation: bool = True
    friction_law: FrictionLaw = FrictionLaw.STICK_SLIP
    friction_vmin: float = 1e-6
    scheme: Scheme = Scheme.MIDPOINT
    rest: Rest = field(default_factory=Rest)
    energy_tol: float = 0.1
    allow_unstable: bool = False
    sink_limit: float = 0.25

    def __post_init__(self) -> None:
        for name, kind in (("die", Die), ("ground", Ground), ("rest", Rest)):
            check_type(name, getattr(self, name), kind)
        walls = (self.walls,) if isinstance(self.walls, Wall) else self.walls
        if not isinstance(walls, (tuple, list)) or not all(isinstance(w, Wall) for w in walls):
            raise TypeError(f"walls must be a tuple of Wall, got {self.walls!r}")
        object.__setattr__(self, "walls", tuple(walls))
        for name in ("rotation", "allow_unstable"):
            check_bool(name, getattr(self, name))
        for name in ("sink_limit", "t_max", "friction_vmin", "energy_tol"):
            check_positive(name, getattr(self, name))
        check_nonnegative("gravity", self.gravity)
        check_range("safety", self.safety, 0.0, 1.0, low_open=True)
        if self.dt is not None:
            check_positive("dt", self.dt)
        for name, kind in (("scheme", Scheme), ("friction_law", FrictionLaw)):
            object.__setattr__(self, name, as_enum(name, kind, getattr(self, name)))
        step = self.step_within(self.critical_dt, self.stiffest_plane())
        if not (math.isfinite(step) and 0.0 < step <= self.t_max):
            raise ValueError(f"the step must be in (0, t_max = {self.t_max:g}] s, got "
                             f"{step:.6g} s from dt={self.dt}, safety={self.safety:g} and the "
                             f"critical step of {self.stiffest_plane()} (die mass "
                             f"{self.die.mass:g})")
        self.steps_for()

    @property
    def planes(self) -> tuple[Plane, ...]:
        """The floor, then the walls: every plane the die touches."""
        return (self.ground, *self.walls)

    @property
    def effective_mass(self) -> float:
        """Smallest effective mass per contact vertex on the floor (:meth:`effective_mass_on`)."""
        return self.effective_mass_on(self.ground)

    def effective_mass_on(self, plane: Plane) -> float:
        """Smallest effective mass per contact vertex on ``plane``, ``S / omega_max**2`` (kg).

        ``omega_max``: the fastest mode with a face on the plane (``docs/model.md``, "Stable
        step"); ``m/4`` with ``rotation=False``.
        """
        if not self.rotation:
            return self.die.mass / 4
        sticks = self.friction_law == FrictionLaw.STICK_SLIP and plane.friction > 0
        return _effective_mass(self.die, plane.tangential if sticks else 0.0)

    @property
    def critical_dt(self) -> float:
        """Largest stable step (s): :func:`critical_step` of the stiffest plane's contact mode."""
        return min(self._critical_dts())

    def stiffest_plane(self) -> str:
        """The plane that sets :attr:`critical_dt`, named with its contact constants."""
        i = int(np.argmin(self._critical_dts()))
        plane = self.planes[i]
        name = "the table" if i == 0 else f"wall {i - 1}"
        return (f"{name} (stiffness {plane.stiffness:g}, damping {plane.damping:g}, effective "
                f"mass {self.effective_mass_on(plane):.6g})")

    def _critical_dts(self) -> list[float]:
        return [critical_step(p.stiffness, p.damping, self.effective_mass_on(p), self.scheme)
                for p in self.planes]

    @property
    def step(self) -> float:
        """The step used: ``dt`` if given, else ``safety * critical_dt``."""
        return self.dt if self.dt is not None else self.safety * self.critical_dt

    def step_within(self, critical: float, of: str) -> float:
        """``dt`` (above ``critical`` only if ``allow_unstable``), else ``safety * critical`` (s).

        ``of`` names what sets ``critical``, for the error message.
        """
        if self.dt is None:
            return self.safety * critical
        if self.dt > critical and not self.allow_unstable:
            raise ValueError(f"dt must be <= the critical step {critical:.6g} s of {of}, got "
                             f"{self.dt:g}; pass allow_unstable=True to run it anyway")
        return self.dt

    @property
    def n_steps(self) -> int:
        """Number of steps to reach ``t_max``."""
        return self.steps_for()

    def steps_for(self, t_max: float | None = None, step: float | None = None) -> int:
        """Steps of ``step`` (s, default :attr:`step`) to ``t_max`` (s), <= :data:`MAX_STEPS`."""
        t_max = self.t_max if t_max is None else t_max
        check_positive("t_max", t_max)
        own = step is None
        step = self.step if own else step
        count = t_max / step
        if count > MAX_STEPS:
            origin = (f" from dt={self.dt}, safety {self.safety:g} and the critical step of "
                      f"{self.stiffest_plane()}, die mass {self.die.mass:g}" if own else "")
            raise ValueError(f"t_max / step must be <= {MAX_STEPS:.0e} steps, got {count:.3g} "
                             f"(t_max {t_max:g} s, step {step:.3g} s{origin}): shorten t_max "
                             "or soften the contact")
        return max(1, round(count))

    def sink(self, position: np.ndarray, orientation: np.ndarray) -> np.ndarray:
        """Depth (m) of the deepest vertex inside any plane for each die, (B,); < 0 if none.

        ``position`` (B, 3) centre of mass, ``orientation`` (B, 3, 3) body-to-world.
        """
        vertices = position[:, None, :] + np.einsum("bij,kj->bki", orientation,
                                                    self.die.vertices_body)
        return -np.min([plane.height(vertices).min(axis=1) for plane in self.planes], axis=0)

    def with_(self, **changes: object) -> Scene:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)


def check_material(stiffness: float, damping: float, friction: float,
                   tangential: float) -> None:
    """Check ``stiffness`` > 0, ``damping``, ``friction`` >= 0, ``tangential`` in (0, 1]."""
    check_positive("stiffness", stiffness)
    check_range("tangential", tangential, 0.0, 1.0, low_open=True)
    check_nonnegative("damping", damping)
    check_nonnegative("friction", friction)


def critical_step(stiffness: float, damping: float, mass: float, scheme: Scheme) -> float:
    """Largest stable step of ``scheme`` for ``mass x'' = -stiffness x - damping x'``.

    The symplectic Euler bound ``(w dt)^2 + 2 (D/m) dt < 4``, the midpoint's
    ``(w dt)^2 + 4 (D/m) dt < 4``; the roots rationalised (no cancellation when ``D^2 >> S m``).
    """
    s, d, m = stiffness, damping, mass
    if scheme == Scheme.MIDPOINT:
        return 2.0 * m / (math.sqrt(d * d + s * m) + d)
    return 4.0 * m / (math.sqrt(d * d + 4.0 * s * m) + d)


@functools.lru_cache(maxsize=256)
def _effective_mass(die: Die, tangential: float) -> float:
    """:meth:`Scene.effective_mass_on` for ``die``, sticking springs ``tangential`` times S."""
    inv_sqrt_m = np.zeros((6, 6))
    inv_sqrt_m[:3, :3] = np.eye(3) / math.sqrt(die.mass)
    values, vectors = np.linalg.eigh(die.inertia_body)
    inv_sqrt_m[3:, 3:] = vectors @ np.diag(values**-0.5) @ vectors.T  # I^(-1/2)
    vertices = die.vertices_body
    worst = 0.0
    for face, n in zip(die.faces, die.face_normals, strict=True):
        on_face = vertices[sorted(face)]
        springs = [(1.0, n)] + [(tangential, t) for t in _tangents(n) if tangential > 0]
        stiffness = np.zeros((6, 6))
        for weight, d in springs:
            a = np.hstack([np.tile(d, (len(on_face), 1)), np.cross(on_face, d)])
            stiffness += weight * (a.T @ a)
        k = inv_sqrt_m @ stiffness @ inv_sqrt_m
        worst = max(worst, float(np.linalg.eigvalsh(k)[-1]))
    return 1.0 / worst


def _tangents(normal: np.ndarray) -> np.ndarray:
    """Two orthonormal vectors across the unit ``normal`` (the other two axes for an axis)."""
    if np.count_nonzero(normal) == 1:
        return np.eye(3)[np.abs(normal) < 0.5]
    first = np.cross(normal, np.eye(3)[np.argmin(np.abs(normal))])
    first /= np.linalg.norm(first)
    return np.array([first, np.cross(normal, first)])

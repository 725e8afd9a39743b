"""The env's physical keywords: each validated where given, applied to a base scene.

What is refused and why: ``docs/environment.md``, "What gym.make refuses before any work".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from dice_env.model.checks import check_nonnegative, check_positive, check_range
from dice_env.model.die import STANDARD_SIZES, Die
from dice_env.model.scene import ContactLaw, FrictionLaw, Ground, Rest, Scene, Scheme, Wall, as_enum
from dice_env.model.surroundings import WALLS
from dice_env.model.surroundings import walls as preset_walls

DEFAULT_T_MAX = 5.0
"""The env's simulated time limit per throw (s) when no ``scene`` is given."""
ENV_MAX_STEPS = 10**7
"""The most steps of one env throw (``t_max`` or ``rest_hold`` over the step)."""
MAX_SINK = 0.1  # the weight's sink of a flat die's corners into the table, in die sizes


def check_face(name: str, value: object, n_faces: int) -> int:
    """``value`` as a face label 1 … ``n_faces``, or ``ValueError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an int in [1, {n_faces}], got {value!r}")
    check_range(name, int(value), 1, n_faces)
    return int(value)


@dataclass(frozen=True)
class SceneKeywords:
    """The ``gym.make`` keywords that build the env's scene; each one None keeps the base's.

    Meanings, units and ranges: the keyword table of ``docs/environment.md``. ``size``,
    ``edge``, ``mass`` and ``load_*`` rebuild a uniform standard die; the enum keywords take a
    member or its name (any case); ``walls`` a preset name or a tuple of :class:`Wall`.
    """

    t_max: float | None = None
    die: str | Die | None = None
    size: float | None = None
    edge: float | None = None
    mass: float | None = None
    load_face: int | None = None
    load_fraction: float | None = None
    load_depth: float | None = None
    stiffness: float | None = None
    damping: float | None = None
    friction: float | None = None
    tilt_deg: float | None = None
    contact_law: str | ContactLaw | None = None
    gravity: float | None = None
    dt: float | None = None
    safety: float | None = None
    rest_speed: float | None = None
    rest_hold: float | None = None
    energy_tol: float | None = None
    scheme: str | Scheme | None = None
    friction_law: str | FrictionLaw | None = None
    friction_vmin: float | None = None
    walls: str | tuple[Wall, ...] | None = None

    def build(self, scene: Scene | None = None) -> Scene:
        """``scene`` (default ``Scene(t_max=DEFAULT_T_MAX)``) with the keywords given (not None)."""
        if scene is None:
            scene = Scene(t_max=DEFAULT_T_MAX)
        if not isinstance(scene, Scene):
            raise ValueError(f"scene must be a dice_env.Scene or None, got {type(scene).__name__}")
        changes = _given(t_max=self.t_max, gravity=self.gravity, dt=self.dt, safety=self.safety,
                         energy_tol=self.energy_tol, friction_vmin=self.friction_vmin)
        for name, kind in (("scheme", Scheme), ("friction_law", FrictionLaw)):
            if getattr(self, name) is not None:
                changes[name] = as_enum(name, kind, getattr(self, name))
        built = scene.with_(
            die=self._die(scene.die),
            walls=scene.walls if self.walls is None else _walls(self.walls),
            ground=self._ground(scene.ground), rest=self._rest(scene.rest), **changes)
        if self.safety is not None and built.dt is not None:
            raise ValueError(f"safety has no effect with a fixed step (dt={built.dt:g} s): give "
                             "safety or dt, not both")
        if self.friction_vmin is not None and built.friction_law != FrictionLaw.REGULARIZED:
            raise ValueError("friction_vmin acts only with friction_law='regularized' (the "
                             f"scene's is {built.friction_law.name.lower()!r}): give both or "
                             "neither")
        return built

    def _die(self, base: Die) -> Die:
        """``base`` or the ``die`` keyword's die, with the die keywords given."""
        base = _base_die(base, self.die)
        size = _size(self.die, self.size, self.edge)
        size_name = "size" if self.edge is None else "edge"
        given = _given(**{size_name: size}, mass=self.mass, load_face=self.load_face,
                       load_fraction=self.load_fraction, load_depth=self.load_depth)
        if "load_face" in given:
            check_face("load_face", self.load_face, base.n_faces)
        for name in ("load_fraction", "load_depth"):
            if name in given:
                check_range(name, given[name], 0.0, 1.0, high_open=True)
        if not given:
            return base
        if base.name not in STANDARD_SIZES or base != Die.standard(base.name, base.size,
                                                                   base.mass):
            com = ", ".join(f"{c:g}" for c in base.com)
            raise ValueError(
                f"{', '.join(given)} cannot be applied to the scene's die: it is not a uniform "
                f"die of a standard shape ({base!r}, com ({com}) m); build the die you want in "
                f"the scene and leave out {', '.join(given)}")
        dims = {"size": base.size, "mass": base.mass} | _given(size=size, mass=self.mass)
        check_positive(size_name, dims["size"])
        check_positive("mass", dims["mass"])
        problem = (f"{size_name}={dims['size']:g} m, mass={dims['mass']:g} kg and load_fraction="
                   f"{self.load_fraction} give no valid die (a {base.name})")
        try:
            die = Die.standard(base.name, **dims)
            if self.load_fraction:
                die = die.load(**_given(face=given.get("load_face", die.n_faces),
                                        fraction=self.load_fraction, depth=self.load_depth))
        except ValueError as error:  # the inertia of an extreme size underflows
            raise ValueError(f"{problem}: {error}") from error
        with np.errstate(all="ignore"):
            moments = np.linalg.eigvalsh(die.inertia_body)
            usable = np.isfinite(moments).all() and np.isfinite(1.0 / moments).all()
        if not (usable and moments[0] > 0):
            raise ValueError(f"{problem}: its moments of inertia {moments} under- or overflow")
        return die

    def _ground(self, base: Ground) -> Ground:
        """``base`` with the table keywords given."""
        changes = _given(stiffness=self.stiffness, damping=self.damping, friction=self.friction)
        if self.contact_law is not None:
            changes["contact_law"] = as_enum("contact_law", ContactLaw, self.contact_law)
        if self.tilt_deg is not None:
            check_range("tilt_deg", self.tilt_deg, 0.0, 90.0, high_open=True)
            changes["normal"] = Ground.tilted(self.tilt_deg).normal
        return replace(base, **changes) if changes else base

    def _rest(self, base: Rest) -> Rest:
        """``base`` with ``rest_speed`` and ``rest_hold`` if given."""
        if self.rest_speed is not None:
            check_positive("rest_speed", self.rest_speed)
        if self.rest_hold is not None:
            check_nonnegative("rest_hold", self.rest_hold)
        changes = _given(speed=self.rest_speed, hold=self.rest_hold)
        return replace(base, **changes) if changes else base


def check_scene(scene: Scene, release_height: float) -> None:
    """Refuse a scene the env cannot run as throws from ``release_height``.

    The die's weight alone, on its face of fewest corners, must sink it < :data:`MAX_SINK` sizes;
    a throw may take :data:`ENV_MAX_STEPS` steps at most; the paper law's air drag (8 D v) must
    not outweigh the die in a drop from the hand.
    """
    die, ground = scene.die, scene.ground
    corners = min(len(face) for face in die.faces)
    sink = die.mass * scene.gravity * ground.normal[2] / (corners * ground.stiffness)
    if sink > MAX_SINK * die.size:
        raise ValueError(
            f"the die's weight would press a flat face's corners {sink:.3g} m into the table, "
            f"more than {MAX_SINK} of its size ({die.size:g} m): mass={die.mass:g} kg, "
            f"gravity={scene.gravity:g} m/s^2, stiffness={ground.stiffness:g} N/m")
    step = scene.step  # the Scene checked the step itself
    for name, value in (("t_max", scene.t_max), ("rest_hold", scene.rest.hold)):
        if value / step > ENV_MAX_STEPS:
            origin = (f"dt={scene.dt:g}" if scene.dt is not None else
                      f"safety={scene.safety:g} times the critical step of "
                      f"{scene.stiffest_plane()}, mass={scene.die.mass:g}")
            raise ValueError(
                f"{name} must be at most {ENV_MAX_STEPS:.0e} steps: {name}={value:g} s over a step "
                f"of {step:.3g} s is {value / step:.3g} steps ({origin}); lower {name}, or make "
                "the step longer")
    if not (ground.contact_law == ContactLaw.PAPER and ground.damping > 0):
        return
    g = scene.gravity * ground.normal[2]
    weight, drop_speed, damping = die.mass * g, math.sqrt(2.0 * g * release_height), ground.damping
    if g > 0 and 8.0 * damping * drop_speed <= weight:
        return
    limit = weight / (8.0 * drop_speed) if g > 0 else 0.0
    raise ValueError(
        f"contact_law='paper' needs damping <= m g / (8 sqrt(2 g release_height)) = "
        f"{limit:.4g} N s/m, got damping={damping:g}: with its air drag of 8 D v the die "
        f"falls at most m g / (8 D) = {weight / (8.0 * damping):.3g} m/s (a drop from "
        f"release_height={release_height:g} m reaches {drop_speed:.3g} m/s; gravity="
        f"{scene.gravity:g} m/s^2). Use contact_law='gated' (the default) or a damping that small")


def _base_die(base: Die, die: str | Die | None) -> Die:
    """The scene's die, or the die the ``die`` keyword names."""
    if die is None or isinstance(die, Die):
        return base if die is None else die
    if not (isinstance(die, str) and die in STANDARD_SIZES):
        raise ValueError(f"die must be a Die or one of {list(STANDARD_SIZES)}, got {die!r}")
    return Die.standard(die)


def _size(die: str | Die | None, size: float | None, edge: float | None) -> float | None:
    """The size keyword: ``size``, or ``edge`` for a d6 (never both)."""
    if edge is None:
        return size
    if size is not None:
        raise ValueError(f"give size or edge, not both (size={size!r}, edge={edge!r})")
    name = die.name if isinstance(die, Die) else die
    if name not in (None, "d6"):
        raise ValueError(f"edge is the d6's size; the die is a {name}: use size")
    return edge


def _walls(walls: str | tuple[Wall, ...]) -> tuple[Wall, ...]:
    """The ``walls`` keyword: a preset name or the walls themselves."""
    if isinstance(walls, str) and walls in WALLS:
        return preset_walls(walls)
    if isinstance(walls, Wall):
        return (walls,)
    if not (isinstance(walls, (tuple, list)) and all(isinstance(w, Wall) for w in walls)):
        raise ValueError(f"walls must be one of {sorted(WALLS)} or a tuple of Wall, "
                         f"got {walls!r}")
    return tuple(walls)


def _given(**values: object) -> dict[str, object]:
    """The keywords whose value is not None."""
    return {name: value for name, value in values.items() if value is not None}

"""The env's physical keywords: each validated where given, applied to a base scene.

:class:`SceneKeywords` holds the ``gym.make`` keywords that build the scene;
:meth:`SceneKeywords.build` turns them into a :class:`~dice_env.model.scene.Scene`. A keyword
changes only what it names; every other field of the base scene (its die, ground, rest test,
``t_max``, ...) is kept. A keyword that cannot be applied to the base scene (``mass`` on a
loaded die) or that would have no effect (``safety`` with a fixed ``dt``) is refused, never
dropped.

:func:`check_scene` refuses scenes the env cannot run as throws, whether built from keywords or
passed as ``scene``: a die whose weight alone sinks it into the table, ``t_max`` or a rest hold
of more than :data:`ENV_MAX_STEPS` steps, and the paper's contact law with a damping whose
air drag keeps the die from falling.
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
"""The env's simulated time limit per throw (s), the ``t_max`` of its scene when no ``scene``
is given. Half of :class:`~dice_env.model.scene.Scene`'s 10 s, a bound for any run: the env's gentle
throws settle in well under 2 s, so 5 s leaves them room and halves the compute of a die that
never settles."""
ENV_MAX_STEPS = 10**7
"""The most steps of one env throw (``t_max`` or ``rest_hold`` over the step): 21 times the
default throw's 4.8e5, so that no keyword makes one ``step`` run for minutes;
:data:`dice_env.model.scene.MAX_STEPS` (10**9) bounds any run of the simulator."""
MAX_SINK = 0.1  # the weight's sink of a flat die's corners into the table, in die sizes


def check_face(name: str, value: object, n_faces: int = 6) -> int:
    """``value`` as a face label 1 … ``n_faces``, or ``ValueError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an int in [1, {n_faces}], got {value!r}")
    check_range(name, int(value), 1, n_faces)
    return int(value)


@dataclass(frozen=True)
class SceneKeywords:
    """The ``gym.make`` keywords that build the env's scene; each one None keeps the base's.

    :meth:`build` applies the keywords given to a base scene (default
    ``Scene(t_max=DEFAULT_T_MAX)``). ``size``, ``edge``, ``mass`` and ``load_*`` rebuild a uniform
    standard die; the enum keywords take a member or its name (any case).
    """

    t_max: float | None = None
    """Simulated time limit per throw (s)."""
    die: str | Die | None = None
    """The die: a :class:`Die` or a standard name ("d4" … "d20", :meth:`Die.standard` with its
    default size and density)."""
    size: float | None = None
    """The die's size (m, :attr:`Die.size`)."""
    edge: float | None = None
    """The d6's size (m): ``size`` under the d6's name, never with ``size``."""
    mass: float | None = None
    """The die's mass (kg)."""
    load_face: int | None = None
    """The face a loaded die favours (1 … n; default n)."""
    load_fraction: float | None = None
    """The load's share of the mass, [0, 1): > 0 loads the die (:meth:`Die.load`)."""
    load_depth: float | None = None
    """The load's depth toward ``load_face``, [0, 1)."""
    stiffness: float | None = None
    """The table's contact stiffness S (N/m)."""
    damping: float | None = None
    """The table's contact damping D (N s/m)."""
    friction: float | None = None
    """The table's friction coefficient μ."""
    tilt_deg: float | None = None
    """The table's tilt about y from level (degrees, [0, 90))."""
    contact_law: str | ContactLaw | None = None
    """The table's contact law, "gated" or "paper"."""
    gravity: float | None = None
    """Gravity (m/s²)."""
    dt: float | None = None
    """A fixed step (s); refuses ``safety``."""
    safety: float | None = None
    """The automatic step's safety factor."""
    rest_speed: float | None = None
    """The rest test's speed (> 0)."""
    rest_hold: float | None = None
    """How long a die stays quiet to count as settled (s, >= 0)."""
    energy_tol: float | None = None
    """The energy rise that flags a throw unstable."""
    scheme: str | Scheme | None = None
    """The contact step, "paper" or "midpoint"."""
    friction_law: str | FrictionLaw | None = None
    """Friction, "stick_slip" or "regularized"."""
    friction_vmin: float | None = None
    """The regularized friction's umin (m/s); refused with any other ``friction_law``."""
    walls: str | tuple[Wall, ...] | None = None
    """A preset of :mod:`dice_env.model.surroundings` ("none", "tray", "craps") or a tuple of
    :class:`Wall`."""

    def build(self, scene: Scene | None = None) -> Scene:
        """``scene`` (default ``Scene(t_max=DEFAULT_T_MAX)``) with the keywords given (not None).

        ``tilt_deg`` tilts the table from level; a keyword the scene cannot take, or one
        without effect, is refused (see the module).
        """
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
        """``base`` or the ``die`` keyword's die, with the die keywords given.

        Only a uniform standard die can take ``size`` (``edge``), ``mass`` and ``load_*``.
        """
        base = _base_die(base, self.die)
        size = _size(self.die, self.size, self.edge)
        size_name = "size" if self.edge is None else "edge"
        load_face, load_fraction, load_depth = self.load_face, self.load_fraction, self.load_depth
        if load_face is not None:
            check_face("load_face", load_face, base.n_faces)
        if load_fraction is not None:
            check_range("load_fraction", load_fraction, 0.0, 1.0, high_open=True)
        if load_depth is not None:
            check_range("load_depth", load_depth, 0.0, 1.0, high_open=True)
        given = _given(**{size_name: size}, mass=self.mass, load_face=load_face,
                       load_fraction=load_fraction, load_depth=load_depth)
        if not given:
            return base
        if base.name not in STANDARD_SIZES or base != Die.standard(base.name, base.size,
                                                                   base.mass):
            com = ", ".join(f"{c:g}" for c in base.com)
            raise ValueError(
                f"{', '.join(given)} cannot be applied to the scene's die: it is not a uniform "
                f"die of a standard shape ({base!r}, com ({com}) m), so it cannot be rebuilt from "
                "keywords without losing its shape or mass distribution. Build the die you want "
                "in the scene (e.g. Die.standard(name, size, mass).load(face, fraction, depth)) "
                f"and leave out {', '.join(given)}")
        dims = {"size": base.size if size is None else size,
                "mass": base.mass if self.mass is None else self.mass}
        check_positive(size_name, dims["size"])
        check_positive("mass", dims["mass"])
        problem = (f"{size_name}={dims['size']:g} m, mass={dims['mass']:g} kg and load_fraction="
                   f"{load_fraction} give no valid die (a {base.name})")
        try:
            die = Die.standard(base.name, **dims)
            if load_fraction:
                die = die.load(**_given(face=load_face if load_face is not None else die.n_faces,
                                        fraction=load_fraction, depth=load_depth))
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
    """Refuse a scene the env cannot run as throws from ``release_height``; see the module."""
    _check_sink(scene)
    _check_steps(scene)
    if scene.ground.contact_law == ContactLaw.PAPER and scene.ground.damping > 0:
        _check_paper_drag(scene, release_height)


def _check_sink(scene: Scene) -> None:
    """The die's weight alone must not sink it more than :data:`MAX_SINK` die sizes.

    The die lies on its face with the fewest corners (4 for the d6, 3 for the d4).
    """
    die, ground = scene.die, scene.ground
    corners = min(len(face) for face in die.faces)
    sink = die.mass * scene.gravity * ground.normal[2] / (corners * ground.stiffness)
    if sink > MAX_SINK * die.size:
        raise ValueError(
            f"the die's weight would press a flat face's corners {sink:.3g} m into the table, "
            f"more than {MAX_SINK} of the die's size ({die.size:g} m): mass={die.mass:g} kg, "
            f"gravity={scene.gravity:g} m/s^2, stiffness={ground.stiffness:g} N/m; raise "
            "stiffness or size, or lower mass or gravity")


def _check_steps(scene: Scene) -> None:
    """A throw may take at most :data:`ENV_MAX_STEPS` steps of a computable step."""
    with np.errstate(all="ignore"):
        try:
            step = scene.step
        except (ArithmeticError, np.linalg.LinAlgError):
            step = math.nan
    if not math.isfinite(step) or step <= 0:
        raise ValueError(f"the step comes out as {step:g} s for {_step_origin(scene)}, "
                         f"size={scene.die.size:g}: bring them nearer the defaults")
    for name, value in (("t_max", scene.t_max), ("rest_hold", scene.rest.hold)):
        if value / step > ENV_MAX_STEPS:
            raise ValueError(
                f"{name} must be at most {ENV_MAX_STEPS:.0e} steps: {name}={value:g} s over a step "
                f"of {step:.3g} s is {value / step:.3g} steps ({_step_origin(scene)}); lower "
                f"{name}, or make the step longer")


def _check_paper_drag(scene: Scene, release_height: float) -> None:
    """The paper law's air drag (8 D v) must not outweigh the die in a drop from the hand.

    Without gravity toward the table the drag stops every die in the air: always refused.
    """
    g = scene.gravity * scene.ground.normal[2]
    weight = scene.die.mass * g
    drop_speed = math.sqrt(2.0 * g * release_height)
    damping = scene.ground.damping
    if g > 0 and 8.0 * damping * drop_speed <= weight:
        return
    limit = weight / (8.0 * drop_speed) if g > 0 else 0.0
    raise ValueError(
        f"contact_law='paper' needs damping <= m g / (8 sqrt(2 g release_height)) = "
        f"{limit:.4g} N s/m, got damping={damping:g}: the paper's law pushes every corner "
        "moving toward the table with D times its speed even in the air, an air drag of 8 D v, "
        f"so the die falls at most m g / (8 D) = {weight / (8.0 * damping):.3g} m/s (a drop "
        f"from release_height={release_height:g} m reaches {drop_speed:.3g} m/s; gravity="
        f"{scene.gravity:g} m/s^2) and the throws hardly land. Use contact_law='gated' (the "
        "default: a real table), or a damping that small (the table then barely damps impacts: "
        "restitution near 1)")


def _step_origin(scene: Scene) -> str:
    """Where the scene's step comes from, naming the keywords that set it."""
    if scene.dt is not None:
        return f"dt={scene.dt:g}"
    return (f"safety={scene.safety:g} times the critical step of {scene.stiffest_plane()}, "
            f"mass={scene.die.mass:g}")


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
    if isinstance(walls, str):
        if walls not in WALLS:
            raise ValueError(f"walls must be one of {sorted(WALLS)} or a tuple of Wall, "
                             f"got {walls!r}")
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

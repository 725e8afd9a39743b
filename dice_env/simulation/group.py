"""Several dice in one throw, colliding: the group's state, the die–die material, the run.

    dice = (Die(), Die.standard("d20"))
    state = GroupState.of([State.release(scene.with_(die=d), ...) for d in dice])
    result = simulate_group(scene, dice, state, until="decided")
    result.face      # (B, N): each die's face; 0 for a die not read (leaning on another)

The scene gives the planes, gravity, the scheme and the rest test, not the dice. Dice touch
each other through :class:`DieContact` (``docs/model.md``, "Several dice in one throw").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations
from typing import ClassVar

import numpy as np

from dice_env.model.checks import as_enum, check_type
from dice_env.model.defaults import DIE_MASS, STIFFNESS, damping_for_restitution
from dice_env.model.die import Die
from dice_env.model.scene import FrictionLaw, Scene, check_material, critical_step
from dice_env.physics import group_kernel
from dice_env.simulation.simulate import (
    UP,
    DiceArrays,
    RunResult,
    State,
    blank_outcome,
    check_run,
    ending,
    lock_energy,
    outcome_fields,
    pack_run,
    pack_scene,
    proven_rest,
    record_plan,
    recorded,
    run_kernel,
)

# Die against die, plastic on plastic: estimates (no measurement of dice striking dice is known
# to us): restitution about the die's on a hard table, friction within the polymer's 0.3-0.5.
DIE_RESTITUTION = 0.5
DIE_FRICTION = 0.4
MAX_DICE = 64  # dice in one throw: every pair is tested each step
GROUP_UNTIL = ("rest", "decided", "t_max")  # simulate_group's until (early rest: one die alone)
TOUCH = 1e-3  # dice released closer than this fraction of the smaller's size touch, not overlap
MAX_APART = 2**20  # beyond this table's step over the pair's, every move takes the pair's step
MAX_UNITS = 5  # a move apart takes at most this many units (ratio above 1/5; see moves)
# DieContact(islands=True): the least and the most time (s) its islands step on their own
ISLAND_WINDOW = (0.05e-3, 0.1)


@dataclass(frozen=True)
class DieContact:
    """The die–die material: stiffness, damping and friction of a contact.

    ``stiffness`` (N/m per contact), ``damping`` (N s/m; default: :data:`DIE_RESTITUTION` for the
    default die), ``friction_law`` (:class:`dice_env.model.scene.FrictionLaw`), ``tangential``:
    the stick-slip spring and damper as a fraction of them. With ``islands`` (the default;
    several dice on a level floor), dice that cannot meet for a while step apart, each island
    of dice at its own step with its own flights, and an island at rest sleeps until a die
    that may reach it wakes it (``docs/performance.md``, "Islands"); without, every die takes
    every step of the throw, at the nearest pair's step.
    """

    stiffness: float = STIFFNESS
    damping: float = damping_for_restitution(DIE_RESTITUTION, STIFFNESS, DIE_MASS)
    friction: float = DIE_FRICTION
    friction_law: FrictionLaw = FrictionLaw.STICK_SLIP
    tangential: float = 2.0 / 7.0
    islands: bool = True

    def __post_init__(self) -> None:
        check_material(self.stiffness, self.damping, self.friction, self.tangential)
        check_type("islands", self.islands, bool)
        object.__setattr__(self, "friction_law",
                           as_enum("friction_law", FrictionLaw, self.friction_law))

    @property
    def law(self) -> str:
        """The friction law in words, for reports: ``"stick-slip"`` or ``"regularized"``."""
        return self.friction_law.name.lower().replace("_", "-")


@dataclass
class GroupState(DiceArrays):
    """State of B throws of N dice: :class:`~dice_env.simulation.simulate.DiceArrays`, (B, N)."""

    LEAD: ClassVar[tuple[str, ...]] = ("B", "N")

    @classmethod
    def of(cls, states: Sequence[State]) -> GroupState:
        """The group whose die ``i`` is ``states[i]``, each a batch of B (:meth:`State.release`)."""
        if not isinstance(states, Sequence) or not states \
                or not all(isinstance(s, State) for s in states):
            raise TypeError("states must be a non-empty sequence of State")
        sizes = {s.batch_size for s in states}
        if len(sizes) > 1:
            raise ValueError(f"states must share one batch size B, got {sorted(sizes)}")
        return cls(*(np.stack(arrays, axis=1) for arrays in zip(
            *(s._arrays() for s in states), strict=True)))

    def die(self, i: int) -> State:
        """Die ``i`` of every throw, as a :class:`State`."""
        return State(*(np.array(a[:, i]) for a in self._arrays()))

    @property
    def n_dice(self) -> int:
        """Dice per throw N."""
        return self.position.shape[1]


@dataclass
class GroupResult(RunResult):
    """Outcome of B throws of N dice: the fields of :class:`dice_env.Result`, and more.

    Per die (B, N): ``face`` (0 where not read), ``read`` (False for a die leaning on another
    at the end), ``impacts``, ``die_impacts`` (contacts with another die faster than the rest
    speed), ``max_penetration``, ``sunk`` (also a die-die overlap beyond the sink limit);
    ``touched`` (B, N, P): the die touched plane P (:attr:`Scene.planes`). Per throw (B,):
    ``settled`` (every die at rest), ``decided``, ``rest_time``, ``unstable``,
    ``energy_rise``, ``overlap`` (deepest die–die overlap, m), ``steps``; ``final``.

    The first die–die contact: ``meet_dice`` (B, 2) the pair (-1: none), ``meet_steps`` (B, 2)
    the steps done at its start and end (-1: none, or still touching), ``meet_velocity`` and
    ``meet_spin`` (B, 2, N, 3): every die's velocity and angular velocity (world) before its
    first force and after its last (with islands, the pair's island's; 0 for the others).
    Recorded: ``t`` (n,), ``x_cm`` (B, n, N, 3),
    ``orientations`` (B, n, N, 3, 3).
    """

    final: GroupState
    read: np.ndarray
    overlap: np.ndarray
    die_impacts: np.ndarray
    touched: np.ndarray
    meet_dice: np.ndarray
    meet_steps: np.ndarray
    meet_velocity: np.ndarray
    meet_spin: np.ndarray
    t: np.ndarray | None = None
    x_cm: np.ndarray | None = None
    orientations: np.ndarray | None = None


def group_step(scene: Scene, dice: Sequence[Die], contact: DieContact = DieContact()) -> float:
    """The unit of a throw's steps (s): :meth:`Scene.step_within` the least critical step.

    Without ``scene.dt``, where the pairs' critical step is the least, a fraction of the table's
    (:func:`moves`): a move takes the most whole units within the pairs' step, the table's
    step while no pair is within reach.
    """
    return _step(scene, _dice(dice), contact)[0]


def group_steps(scene: Scene, dice: Sequence[Die], t_max: float | None = None,
                contact: DieContact = DieContact()) -> tuple[float, int]:
    """:func:`group_step` and its count to ``t_max`` (default the scene's).

    The scene's :data:`~dice_env.model.scene.MAX_STEPS` bounds the moves near another die
    (:func:`pair_step`), the most a throw can take, not the units.
    """
    dt, _, units = _step(scene, _dice(dice), contact)
    return dt, _units_to(scene, t_max, dt, units[0])


def _units_to(scene: Scene, t_max: float | None, dt: float, near: int) -> int:
    """Units of ``dt`` to ``t_max``; refused beyond ``MAX_STEPS`` moves of ``near`` units."""
    scene.steps_for(t_max, near * dt)
    return max(1, round((scene.t_max if t_max is None else t_max) / dt))


def pair_step(scene: Scene, dice: Sequence[Die], contact: DieContact = DieContact()) -> float:
    """The step of a move with dice within reach (s): :func:`group_step` times the units near."""
    dt, _, units = _step(scene, _dice(dice), contact)
    return units[0] * dt


def moves(ratio: float) -> tuple[int, int]:
    """Units of a move near and apart, for the pairs' step ``ratio`` times the table's.

    The ``apart`` up to :data:`MAX_UNITS` with the largest ``near / apart <= ratio`` (the
    fewest units of equals); below ``1 / MAX_UNITS``, ``near`` is 1.
    """
    if ratio * MAX_UNITS < 1:
        return 1, math.ceil(1 / ratio)
    return max(((math.floor(apart * ratio), apart) for apart in range(1, MAX_UNITS + 1)),
               key=lambda pair: (pair[0] / pair[1], -pair[1]))


def _step(scene: Scene, dice: tuple[Die, ...], contact: DieContact) -> tuple[float, float, tuple]:
    """:func:`group_step`, a pair's least reduced mass (kg; inf for one), :func:`moves`."""
    alone = [scene.with_(die=die) for die in dice]
    critical = min(s.critical_dt for s in alone)
    masses = [s.effective_mass for s in alone]
    reduced = min((m_i * m_j / (m_i + m_j) for m_i, m_j in combinations(masses, 2)),
                  default=math.inf)
    if len(dice) > 1:
        pair = critical_step(contact.stiffness, contact.damping, reduced, scene.scheme)
        if not scene.safety * pair > 0:
            raise ValueError(f"the step of die against die comes out as {pair:g} s from the "
                             f"contact's stiffness {contact.stiffness:g} N/m and damping "
                             f"{contact.damping:g} N s/m (DieContact) on the dice's reduced "
                             f"mass {reduced:.3g} kg: bring them nearer the defaults")
        if scene.dt is None and pair < critical and critical / pair < MAX_APART:
            units = moves(pair / critical)
            return scene.safety * critical / units[1], reduced, units
        critical = min(critical, pair)
    return scene.step_within(critical, "the dice on the planes and against each other"), \
        reduced, (1, 1)


def simulate_group(scene: Scene, dice: Sequence[Die], state: GroupState, *,
                   contact: DieContact = DieContact(), t_max: float | None = None,
                   until: str = "rest", free_flight: bool = True, record_every: int = 0,
                   orientations: bool = False, num_threads: int | None = None) -> GroupResult:
    """Run B throws of the N ``dice`` together; ``state`` is not modified.

    Keywords as :func:`dice_env.simulate`; ``until`` in :data:`GROUP_UNTIL`; ``record_every``
    > 0 records the centres (and the ``orientations``); ``contact`` the die–die material and
    whether dice step in islands (:class:`DieContact`). Refused besides: dice that overlap at
    the start, more than :data:`MAX_DICE` dice, a die-die step that underflows, with
    ``until="decided"`` a gravity whose energies overflow.
    """
    dice = _dice(dice)
    threads = check_run(scene, state, GroupState, record_every, num_threads,
                        free_flight=free_flight, orientations=orientations)
    ends = ending(until, GROUP_UNTIL)
    check_type("contact", contact, DieContact)
    if state.n_dice != len(dice):
        raise ValueError(f"state holds {state.n_dice} dice per throw, dice {len(dice)}")
    dt, reduced, units = _step(scene, dice, contact)
    n_steps = _units_to(scene, t_max, dt, units[0])
    out = state.copy()
    b, n = out.batch_size, out.n_dice
    _check_apart(dice, out)
    scenes = [scene.with_(die=die, dt=dt, allow_unstable=True) for die in dice]
    size = min(d.size for d in dice)
    outcome = group_kernel.GroupOutcome(
        **blank_outcome(scene, np.stack([s.sink(out.position[:, i], out.orientation[:, i])
                                         for i, s in enumerate(scenes)], axis=1), size),
        overlap=np.zeros(b), contacts=np.zeros((b, n), np.int64),
        touching=np.zeros((b, n), np.bool_), die_impacts=np.zeros((b, n), np.int64),
        touched=np.zeros((b, n, len(scene.planes)), np.bool_),
        meet_dice=np.full((b, 2), -1, np.int64), meet_steps=np.full((b, 2), -1, np.int64),
        meet=np.zeros((b, 2, n, 6)))
    _, contact_planes = pack_scene(scenes[0])
    options, _ = pack_run(scenes[0], n_steps=n_steps, free_flight=free_flight)
    hold = scene.rest.hold / dt  # beyond the run (never rest) as n_steps, to fit an int64
    stops = group_kernel.GroupStops(
        n_steps=n_steps, at_rest=ends.at_rest, v_rest=float(scene.rest.speed),
        hold_steps=n_steps if hold >= n_steps else math.ceil(hold), decide=ends.decided,
        energy_scale=float(sum(d.mass * scene.gravity * d.size for d in dice)),
        islands=contact.islands and n > 1,  # a group of one is the single die
        least=max(1, math.ceil(ISLAND_WINDOW[0] / dt)), most=max(1, int(ISLAND_WINDOW[1] / dt)))
    bodies = _bodies(scenes, ends.decided)
    stride, n_rec = record_plan(record_every, n_steps, b * n * (12 if orientations else 3),
                                f"{b} throws of {n} dice")
    records = group_kernel.GroupRecords(
        stride=stride, x=np.zeros((b, n_rec, n, 3)),
        orientation=np.zeros((b, n_rec if orientations else 0, n, 3, 3)))
    inputs = (group_kernel.GroupDice(*out._arrays()), bodies, _hulls(dice, bodies),
              _pair(scene, contact, dt, reduced, units), contact_planes, options, stops, records)
    run_kernel("dice", inputs, outcome, batch=b, threads=threads, work=b * n * n_steps)
    fields = outcome_fields(scene, outcome, size)
    # The kernel checks the centres, velocities and momenta; a rotation that overflows in the
    # last step (a spin near 1e300 rad/s) leaves a non-finite orientation it did not see.
    fields["unstable"] |= ~np.all([np.isfinite(a).reshape(b, -1).all(axis=1)
                                   for a in out._arrays()], axis=0)
    fields["sunk"] |= outcome.overlap[:, None] > scene.sink_limit * size
    read = ~(outcome.touching & (outcome.contacts < 3))
    face = np.stack([die.face_read(out.orientation[:, i], UP) for i, die in enumerate(dice)],
                    axis=1)
    return GroupResult(
        face=np.where(read, face, 0), read=read, final=out, overlap=outcome.overlap,
        die_impacts=outcome.die_impacts, touched=outcome.touched, meet_dice=outcome.meet_dice,
        meet_steps=outcome.meet_steps, meet_velocity=outcome.meet[..., :3],
        meet_spin=outcome.meet[..., 3:], **fields,
        **recorded(record_every, records, dt,
                   {"orientations": records.orientation} if orientations else {}))


def _pair(scene: Scene, contact: DieContact, dt: float, reduced: float,
          units: tuple[int, int]) -> group_kernel.Pair:
    """The kernel's die–die contact: the pair's ``reduced`` mass (kg), :func:`moves` of ``dt``."""
    near = units[0] * dt
    return group_kernel.Pair(
        float(contact.stiffness), float(contact.damping), float(contact.friction),
        float(scene.friction_vmin), float(group_kernel.GRIP * reduced / near),
        contact.friction_law == FrictionLaw.STICK_SLIP and contact.friction > 0,
        float(contact.tangential * contact.stiffness),
        float(contact.tangential * contact.damping), float(near / reduced), *map(int, units))


def _dice(dice: Sequence[Die]) -> tuple[Die, ...]:
    """``dice`` as a tuple of 1 to :data:`MAX_DICE` dice."""
    if not isinstance(dice, Sequence) or not all(isinstance(d, Die) for d in dice):
        raise TypeError("dice must be a sequence of Die")
    if not 1 <= len(dice) <= MAX_DICE:
        raise ValueError(f"dice must hold 1 to {MAX_DICE} dice, got {len(dice)}")
    return tuple(dice)


def _bodies(scenes: list[Scene], decide: bool) -> group_kernel.Bodies:
    """The kernel's :class:`~dice_env.physics.group_kernel.Bodies`, one scene per die."""
    dice = [s.die for s in scenes]
    packed = [pack_scene(s)[0] for s in scenes]
    lock = [np.full(d.n_faces, -math.inf) for d in dice]
    floor = np.zeros(len(dice))
    deciding = zip(scenes, dice, strict=True) if decide else ()  # the rule's locks and floors
    for i, (scene, die) in enumerate(deciding):
        weight = die.mass * scene.gravity
        try:
            lock[i] = lock_energy(scene)
            floor[i] = weight * float(die.resting_heights.min()) - weight**2 / (
                2.0 * scene.ground.stiffness)
        except OverflowError as error:  # (m g)^2 beyond floats: a gravity near 1e300
            raise ValueError(f"gravity={scene.gravity:g} m/s^2 overflows the energies of "
                             f"until='decided' for die {i} ((m g)^2 / 2 S, mass "
                             f"{die.mass:g} kg): lower gravity, or pass an until other "
                             "than 'decided'") from error
    per_die = {name: np.array([getattr(p, name) for p in packed])
               for name in ("mass", "inv_inertia", "inv_iso", "inv_i_min", "r_max", "reads_down")}
    return group_kernel.Bodies(
        vertices=_padded([p.vertices for p in packed], 0.0),
        n_vertices=np.array([len(d.vertices) for d in dice]),
        faces=_padded([d.face_normals for d in dice], 0.0),
        n_faces=np.array([d.n_faces for d in dice]), lock=_padded(lock, -math.inf), floor=floor,
        low=np.array([_least_energy(s) for s in scenes]),
        rest=np.array([_rest_bound(s) for s in scenes]), **per_die)


def _rest_bound(scene: Scene) -> float:
    """The energy (J) below which a quiet die alone stays quiet (``-inf``: none, or overflow)."""
    try:
        return sum(proven_rest(scene, early_rest=True))
    except OverflowError:  # (m g)^2 beyond floats: no proof
        return -math.inf


def _least_energy(scene: Scene) -> float:
    """A lower bound of the die's energy on the scene's ground (J; ``-inf`` if not level).

    Resting on its lowest face, the ground's spring pressed by the whole weight.
    """
    ground, weight = scene.ground, np.float64(scene.die.mass * scene.gravity)
    if tuple(ground.normal) != (0.0, 0.0, 1.0):
        return -math.inf
    with np.errstate(over="ignore"):
        low = weight * (ground.offset + float(scene.die.resting_heights.min())) \
            - weight**2 / (2.0 * ground.stiffness)
    return float(low) if math.isfinite(low) else -math.inf


def _hulls(dice: tuple[Die, ...], bodies: group_kernel.Bodies) -> group_kernel.Hulls:
    """The kernel's :class:`~dice_env.physics.group_kernel.Hulls` of ``dice``."""
    vertices = [bodies.vertices[i, :len(d.vertices)] for i, d in enumerate(dice)]
    classes = [_edge_classes(v, d.edges) for v, d in zip(vertices, dice, strict=True)]
    planes = [np.column_stack([d.face_normals, [v[face[0]] @ normal for face, normal in zip(
        d.faces, d.face_normals, strict=True)]]) for v, d in zip(vertices, dice, strict=True)]
    n_starts = max(len(start) for _, start, _ in classes)
    return group_kernel.Hulls(
        axes=_padded([d.face_normals[_distinct_axes(d.face_normals)] for d in dice]),
        directions=_padded([d for *_, d in classes]),
        edges=_padded([d.edges[order] for d, (order, *_) in zip(dice, classes, strict=True)], 0),
        classes=np.stack([np.pad(start, (0, n_starts - len(start)), mode="edge")
                          for _, start, _ in classes]),  # padded classes are empty
        planes=_padded(planes), n_planes=np.array([len(p) for p in planes]),
        n_vertices=bodies.n_vertices, r_max=bodies.r_max)


def _padded(rows: list[np.ndarray], fill: float | None = None) -> np.ndarray:
    """The rows stacked, each padded to the longest with ``fill`` (None: its first entry)."""
    size = max(len(r) for r in rows)
    pads = [np.repeat(r[:1], size - len(r), axis=0) if fill is None
            else np.full((size - len(r), *r.shape[1:]), fill, r.dtype) for r in rows]
    return np.stack([np.concatenate([r, pad]) for r, pad in zip(rows, pads, strict=True)])


def _distinct_axes(normals: np.ndarray) -> np.ndarray:
    """The faces whose normals are distinct axes: the first of two opposite faces."""
    opposite = np.abs(normals[:, None] + normals[None]).max(axis=-1) <= 1e-9
    return np.flatnonzero(~np.tril(opposite, -1).any(axis=1))


def _edge_classes(vertices: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, ...]:
    """The edges by direction: their order, each class's start in it (then the end), its axis."""
    directions = vertices[edges[:, 1]] - vertices[edges[:, 0]]
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    parallel = np.linalg.norm(np.cross(directions[:, None], directions[None]), axis=-1) <= 1e-9
    firsts, cls = np.unique(parallel.argmax(axis=0), return_inverse=True)  # by first member
    return (np.argsort(cls, kind="stable"), np.concatenate([[0], np.cumsum(np.bincount(cls))]),
            directions[firsts])


def _check_apart(dice: tuple[Die, ...], state: GroupState) -> None:
    """Refuse dice that overlap by more than :data:`TOUCH` of the smaller one's size."""
    sizes = np.array([d.size for d in dice])
    inside = overlaps(dice, state) > TOUCH * np.minimum.outer(sizes, sizes)  # (B, N, N)
    pairs = np.argwhere(np.triu(inside.any(axis=0), 1))
    if len(pairs):
        i, j = pairs[0]
        throw = int(np.flatnonzero(inside[:, i, j])[0])
        raise ValueError(f"state.position: dice {i} and {j} of throw {throw} overlap at the "
                         "start (no plane separates them)")


def overlaps(dice: Sequence[Die], state: GroupState) -> np.ndarray:
    """How deep each pair of ``dice`` overlaps in ``state``: (B, N, N), m, <= 0 where apart.

    The least overlap along the separating axes: both dice's face normals and edge crosses.
    """
    dice = _dice(dice)
    corners = [state.position[:, i, None, :] + np.einsum(
        "bij,kj->bki", state.orientation[:, i], die.vertices_body) for i, die in enumerate(dice)]
    normals = [np.einsum("bij,fj->bfi", state.orientation[:, i], die.face_normals)
               for i, die in enumerate(dice)]
    edges = [c[:, die.edges[:, 1]] - c[:, die.edges[:, 0]]
             for c, die in zip(corners, dice, strict=True)]
    b, n = state.batch_size, len(dice)
    depth = np.full((b, n, n), -np.inf)
    for i, j in combinations(range(n), 2):
        crossed = np.cross(edges[i][:, :, None], edges[j][:, None, :]).reshape(b, -1, 3)
        length = np.linalg.norm(crossed, axis=-1, keepdims=True)
        crossed = crossed / np.where(length > 0, length, 1.0)
        axes = np.concatenate([normals[i], normals[j], crossed], axis=1)  # (B, A, 3)
        on_i = np.einsum("bai,bki->bak", axes, corners[i])
        on_j = np.einsum("bai,bki->bak", axes, corners[j])
        overlap = np.minimum(on_i.max(-1) - on_j.min(-1), on_j.max(-1) - on_i.min(-1))
        faces = normals[i].shape[1] + normals[j].shape[1]
        real = np.concatenate([np.ones((b, faces), bool),
                               length[..., 0] > 1e-9 * (dice[i].size * dice[j].size)], axis=1)
        depth[:, i, j] = depth[:, j, i] = np.where(real, overlap, np.inf).min(axis=1)
    return depth

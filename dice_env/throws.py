"""Throws: the hands that draw releases, and the faces the releases show.

The one home of the throw distributions the studies, the agents and the benchmarks share. The
uniform orientations and the chi-square use scipy (the ``studies`` extra), imported when called.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from dice_env.intervals import wilson
from dice_env.model.checks import check_int
from dice_env.model.defaults import DIE_EDGE
from dice_env.model.die import Die
from dice_env.model.rotations import axis_angle, rotation_vector_to_matrix
from dice_env.model.scene import Scene
from dice_env.model.surroundings import tray
from dice_env.simulation.group import GroupState
from dice_env.simulation.simulate import DiceArrays, Result, State, simulate

BATCH = 2048  # dice per kernel call
T_TRAY = 10.0  # s: the limit of a throw into the tray; a throw not decided by then is voided
T_THROW = 4.0  # s: the most a throw whose face is compared runs (all settle sooner)
PER_ROW = 4  # dice per row in a hand


@dataclass(frozen=True)
class Vigour:
    """Ranges of a random throw, each drawn uniformly; orientation uniform over rotations.

    ``clearance``: centre height above touching (edges); ``speed`` (edges/s) in a uniform
    direction toward the table; ``spin`` (rad/s) about a uniform axis.
    """

    clearance: tuple[float, float] = (5.0, 20.0)
    speed: tuple[float, float] = (30.0, 150.0)
    spin: tuple[float, float] = (10.0, 100.0)


# The fairness throws: dropped from 8–32 cm, 0.5–2.4 m/s, 10–100 rad/s for the 16 mm die.
VIGOROUS = Vigour()


def random_orientations(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` rotation matrices uniform over SO(3), shape (n, 3, 3)."""
    from scipy.spatial.transform import Rotation  # scipy: the studies extra

    return Rotation.random(n, random_state=rng).as_matrix()


def random_directions(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` unit vectors uniform over the sphere, shape (n, 3)."""
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def toward_table(scene: Scene, directions: np.ndarray) -> np.ndarray:
    """``directions`` (n, 3) with those pointing away from the table mirrored toward it."""
    away = directions @ np.asarray(scene.ground.normal) > 0
    return np.where(away[:, None], -directions, directions)


def touching_height(scene: Scene, orientation: np.ndarray) -> np.ndarray:
    """Height of the centre (along the normal) at which the lowest corner touches the plane."""
    corners = np.einsum("bij,kj->bki", orientation, scene.die.vertices_body)
    return -(corners @ np.asarray(scene.ground.normal)).min(axis=1)


def release_state(scene: Scene, orientation: np.ndarray, clearance: np.ndarray,
                  velocity: np.ndarray, spin: np.ndarray) -> State:
    """Dice released ``clearance`` (m) above touching, above the origin along the normal."""
    normal = np.asarray(scene.ground.normal)
    height = touching_height(scene, orientation) + clearance
    return State.release(scene, height[:, None] * normal, velocity, spin, orientation)


def vigorous_throws(scene: Scene, n: int, rng: np.random.Generator,
                    vigour: Vigour = VIGOROUS, unit: float | None = None) -> State:
    """``n`` random throws from ``vigour``, lengths in ``unit`` (m; default the die's size)."""
    a = scene.die.size if unit is None else unit
    orientation = random_orientations(rng, n)
    clearance = rng.uniform(*vigour.clearance, n) * a
    direction = toward_table(scene, random_directions(rng, n))
    velocity = direction * rng.uniform(*vigour.speed, n)[:, None] * a
    spin = random_directions(rng, n) * rng.uniform(*vigour.spin, n)[:, None]
    return release_state(scene, orientation, clearance, velocity, spin)


def energy_throws(scene: Scene, excess: np.ndarray, rng: np.random.Generator) -> State:
    """Throws whose energy exceeds a gentle touching release by ``excess`` (units m g a).

    The excess is split at random (uniform on the simplex) between drop height, speed toward
    the table's half-space and spin; ``excess = 0`` is a release at rest with a corner touching.
    """
    die, g = scene.die, scene.gravity
    n = len(excess)
    parts = rng.dirichlet(np.ones(3), n) * (excess * (die.mass * g * die.size))[:, None]
    orientation = random_orientations(rng, n)
    direction = toward_table(scene, random_directions(rng, n))
    velocity = direction * np.sqrt(2 * parts[:, 1] / die.mass)[:, None]
    axis = random_directions(rng, n)
    body_axis = np.einsum("bji,bj->bi", orientation, axis)
    inertia_along = np.einsum("bi,ij,bj->b", body_axis, die.inertia_body, body_axis)
    spin = axis * np.sqrt(2 * parts[:, 2] / inertia_along)[:, None]
    clearance = parts[:, 0] / (die.mass * g * scene.ground.normal[2])
    return release_state(scene, orientation, clearance, velocity, spin)


def hand_throws(scene: Scene, n: int, rng: np.random.Generator,
                vigour: Vigour = VIGOROUS, unit: float = DIE_EDGE) -> State:
    """``n`` random throws of ``scene``'s die drawn from ``vigour`` in units of ``unit`` (m).

    The default unit, the default d6's edge, gives every die the same hand.
    """
    return vigorous_throws(scene, n, rng, vigour, unit)


@dataclass(frozen=True)
class Hand:
    """A hand that throws several dice at once (docs/pairs.md); metres, m/s, rad/s.

    Dice held as :func:`layout` holds them, ``clearance`` above touching; one
    velocity ``speed`` toward the table plus each die's normal ``noise``; each die its own
    ``spin`` and orientation. Ranges are drawn uniformly per throw.
    """

    spacing: float = 0.03
    per_row: int = PER_ROW
    clearance: tuple[float, float] = (0.08, 0.32)
    speed: tuple[float, float] = (0.48, 2.4)
    noise: float = 0.1
    spin: tuple[float, float] = (10.0, 100.0)


HAND = Hand()  # the fairness study's vigorous throw, given to both dice at once


def tray_scene() -> Scene:
    """The 30 x 20 cm tray on the default table, each throw ending by :data:`T_TRAY`."""
    return Scene(walls=tray(), t_max=T_TRAY)


def layout(n_dice: int, spacing: float, normal: Sequence[float] = (0.0, 0.0, 1.0),
           per_row: int = PER_ROW) -> np.ndarray:
    """Offsets (n_dice, 3) of dice held ``spacing`` apart, centred on the hand's centre.

    Rows of ``per_row`` across the throw (along y), each row centred, the rows along x; all in
    the plane across ``normal`` (the table's). The env's hand and :class:`Hand` both hold dice so.
    """
    check_int("n_dice", n_dice, 1)
    normal = np.asarray(normal, dtype=np.float64)
    x_axis = np.cross([0.0, 1.0, 0.0], normal)
    x_axis /= np.linalg.norm(x_axis)
    y_axis = np.cross(normal, x_axis)
    rows = -(-n_dice // per_row)
    row, column = np.divmod(np.arange(n_dice), per_row)
    in_row = np.minimum(per_row, n_dice - row * per_row)
    return spacing * ((row - (rows - 1) / 2)[:, None] * x_axis
                      + (column - (in_row - 1) / 2)[:, None] * y_axis)


def group_throws(scene: Scene, dice: tuple[Die, ...], n: int, rng: np.random.Generator,
                 hand: Hand = HAND) -> GroupState:
    """``n`` throws of ``dice`` from one ``hand`` (see :class:`Hand`) in ``scene``."""
    height = rng.uniform(*hand.clearance, n) + max(d.reach for d in dice)
    velocity = (toward_table(scene, random_directions(rng, n))
                * rng.uniform(*hand.speed, n)[:, None])
    states = []
    offsets = layout(len(dice), hand.spacing, scene.ground.normal, hand.per_row)
    for die, offset in zip(dice, offsets, strict=True):
        position = offset + height[:, None] * np.asarray(scene.ground.normal)
        spin = random_directions(rng, n) * rng.uniform(*hand.spin, n)[:, None]
        states.append(State.release(scene.with_(die=die), position,
                                    velocity + rng.normal(0.0, hand.noise, (n, 3)), spin,
                                    random_orientations(rng, n)))
    return GroupState.of(states)


@dataclass(frozen=True)
class Cup:
    """A cup of twelve dice tipped onto the table, in one layer (:data:`CUP_BLOCK`; docs/weldon.md).

    Lengths in die edges, speeds in edges/s, spins in rad/s; ranges drawn uniformly. ``spacing``
    exceeds the cube's diagonal (sqrt 3), so the dice start apart in any orientation; dice in
    layers would pile onto each other and many end leaning.
    """

    height: tuple[float, float] = (3.0, 6.0)
    speed: tuple[float, float] = (10.0, 40.0)
    scatter: float = 5.0
    spin: tuple[float, float] = (5.0, 40.0)
    spacing: float = 1.8
    jitter: float = 0.03


CUP = Cup()
CUP_BLOCK = (4, 3, 1)  # the cup's dice: a block of 4 x 3 x 1


def cup_throws(scene: Scene, n: int, rng: np.random.Generator, cup: Cup = CUP) -> list[State]:
    """``n`` cups of twelve dice (the scene's die): one :class:`State` of ``n`` per die."""
    a = scene.die.size
    nx, ny, nz = CUP_BLOCK
    slots = np.array([(i - (nx - 1) / 2, j - (ny - 1) / 2, k)
                      for k in range(nz) for j in range(ny) for i in range(nx)])
    lowest = math.sqrt(3) / 2 + rng.uniform(*cup.height, n)
    heading = rng.uniform(0.0, 2 * math.pi, n)
    carried = np.stack([np.cos(heading), np.sin(heading), np.zeros(n)], axis=1)
    carried *= rng.uniform(*cup.speed, n)[:, None]
    states = []
    for slot in slots:
        centre = slot * cup.spacing + rng.uniform(-cup.jitter, cup.jitter, (n, 3))
        centre[:, 2] += lowest
        velocity = carried + rng.normal(0.0, cup.scatter, (n, 3))
        spin = random_directions(rng, n) * rng.uniform(*cup.spin, n)[:, None]
        states.append(State.release(scene, centre * a, velocity * a, spin,
                                    random_orientations(rng, n)))
    return states


@dataclass(frozen=True)
class Release:
    """A nominal release and the thrower's hand noise (SI units, angles in rad).

    ``height`` of the centre, ``spin`` (angular velocity), ``tilt`` (rotation vector); normal
    noise of the ``sigma_*`` per component; ``target``: the face that counts as success.
    """

    name: str
    height: float
    velocity: tuple[float, float, float]
    spin: tuple[float, float, float]
    tilt: tuple[float, float, float]
    sigma_position: float
    sigma_velocity: float
    sigma_spin: float
    sigma_angle: float
    target: int = 1

    def sample(self, scene: Scene, n: int, rng: np.random.Generator) -> State:
        """``n`` noisy releases of this throw."""
        position = np.array([0.0, 0.0, self.height]) + self.sigma_position * rng.normal(size=(n, 3))
        velocity = np.array(self.velocity) + self.sigma_velocity * rng.normal(size=(n, 3))
        spin = np.array(self.spin) + self.sigma_spin * rng.normal(size=(n, 3))
        noise = rotation_vector_to_matrix(self.sigma_angle * rng.normal(size=(n, 3)))
        tilt = rotation_vector_to_matrix(np.array(self.tilt))
        return State.release(scene, position, velocity, spin, noise @ tilt)


RELEASES = (
    Release("gentle", 0.064, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.44, 0.26, 0.0),
            0.002, 0.02, 0.5, 0.05),
    Release("tossed", 0.15, (0.5, 0.0, 0.0), (0.0, 10.0, 5.0), (0.3, 0.0, 0.0),
            0.005, 0.1, 3.0, 0.1),
    Release("vigorous", 0.25, (1.0, 0.2, -0.5), (25.0, -15.0, 10.0), (0.0, 0.0, 0.0),
            0.01, 0.2, 5.0, 0.2),
)


@dataclass(frozen=True)
class SetThrow:
    """The craps set throw (docs/craps.md): two d6 held in a set, thrown by the env's hand.

    The hand moves at ``speed`` (m/s) along x and ``lift`` up, with ``backspin`` (rad/s) about
    -y, released ``height`` (m) up; an action component of 1 is ``max_speed`` (m/s) or
    ``max_spin`` (rad/s).
    """

    speed: float = 2.0
    lift: float = 1.5
    backspin: float = 20.0
    height: float = 0.12
    max_speed: float = 4.0
    max_spin: float = 40.0

    def action(self, speed: float | None = None) -> np.ndarray:
        """The throw (6,): ``speed`` (default :attr:`speed`) along x, then lift and backspin."""
        speed = self.speed if speed is None else speed
        return np.array([speed / self.max_speed, 0.0, self.lift / self.max_speed, 0.0,
                         -self.backspin / self.max_spin, 0.0])


SET_THROW = SetThrow()


def sevens_set() -> np.ndarray:
    """The two dice's orientations in the hand (2, 3, 3): the "all-sevens" set.

    Die 2 is die 1 turned half a turn about y (the roll axis): while both turn alike about y,
    the faces up add to 7.
    """
    return np.stack([np.eye(3), axis_angle([0.0, 1.0, 0.0], np.pi)])


def crossed_set() -> np.ndarray:
    """The two dice's orientations in the hand (2, 3, 3): a set against the seven.

    Die 2 is die 1 turned a quarter turn about x: 2 of the 16 pairings of the faces rolled
    through about y add to seven (4 for dice set alike or in :func:`sevens_set`).
    """
    return np.stack([np.eye(3), axis_angle([1.0, 0.0, 0.0], np.pi / 2)])


def batches(state: DiceArrays, size: int, bar: object = None) -> Iterator[DiceArrays]:
    """``state``'s throws in consecutive batches of ``size``; a ``bar`` advances by each."""
    for start in range(0, state.batch_size, size):
        batch = type(state)(*(a[start:start + size] for a in state._arrays()))
        yield batch
        if bar is not None:
            bar.update(batch.batch_size)


@dataclass
class Faces:
    """Faces of a set of throws: ``counts`` (F,) per label over the ``ended`` throws.

    ``undecided``: the throws not counted (moving at the time limit, unstable or sunk);
    ``chi2``, ``p_value``: the chi-square test of uniformity.
    """

    counts: np.ndarray
    ended: int
    undecided: int
    chi2: float
    p_value: float

    @classmethod
    def of(cls, counts: np.ndarray, throws: int) -> Faces:
        """The faces ``counts`` (F,) counted among ``throws`` throws, with their chi-square."""
        from scipy import stats  # scipy: the studies extra

        ended = int(counts.sum())
        chi2, p = stats.chisquare(counts) if ended else (np.nan, np.nan)
        return cls(counts, ended, throws - ended, float(chi2), float(p))

    @property
    def shares(self) -> np.ndarray:
        """Each face's share of the counted throws."""
        return self.counts / self.ended

    @property
    def intervals(self) -> np.ndarray:
        """95% Wilson intervals of each face's probability, (F, 2)."""
        return wilson(self.counts, self.ended)

    @property
    def max_deviation(self) -> float:
        """Largest deviation of a face's share from ``1/F``."""
        return float(np.abs(self.shares - 1 / len(self.counts)).max())


def counted(result: Result) -> np.ndarray:
    """The throws whose face counts: ended decided or at rest, neither unstable nor sunk."""
    return (result.decided | result.settled) & ~result.unstable & ~result.sunk


def throw_faces(scene: Scene, state: State, bar: object = None, batch: int = BATCH) -> Faces:
    """Throw ``state`` in ``scene`` until each face is decided; count the faces."""
    n_faces = scene.die.n_faces
    counts = np.zeros(n_faces, np.int64)
    for chunk in batches(state, batch, bar):
        res = simulate(scene, chunk, until="decided")
        counts += np.bincount(res.face[counted(res)], minlength=n_faces + 1)[1:]
    return Faces.of(counts, state.batch_size)


def face_agreement(scene: Scene, start: State, factor: int = 4,
                   perturbation: float = 1e-9) -> dict[str, np.ndarray]:
    """Per throw: same face at ``dt`` and at ``dt/factor`` (``step``); and at ``dt`` again.

    ``floor``: the same face after adding ``perturbation`` rad/s to every spin component.
    """
    scene = scene.with_(t_max=T_THROW)
    base = simulate(scene, start)
    fine = simulate(scene.with_(dt=scene.step / factor), start)
    nudged = State.release(scene, start.position, start.velocity,
                           start.angular_velocity + perturbation, start.orientation)
    floor = simulate(scene, nudged)
    return {"step": base.face == fine.face, "floor": base.face == floor.face,
            "settled": base.settled & fine.settled, "penetration": base.max_penetration}


"""Throw dice: the state of a batch, one call to the compiled kernel, and the outcomes."""

from __future__ import annotations

import functools
import importlib.util
import math
import os
import threading
from collections.abc import Callable
from dataclasses import dataclass, fields
from types import ModuleType
from typing import ClassVar, NamedTuple, Self

import numba
import numpy as np

from dice_env.model.checks import (
    as_batch,
    check_bool,
    check_choice,
    check_finite,
    check_int,
    check_range,
    check_type,
)
from dice_env.model.rotations import orthonormality_error
from dice_env.model.scene import ContactLaw, FrictionLaw, Scene, Scheme
from dice_env.physics import group_kernel, kernel, vector_kernel
from dice_env.simulation.compile_notice import announce, cache_hint, ready


@dataclass
class DiceArrays:
    """The five state arrays of dice, with :attr:`LEAD` leading axes (B for :class:`State`).

    ``orientation``: body-to-world rotations; ``angular_velocity``: the ω of the corner
    velocities. Checked: finite, one lead shape, a die at least, rotations to :data:`ROTATION_TOL`.
    """

    LEAD: ClassVar[tuple[str, ...]] = ("B",)

    position: np.ndarray
    velocity: np.ndarray
    angular_momentum: np.ndarray
    orientation: np.ndarray
    angular_velocity: np.ndarray

    def __post_init__(self) -> None:
        owner, lead = type(self).__name__, len(self.LEAD)
        axes = ", ".join(self.LEAD)
        for name in (f.name for f in fields(self)):
            tail = (3, 3) if name == "orientation" else (3,)
            array = np.asarray(getattr(self, name), dtype=np.float64)
            if array.ndim != len(tail) + lead or array.shape[lead:] != tail:
                raise ValueError(f"{owner}.{name} must have shape ({axes}, "
                                 f"{', '.join(map(str, tail))}), got {array.shape}")
            check_finite(f"{owner}.{name}", array)
            object.__setattr__(self, name, array)
        shapes = sorted({a.shape[:lead] for a in self._arrays()})
        if len(shapes) > 1:
            what = "batch size B" if lead == 1 else f"shape ({axes})"
            raise ValueError(f"{owner} arrays must share one {what}, got {shapes}")
        if min(self.position.shape[:lead]) == 0:
            got = " = ".join(f"{axis} >= 1" for axis in self.LEAD)
            raise ValueError(f"{owner} must hold at least one die ({got}), got "
                             f"({axes}) = {self.position.shape[:lead]}")
        error = orthonormality_error(self.orientation).max()
        if error > ROTATION_TOL:
            raise ValueError(f"{owner}.orientation must be rotation matrices (R R^T = I, "
                             f"det R = +1, to {ROTATION_TOL:g}), got an error of {error:.3g}")

    @property
    def batch_size(self) -> int:
        """Number of throws B."""
        return self.position.shape[0]

    def copy(self) -> Self:
        """An independent, checked copy with C-contiguous arrays (the kernels' one layout)."""
        return type(self)(*(np.array(a, order="C") for a in self._arrays()))

    def _arrays(self) -> tuple[np.ndarray, ...]:
        return tuple(getattr(self, f.name) for f in fields(self))


@dataclass
class State(DiceArrays):
    """State of a batch of B dice (world frame): the :class:`DiceArrays` with lead axis B.

    ``angular_velocity`` is ``I_world^-1 L`` except where a paper script starts without spin.
    """

    @classmethod
    def release(cls, scene: Scene, position: np.ndarray, velocity: np.ndarray,
                angular_velocity: np.ndarray | None = None,
                orientation: np.ndarray | None = None) -> State:
        """Dice released at ``position`` with ``velocity`` and ``angular_velocity`` (rad/s).

        Each argument is (3,) or (B, 3) (orientation (3, 3) or (B, 3, 3)), broadcast to the
        batch; default no spin, identity orientation. No corner may start deeper in the table
        than :data:`RELEASE_SINK` of the die's size or ``m g / S``, whichever is more.
        """
        position = as_batch("position", position, (3,))
        velocity = as_batch("velocity", velocity, (3,))
        spin = as_batch("angular_velocity",
                        np.zeros(3) if angular_velocity is None else angular_velocity, (3,))
        rot = as_batch("orientation", np.eye(3) if orientation is None else orientation, (3, 3))
        if orthonormality_error(rot).max() > 1e-9:
            raise ValueError("orientation must be rotation matrices (R R^T = I, det R = +1, "
                             "to 1e-9)")
        sizes = {a.shape[0] for a in (position, velocity, spin, rot)} - {1}
        if len(sizes) > 1:
            raise ValueError(f"batch sizes of the release arguments disagree: {sorted(sizes)}")
        size = sizes.pop() if sizes else 1
        if size == 0:
            raise ValueError("release arguments must hold at least one die, got a batch of 0")
        position, velocity, spin, rot = (np.broadcast_to(a, (size, *a.shape[1:]))
                                         for a in (position, velocity, spin, rot))
        sink = scene.sink(position, rot)
        pressed = max(RELEASE_SINK * scene.die.size,
                      scene.die.mass * scene.gravity / scene.ground.stiffness)
        if sink.max() > pressed:
            i = int(sink.argmax())
            raise ValueError(f"position must hold every corner of the die above the table (or "
                             f"touching it, pressed in by at most {pressed:.3g} m): die {i} "
                             f"starts with a corner {sink[i]:.3g} m below it (centre "
                             f"{position[i].tolist()})")
        world_inertia = rot @ scene.die.inertia_body @ rot.transpose(0, 2, 1)
        momentum = np.einsum("bij,bj->bi", world_inertia, spin)
        return cls(*(np.array(a) for a in (position, velocity, momentum, rot, spin)))


@dataclass
class RunResult:
    """The fields of every run's outcome, one die's or several's; :class:`Result` explains them."""

    face: np.ndarray
    settled: np.ndarray
    decided: np.ndarray
    rest_time: np.ndarray
    impacts: np.ndarray
    unstable: np.ndarray
    energy_rise: np.ndarray
    max_penetration: np.ndarray
    sunk: np.ndarray
    steps: np.ndarray
    final: DiceArrays


@dataclass
class Result(RunResult):
    """Outcome of a batch of throws (arrays over the batch, B).

    ``face``: the label read at the end (against gravity; the d4's face down); ``settled``:
    came to rest; ``rest_time``: when the rest began (s; the time simulated if not settled);
    ``decided``: ended by ``until="decided"``; ``impacts``: airborne-to-contact transitions;
    ``unstable``: energy rose beyond the scene's tolerance or the state stopped being finite;
    ``energy_rise``: the largest rise in units of that tolerance; ``max_penetration``: deepest
    corner below a plane (m); ``sunk``: deeper than the scene's
    :attr:`~dice_env.model.scene.Scene.sink_limit` (never count such a face); ``steps``;
    ``final``: the state at the end. Recorded: ``t`` (n,), ``x_cm`` (B, n, 3), ``energy``
    (B, n; kinetic + m g z), ``orientations`` (B, n, 3, 3), ``nodes`` (B, n, 8, 3).
    """

    final: State
    t: np.ndarray | None = None
    x_cm: np.ndarray | None = None
    energy: np.ndarray | None = None
    orientations: np.ndarray | None = None
    nodes: np.ndarray | None = None


def simulate(scene: Scene, state: State, *, t_max: float | None = None, until: str = "rest",
             record_every: int = 0, record: tuple[str, ...] = ("energy",),
             num_threads: int | None = None, free_flight: bool = True,
             device: str = "cpu") -> Result:
    """Run a batch of throws; ``state`` is not modified.

    ``t_max`` overrides the scene's time limit. ``until`` (:data:`ENDINGS`) ends a die's run
    before it: ``"rest"`` after the hold ``scene.rest.hold``; ``"early_rest"`` as soon as its
    energy proves rest (fair die, horizontal table; the final state still vibrating);
    ``"decided"`` once its energy is below :func:`lock_energy` of its face (not ``settled``);
    ``"t_max"``: the time limit alone. ``record_every`` > 0 stores the centre of mass every that
    many steps, plus what ``record`` names among :data:`RECORDS`. ``num_threads``: 1 to
    ``NUMBA_NUM_THREADS`` (default all). ``free_flight`` takes the contact-free steps in
    analytic jumps. ``device``: ``"cpu"`` or ``"cuda"`` (:mod:`dice_env.physics.cuda_kernel`;
    no records).

    Refused before any work, naming the argument: more than
    :data:`dice_env.model.scene.MAX_STEPS` steps, records above :data:`MAX_RECORD_BYTES`, a
    state deeper in a plane than the scene's sink limit. Ctrl-C raises ``KeyboardInterrupt``.
    """
    threads = check_run(scene, state, State, record_every, num_threads,
                        free_flight=free_flight)
    ending(until)
    record = _record_names(record)
    cuda = require_device(device)
    body, contact = _packed_scene(scene)
    n_steps = scene.steps_for(t_max)
    out = state.copy()
    b = out.batch_size
    outcome = kernel.Outcome(**blank_outcome(scene, scene.sink(out.position, out.orientation),
                                             scene.die.size))
    records = _records(record, record_every, b, n_steps, len(body.vertices))
    options, stops = pack_run(scene, n_steps=n_steps, until=until, free_flight=free_flight)
    inputs = (kernel.Dice(*out._arrays()), body, contact, options, stops, records)
    if cuda:
        cuda.run(*inputs, outcome)
    else:
        paper = vector_kernel.covers(scene, b, options.flight, records.stride <= n_steps)
        if paper:  # it keeps no records: in their place, which stop tests its loop runs
            inputs = (*inputs[:-1], vector_kernel.stop_tests(stops))
        run_kernel("paper" if paper else "die", inputs, outcome, batch=b, threads=threads,
                   work=b * n_steps)
    arrays = {"energy": records.energy, "orientations": records.orientation, "nodes": records.nodes}
    return Result(face=scene.die.face_read(out.orientation, UP), final=out,
                  **outcome_fields(scene, outcome, scene.die.size),
                  **recorded(record_every, records, scene.step,
                             {name: arrays[name] for name in record}))


class Ending(NamedTuple):
    """What ends a die's run before the time limit: one ``until`` of :data:`ENDINGS`."""

    at_rest: bool  # rest: quiet for the hold (scene.rest)
    early_rest: bool  # with at_rest: rest proven by the energy, before the hold is out
    decided: bool  # a decided face (:func:`lock_energy`)


# simulate's ``until``: the rules that end a run (simulate_group takes GROUP_UNTIL of them)
ENDINGS = {
    "rest": Ending(at_rest=True, early_rest=False, decided=False),
    "early_rest": Ending(at_rest=True, early_rest=True, decided=False),
    "decided": Ending(at_rest=True, early_rest=False, decided=True),
    "t_max": Ending(at_rest=False, early_rest=False, decided=False),
}


def ending(until: object, allowed: tuple[str, ...] = tuple(ENDINGS)) -> Ending:
    """The :data:`ENDINGS` rules of ``until``, refused (``ValueError``) unless in ``allowed``."""
    check_choice("until", until, allowed)
    return ENDINGS[until]


def pack_run(scene: Scene, *, n_steps: int, until: str = "rest",
             free_flight: bool = True) -> tuple[kernel.Options, kernel.Stops]:
    """The kernel's options and stop rules for ``n_steps``; keywords as :func:`simulate`'s."""
    ends = ending(until)
    ground, dt = scene.ground, scene.step
    options = kernel.Options(
        gravity=float(scene.gravity), dt=float(dt), rotation=bool(scene.rotation),
        flight=bool(free_flight and (ground.contact_law != ContactLaw.PAPER
                                     or ground.damping == 0)),
        midpoint=scene.scheme == Scheme.MIDPOINT)
    rest_energy, rest_excess = proven_rest(scene, ends.early_rest)
    stops = kernel.Stops(
        n_steps=int(n_steps), at_rest=ends.at_rest, v_rest=float(scene.rest.speed),
        hold_steps=math.ceil(scene.rest.hold / dt), rest_energy=float(rest_energy),
        rest_excess=float(rest_excess),
        lock=lock_energy(scene) if ends.decided else np.full(scene.die.n_faces, -math.inf),
        energy_scale=float(scene.die.mass * scene.gravity * scene.die.size))
    return options, stops


# each plane contact law's code in the kernel (kernel.Contact.law)
CONTACT_LAWS = {ContactLaw.GATED: kernel.GATED, ContactLaw.PAPER: kernel.PAPER}


def pack_scene(scene: Scene) -> tuple[kernel.Body, kernel.Contact]:
    """The kernel's die and contact groups for ``scene`` (see :mod:`dice_env.physics.kernel`)."""
    die, ground = scene.die, scene.ground
    inertia = die.inertia_body
    body = kernel.Body(
        vertices=np.ascontiguousarray(die.vertices_body), mass=float(die.mass),
        inv_inertia=np.linalg.inv(inertia),
        inv_iso=1.0 / float(inertia[0, 0]) if die.is_isotropic else 0.0,
        inv_i_min=float(1.0 / np.linalg.eigvalsh(inertia)[0]), r_max=die.reach,
        faces=np.ascontiguousarray(die.face_normals), reads_down=bool(die.reads_down))
    contact = kernel.Contact(
        planes=np.array([[*plane.normal, plane.offset, plane.stiffness, plane.damping,
                          plane.friction, plane.tangential * plane.stiffness,
                          plane.tangential * plane.damping] for plane in scene.planes],
                        dtype=np.float64),
        law=CONTACT_LAWS[ground.contact_law],
        stick=scene.friction_law == FrictionLaw.STICK_SLIP, vmin=float(scene.friction_vmin))
    return body, contact


def _records(record: tuple[str, ...], record_every: int, b: int, n_steps: int,
             n_vertices: int) -> kernel.Records:
    """Empty records for ``b`` dice every ``record_every`` steps (0: none), size-checked."""
    tails = {"energy": (), "orientations": (3, 3), "nodes": (n_vertices, 3)}  # RECORDS' order
    stride, n_rec = record_plan(record_every, n_steps,
                                b * (3 + sum(math.prod(tails[name]) for name in record)),
                                f"{b} dice")
    return kernel.Records(stride, np.zeros((b, n_rec, 3)),
                          *(np.zeros((b, n_rec if name in record else 0, *tail))
                            for name, tail in tails.items()))


def check_run(scene: Scene, state: object, kind: type, record_every: object,
              num_threads: int | None, **flags: object) -> int:
    """Check the arguments :func:`simulate` and ``simulate_group`` share; the thread count."""
    check_type("scene", scene, Scene)
    check_type("state", state, kind)
    check_int("record_every", record_every, 0)
    for name, flag in flags.items():
        check_bool(name, flag)
    return thread_count(num_threads)


def record_plan(record_every: int, n_steps: int, floats: int, what: str) -> tuple[int, int]:
    """The kernel's record stride (beyond the run: none) and the states recorded in ``n_steps``.

    Each state is ``floats`` numbers of ``what``; refused above :data:`MAX_RECORD_BYTES`.
    """
    n_rec = n_steps // record_every if record_every else 0
    size = 8 * n_rec * floats
    if size > MAX_RECORD_BYTES:
        raise ValueError(f"record_every={record_every} records {n_rec} states of {what} "
                         f"({size / 2**30:.3g} GiB), more than the limit of "
                         f"{MAX_RECORD_BYTES / 2**30:g} GiB: record less often, fewer throws "
                         "or a shorter t_max")
    return (int(record_every) if 0 < record_every <= n_steps else n_steps + 1), n_rec


def recorded(record_every: int, records: kernel.Records | group_kernel.GroupRecords,
             dt: float, fields: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """A result's records: ``t`` (s), ``x_cm`` and ``fields``; none when ``record_every`` is 0."""
    if not record_every:
        return {}
    return {"t": np.arange(1, records.x.shape[1] + 1) * (records.stride * dt),
            "x_cm": records.x, **fields}


def blank_outcome(scene: Scene, sink: np.ndarray, size: float) -> dict[str, np.ndarray]:
    """The kernels' blank outcome for dice ``sink`` (m, (B,) or (B, N)) deep at the start.

    Refused beyond the scene's sink limit of ``size``, the (smallest) die's size.
    """
    if sink.max() > scene.sink_limit * size:
        at = np.unravel_index(int(sink.argmax()), sink.shape)
        die = f"die {at[-1]}" + (f" of throw {at[0]}" if sink.ndim > 1 else "")
        raise ValueError(f"state.position: {die} starts with a corner {sink[at]:.3g} m inside "
                         f"a plane, deeper than the scene's sink limit ({scene.sink_limit:g} "
                         f"of {size:g} m)")
    b = len(sink)
    return {"status": np.zeros(b, np.int8), "unstable": np.zeros(b, np.bool_),
            "rest_time": np.zeros(b), "energy_rise": np.zeros(b),
            "steps": np.zeros(b, np.int64), "impacts": np.zeros(sink.shape, np.int64),
            "max_pen": np.maximum(sink, 0.0), "abort": np.zeros(1, np.int64)}


def outcome_fields(scene: Scene, outcome: kernel.Outcome | group_kernel.GroupOutcome,
                   size: float) -> dict[str, np.ndarray]:
    """The :class:`RunResult` fields but ``face`` and ``final``; ``size``: the smallest die's."""
    energy_rise = outcome.energy_rise / scene.energy_tol
    return {"settled": outcome.status == kernel.SETTLED,
            "decided": outcome.status == kernel.DECIDED, "rest_time": outcome.rest_time,
            "impacts": outcome.impacts, "unstable": outcome.unstable | (energy_rise > 1.0),
            "energy_rise": energy_rise, "max_penetration": outcome.max_pen,
            "sunk": outcome.max_pen > scene.sink_limit * size, "steps": outcome.steps}


DEVICES = ("cpu", "cuda")  # where simulate runs
UP = np.array([0.0, 0.0, 1.0])  # against gravity: faces are read relative to it
RECORDS = ("energy", "orientations", "nodes")
RELEASE_SINK = 1e-3  # deepest corner of a release, as a fraction of the die's size
MAX_RECORD_BYTES = 4 * 2**30  # records larger than this are refused before any work
ROTATION_TOL = 1e-6  # State.orientation's allowed orthonormality error (a long run drifts)
# Each kind of run's CPU kernel: its loop on numba's threads, its serial loop, its name.
BACKENDS: dict[str, tuple[Callable, Callable, str]] = {
    "die": (kernel.simulate_batch, kernel.simulate_serial, "the die's kernel"),
    "paper": (vector_kernel.simulate_batch, vector_kernel.simulate_serial,
              "the paper scene's kernel"),
    "dice": (group_kernel.simulate_groups, group_kernel.simulate_groups_serial,
             "the kernel of several dice"),
}
# Each loop's name in the compile notice (its cold compile time: compile_times.json).
COMPILES = {loop: name + suffix for parallel, serial, name in BACKENDS.values()
            for loop, suffix in ((serial, ""), (parallel, " on threads"))}
SERIAL_FIRST = 256  # throws: a batch up to this size runs serially until its parallel loop
# is compiled (a first small batch does not wait for that compile)
_LONG_RUN = 2_000_000  # die-steps (about 0.1 s) from which a run goes on a worker thread
_after_fork = False  # set in a child forked after the parent's kernel started threads


def _forked() -> None:
    """In a forked child: GNU OpenMP's threads cannot be used again, so run serially."""
    global _after_fork
    try:
        layer = numba.threading_layer()
    except ValueError:  # the parent never started a parallel region: nothing to avoid
        return
    _after_fork = _after_fork or layer == "omp"


os.register_at_fork(after_in_child=_forked)


def _record_names(record: object) -> tuple[str, ...]:
    """``record`` as a tuple of names from :data:`RECORDS` (a single name may be a string)."""
    names = (record,) if isinstance(record, str) else record
    if not isinstance(names, (tuple, list)) or not all(isinstance(n, str) for n in names):
        raise TypeError(f"record must be a name or a tuple of names from {RECORDS}, "
                        f"got {record!r}")
    unknown = set(names) - set(RECORDS)
    if unknown:
        raise ValueError(f"record must name only {', '.join(map(repr, RECORDS))}, "
                         f"got {sorted(unknown)}")
    return tuple(names)


def require_device(device: str) -> ModuleType | None:
    """The CUDA kernel's module for ``"cuda"`` (refused without numba-cuda and a GPU), else None."""
    check_choice("device", device, DEVICES)
    if device == "cpu":
        return None
    if importlib.util.find_spec("numba_cuda") is None:
        raise ImportError("device='cuda' needs numba-cuda: pip install 'dice_env[cuda]' (an "
                          "NVIDIA GPU and its driver too)")
    from numba import cuda

    if not cuda.is_available():
        raise RuntimeError("device='cuda' found no usable CUDA GPU (numba.cuda.is_available() "
                           "is False): it needs an NVIDIA GPU with its driver; "
                           "numba.cuda.detect() says what is missing")
    from dice_env.physics import cuda_kernel

    return cuda_kernel


def thread_count(num_threads: int | None) -> int:
    """The threads for a run: ``num_threads`` in 1..NUMBA_NUM_THREADS, None for all of them."""
    most = numba.config.NUMBA_NUM_THREADS
    if num_threads is None:
        return most
    return check_int("num_threads", num_threads, 1, most, also=" (NUMBA_NUM_THREADS) or None")


def run_kernel(kind: str, inputs: tuple, outcome: tuple, *, batch: int, threads: int,
               work: int) -> None:
    """Run the CPU kernel of ``kind`` (:data:`BACKENDS`) on ``inputs`` into ``outcome``.

    Serially for one die or thread, after a fork, or up to :data:`SERIAL_FIRST` dice while the
    parallel loop is not compiled. ``work`` (die-steps) decides if Ctrl-C is watched for.
    """
    parallel, serial, _ = BACKENDS[kind]
    args = (*inputs, outcome)
    serial_run = (batch == 1 or threads == 1 or _after_fork
                  or (batch <= SERIAL_FIRST and not ready(parallel, args)))
    run = serial if serial_run else parallel
    announce(run, args, COMPILES[run])
    with cache_hint(run):
        _run_interruptibly(run, args, outcome.abort, threads, long=work > _LONG_RUN)


def _run_interruptibly(run: Callable, args: tuple, abort: np.ndarray, threads: int, *,
                       long: bool) -> None:
    """``run(*args)`` on ``threads`` threads; a ``long`` one on a worker, Ctrl-C sets ``abort``."""
    failure: list[BaseException] = []

    def call() -> None:
        previous = numba.get_num_threads()  # per thread in numba
        numba.set_num_threads(threads)
        try:
            run(*args)
        except BaseException as error:  # raised again in the caller's thread
            failure.append(error)
        finally:
            numba.set_num_threads(previous)

    if long:
        worker = threading.Thread(target=call, name="dice_env-kernel", daemon=True)
        worker.start()
        try:
            while worker.is_alive():
                worker.join(0.05)
        except KeyboardInterrupt:
            abort[0] = 1
            worker.join()
            raise
    else:
        call()
    if failure:
        raise failure[0]


# pack_scene once per scene: every field of a Scene is checked to be frozen and hashable
_packed_scene = functools.lru_cache(maxsize=64)(pack_scene)


def proven_rest(scene: Scene, early_rest: bool) -> tuple[float, float]:
    """Lowest total energy of the die and the excess above it that proves rest (0: none).

    Fair, isotropic die on a horizontal table, ``k`` vertices a face: lowest flat on a face,
    ``m g h - (m g)^2 / (2 k S)``; below ``(m g)^2 / (2 k S)`` above it no lift-off, below
    ``v^2 / (2 (1/m + r_max^2 / I))`` no vertex at ``v``; half the smaller, for the wobble.
    """
    die, ground = scene.die, scene.ground
    corners = {len(face) for face in die.faces}
    if (not early_rest or not die.is_fair or not die.is_isotropic or len(corners) > 1
            or ground.normal != (0.0, 0.0, 1.0)):
        return -math.inf, 0.0
    weight = die.mass * scene.gravity
    lift = weight**2 / (2.0 * corners.pop() * ground.stiffness)
    move = scene.rest.speed**2 / (2.0 * (1.0 / die.mass + die.reach**2 / die.inertia_body[0, 0]))
    return weight * float(die.resting_heights.min()) - lift, 0.5 * min(lift, move)


LOCK_MARGIN = 0.25  # of the barrier: above the energy's largest rise after a decision, at the
# default step and the largest safety (tests/test_decided.py checks it)


def lock_energy(scene: Scene, margin: float = LOCK_MARGIN) -> np.ndarray:
    """Total energy (J) below which each face read can no longer change, (F,) in label order.

    ``m g h_tip - (m g)^2 / (2 S)`` lowered by ``margin`` (in [0, 1]) of the barrier
    ``m g (h_tip - h_rest)`` (``docs/performance.md``); ``-inf`` unless the table is horizontal,
    with gravity and rotation.
    """
    check_range("margin", margin, 0.0, 1.0)
    die, ground = scene.die, scene.ground
    if ground.normal != (0.0, 0.0, 1.0) or scene.gravity == 0 or not scene.rotation:
        return np.full(die.n_faces, -math.inf)
    weight = die.mass * scene.gravity
    tip, rest = die.tipping_heights, die.resting_heights
    return weight * (tip - margin * (tip - rest)) - weight**2 / (2.0 * ground.stiffness)


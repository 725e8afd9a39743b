"""Many throws in seeded chunks, in this process or on a Ray cluster, merged into one tally.

Chunk ``i`` draws from ``SeedSequence(seed, spawn_key=(i,))`` alone and :class:`Tally` objects
merge exactly, so :func:`run_throws` gives the same result bit for bit here or on Ray. A run
folder keeps each finished chunk; run again, it computes only the missing ones. Ray is an
optional extra (``pip install 'dice_env[ray]'``); the command line is a checkout's,
``python -m studies.many_throws``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import math
import re
import sys
import types
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dice_env.disk import write_atomically
from dice_env.model.checks import check_choice, check_int
from dice_env.model.die import STANDARD_SIZES, Die
from dice_env.model.scene import Scene
from dice_env.simulation.chunks import FolderError, identity, load, prepare
from dice_env.simulation.simulate import State, simulate
from dice_env.throws import Faces, counted, hand_throws

# Per-throw outcomes a chunk keeps, with their dtypes.
OUTCOMES = {"face": np.int16, "counted": np.bool_, "decided": np.bool_, "settled": np.bool_,
            "unstable": np.bool_, "sunk": np.bool_, "steps": np.int64, "time": np.float64,
            "impacts": np.int32}
MOMENTS = ("steps", "time", "impacts")  # outcomes summarised by their sum and sum of squares
# Histogram bins: time to the end over [0, t_max]; impacts 0, 1, ... (the last: that or more)
TIME_BINS, IMPACT_BINS = 50, 32
CHUNK = 10_000  # throws per chunk by default: seconds of work for one thread

Draw = Callable[[Scene, int, np.random.Generator], State]


@dataclass(frozen=True)
class Spec:
    """What a run throws; a run folder holds one spec.

    ``chunk``: throws per chunk (the last takes the rest); ``draw(scene, n, rng)``: picklable
    for Ray and, in a run folder, named by its import path (no lambda or local function).
    """

    scene: Scene
    throws: int
    chunk: int
    seed: int
    draw: Draw = hand_throws

    def __post_init__(self) -> None:
        if not isinstance(self.scene, Scene):
            raise TypeError(f"scene must be a Scene or a standard die's name "
                            f"{tuple(STANDARD_SIZES)}, got {type(self.scene).__name__}")
        for name, low in (("throws", 1), ("chunk", 1), ("seed", 0)):
            object.__setattr__(self, name, check_int(name, getattr(self, name), low))
        if not callable(self.draw):
            raise TypeError(f"draw must be callable (scene, n, rng) -> State, got {self.draw!r}")

    @property
    def n_chunks(self) -> int:
        """Number of chunks."""
        return -(-self.throws // self.chunk)

    def size(self, index: int) -> int:
        """Throws in chunk ``index``."""
        return min(self.chunk, self.throws - index * self.chunk)

    def rng(self, index: int) -> np.random.Generator:
        """Chunk ``index``'s generator: the ``index``-th child of ``SeedSequence(seed)``."""
        return np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(index,)))

    def record(self) -> dict:
        """The spec as JSON data; ValueError for a ``draw`` that no name identifies."""
        try:
            draw = _named(self.draw)
        except ValueError as error:
            raise ValueError(f"draw={self.draw!r} cannot be recorded in a run folder: {error}; "
                             "pass a module-level function or a functools.partial of one") from None
        data = {"scene": dataclasses.asdict(self.scene), "throws": self.throws,
                "chunk": self.chunk, "seed": self.seed, "draw": draw}
        return json.loads(json.dumps(data))

    @functools.cached_property
    def identity(self) -> str:
        """A hash of :meth:`record`: the spec a chunk file belongs to."""
        return identity(self.record())

    def chunk_record(self, index: int) -> dict:
        """What chunk ``index``'s file records of itself: the spec, seed, index and throws."""
        return {"spec": self.identity, "seed": self.seed, "index": index,
                "throws": self.size(index)}


def _named(value: object) -> str:
    """``value`` by its importable name or its repr; ValueError when neither identifies it."""
    if isinstance(value, functools.partial):
        return "functools.partial({})".format(", ".join(
            [_named(value.func), *map(_named, value.args),
             *(f"{k}={_named(v)}" for k, v in value.keywords.items())]))
    if isinstance(value, types.MethodType):
        return f"{_named(value.__self__)}.{value.__func__.__name__}"
    if isinstance(value, (types.FunctionType, types.BuiltinFunctionType, type)):
        found = sys.modules.get(value.__module__)
        for part in value.__qualname__.split("."):
            found = getattr(found, part, None)
        if found is not value:
            raise ValueError(f"{value.__qualname__} is no module-level name (a lambda or a "
                             "local function is not identified by its name)")
        return f"{value.__module__}.{value.__qualname__}"
    shown = repr(value)
    if re.search(r" at 0x[0-9a-fA-F]+", shown):
        raise ValueError(f"{shown} is not identified by its repr (it shows an address)")
    return shown


@dataclass(frozen=True)
class Tally:
    """Counts and sums over a set of throws; :meth:`merge` adds tallies exactly.

    ``counts`` (F,): faces of the throws that count (:func:`~dice_env.throws.counted`);
    ``unfinished``: no face by the time limit; ``sums`` (3, 2): sum and sum of squares of each
    of :data:`MOMENTS`; ``time_hist``, ``impacts_hist``: :data:`TIME_BINS`, :data:`IMPACT_BINS`.
    """

    throws: int
    counts: np.ndarray
    unfinished: int
    unstable: int
    sunk: int
    sums: np.ndarray
    time_hist: np.ndarray
    impacts_hist: np.ndarray

    @classmethod
    def of(cls, scene: Scene, outcomes: dict[str, np.ndarray]) -> Tally:
        """The tally of one chunk's per-throw ``outcomes`` (arrays named :data:`OUTCOMES`)."""
        o = outcomes
        sums = np.array([[math.fsum(o[q].astype(float)), math.fsum(o[q].astype(float) ** 2)]
                         for q in MOMENTS])
        return cls(throws=len(o["counted"]),
                   counts=np.bincount(o["face"][o["counted"]], minlength=scene.die.n_faces + 1)[1:],
                   unfinished=int(np.sum(~(o["decided"] | o["settled"]))),
                   unstable=int(o["unstable"].sum()), sunk=int(o["sunk"].sum()), sums=sums,
                   time_hist=np.histogram(np.clip(o["time"], 0.0, scene.t_max), TIME_BINS,
                                          (0.0, scene.t_max))[0],
                   impacts_hist=np.bincount(np.minimum(o["impacts"], IMPACT_BINS - 1),
                                            minlength=IMPACT_BINS))

    @classmethod
    def merge(cls, tallies: Iterable[Tally]) -> Tally:
        """One tally of all ``tallies``: counts added, sums by ``math.fsum`` (any order)."""
        parts = list(tallies)
        if not parts:
            raise ValueError("tallies must hold at least one Tally, got none")
        added = {f.name: sum(getattr(p, f.name) for p in parts)
                 for f in dataclasses.fields(cls) if f.name != "sums"}
        return cls(**added, sums=np.apply_along_axis(math.fsum, 0, [p.sums for p in parts]))

    @property
    def faces(self) -> Faces:
        """The face counts with their shares, intervals and chi-square of uniformity."""
        return Faces.of(self.counts, self.throws)

    def mean(self, name: str) -> float:
        """Mean of ``name`` (one of :data:`MOMENTS`) over all throws."""
        return float(self.sums[_moment(name), 0] / self.throws)

    def std(self, name: str) -> float:
        """Sample standard deviation of ``name`` (one of :data:`MOMENTS`); 0 for one throw."""
        total, squares = self.sums[_moment(name)]
        n = self.throws
        return math.sqrt(max(squares - total * total / n, 0.0) / (n - 1)) if n > 1 else 0.0

    def same_as(self, other: Tally) -> bool:
        """Equal in every field, bit for bit."""
        return all(np.array_equal(getattr(self, f.name), getattr(other, f.name))
                   for f in dataclasses.fields(self))


def _moment(name: str) -> int:
    check_choice("name", name, MOMENTS)
    return MOMENTS.index(name)


def throw_chunk(spec: Spec, index: int, num_threads: int | None = None) -> dict[str, np.ndarray]:
    """Per-throw outcomes (arrays named :data:`OUTCOMES`) of chunk ``index`` of ``spec``."""
    state = spec.draw(spec.scene, spec.size(index), spec.rng(index))
    res = simulate(spec.scene, state, until="decided", num_threads=num_threads)
    return {"face": res.face.astype(np.int16), "counted": counted(res), "decided": res.decided,
            "settled": res.settled, "unstable": res.unstable, "sunk": res.sunk, "steps": res.steps,
            "time": res.rest_time, "impacts": res.impacts.astype(np.int32)}


def run_throws(scene: Scene | str, throws: int, *, chunk: int = CHUNK, seed: int = 0,
               ray: str | None = None, out: Path | str | None = None,
               progress: Callable[[int], object] | None = None, draw: Draw = hand_throws,
               workers: int | None = None, max_retries: int = 3) -> Tally:
    """Throw ``throws`` throws of ``scene`` in seeded chunks of ``chunk``; merge their tallies.

    ``scene``: a :class:`Scene`, or a standard die's name (``"d20"``) on the default table.
    ``ray``: None (this process, all numba threads) or an address (``"auto"``,
    ``"ray://host:10001"``, ``"local"``: a fresh instance), one Ray task on one thread per chunk;
    ``workers``: chunks at once on Ray (default: its CPUs); ``max_retries``: reruns of a chunk
    whose worker died; ``out``: the run folder (FolderError if another run's); ``progress(n)``:
    called as throws are done, ``n`` at a time (those of a run folder's chunks first), e.g. a
    tqdm bar's ``update``. The result does not depend on ``ray``, ``workers``, ``out``,
    ``progress`` or on interruptions.
    """
    if isinstance(scene, str):
        if scene not in STANDARD_SIZES:
            raise ValueError(f"scene must be a Scene or one of {tuple(STANDARD_SIZES)}, "
                             f"got {scene!r}")
        scene = Scene(die=Die.standard(scene))
    spec = Spec(scene, throws, chunk, seed, draw)
    if ray is not None and (not isinstance(ray, str) or not ray):
        raise ValueError(f"ray must be None or an address ('auto', 'local', 'ray://host:port'), "
                         f"got {ray!r}")
    if workers is not None and (not isinstance(workers, int) or isinstance(workers, bool)
                                or workers < 1):
        raise ValueError(f"workers must be None or an int >= 1, got {workers!r}")
    check_int("max_retries", max_retries, 0)
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be None or a callable taking the throws done, "
                        f"got {progress!r}")
    advance = progress or (lambda n: None)
    folder = None if out is None else prepare(Path(out), spec.record(), "out")
    tallies = {} if folder is None else _saved_tallies(folder, spec)
    if tallies:
        advance(sum(t.throws for t in tallies.values()))
    todo = [i for i in range(spec.n_chunks) if i not in tallies]

    def done(index: int, outcomes: dict[str, np.ndarray]) -> None:
        if folder is not None:
            _save_chunk(folder, spec, index, outcomes)
        tallies[index] = Tally.of(spec.scene, outcomes)
        advance(spec.size(index))

    if ray is None:
        for index in todo:
            done(index, throw_chunk(spec, index))
    else:
        _run_on_ray(ray, spec, todo, done, workers, max_retries)
    return Tally.merge(tallies[i] for i in range(spec.n_chunks))


@contextlib.contextmanager
def connected(address: str) -> Iterator[types.ModuleType]:
    """Ray, connected to ``address`` for the block; a process already connected stays so."""
    try:
        import ray
    except ImportError as error:
        raise ImportError(f"ray={address!r} needs Ray: pip install 'dice_env[ray]'") from error
    started = not ray.is_initialized()
    if started:
        ray.init(address=address, **({"include_dashboard": False} if address == "local"
                                     else {}))
    try:
        yield ray
    finally:
        if started:
            ray.shutdown()


def _run_on_ray(address: str, spec: Spec, todo: list[int],
                done: Callable[[int, dict[str, np.ndarray]], None], workers: int | None,
                max_retries: int) -> None:
    """Run the chunks ``todo`` as Ray tasks, ``workers`` at a time; ``done`` each result."""
    with connected(address) as ray:
        task = ray.remote(num_cpus=1, max_retries=max_retries)(throw_chunk)
        at_once = workers or max(1, int(ray.cluster_resources().get("CPU", 1)))
        spec_ref = ray.put(spec)
        waiting, running = list(reversed(todo)), {}
        try:
            while waiting or running:
                while waiting and len(running) < at_once:
                    index = waiting.pop()
                    running[task.remote(spec_ref, index, 1)] = index
                finished, _ = ray.wait(list(running), num_returns=1)
                index = running.pop(finished[0])
                done(index, ray.get(finished[0]))
        finally:
            for ref in running:
                ray.cancel(ref, force=True)


def _chunk_path(folder: Path, index: int) -> Path:
    return folder / f"chunk_{index:06d}.npz"


def _saved_tallies(folder: Path, spec: Spec) -> dict[int, Tally]:
    """The tallies of the chunks already in ``folder``, by index; FolderError for another's."""
    tallies = {}
    for path in sorted(folder.glob("chunk_*.npz")):
        match = re.fullmatch(r"chunk_(\d+)\.npz", path.name)
        index = int(match[1]) if match else -1
        if not 0 <= index < spec.n_chunks or path != _chunk_path(folder, index):
            raise FolderError(f"{str(path)!r} is not a chunk of this run (of chunks 0 to "
                              f"{spec.n_chunks - 1}): delete it, or pass another folder")
        tallies[index] = Tally.of(spec.scene, _read_chunk(path, spec, index))
    return tallies


def _read_chunk(path: Path, spec: Spec, index: int) -> dict[str, np.ndarray]:
    """The outcomes at ``path``, checked to be chunk ``index`` of ``spec``; else FolderError."""
    saved, asked = load(path), spec.chunk_record(index)
    if "chunk" not in saved:
        raise FolderError(f"{str(path)!r} records no spec, seed or index (an older version's "
                          "chunk?): it is not known to be this run's; delete it to throw it "
                          "again, or pass another folder")
    try:
        found = json.loads(str(saved.pop("chunk")))
        differ = [key for key in asked if found[key] != asked[key]]
    except (ValueError, TypeError, KeyError) as error:
        raise FolderError(f"{str(path)!r} is corrupt (its record of the chunk is unreadable): "
                          "delete it to throw it again") from error
    if differ:
        shown = "; ".join("another spec" if k == "spec" else f"{k} {found[k]!r} there, "
                          f"{asked[k]!r} here" for k in differ)
        raise FolderError(f"{str(path)!r} is not chunk {index} of this run ({shown}): delete "
                          "it to throw it again, or pass another folder")
    wrong = _wrong_outcome(saved, spec.scene, asked["throws"])
    if wrong:
        raise FolderError(f"{str(path)!r} is corrupt ({wrong}): delete it to throw it again")
    return saved


def _wrong_outcome(saved: dict[str, np.ndarray], scene: Scene, throws: int) -> str:
    """What in a chunk's outcomes no run of ``throws`` of ``scene`` gives (``""``: nothing)."""
    if sorted(saved) != sorted(OUTCOMES) or any(saved[q].shape != (throws,) for q in OUTCOMES):
        return f"its outcomes are not {tuple(OUTCOMES)} of {throws} throws each"
    for name, dtype in OUTCOMES.items():
        if saved[name].dtype != dtype:
            return f"{name} is {saved[name].dtype}, not {np.dtype(dtype)}"
    o, n_steps = saved, scene.steps_for()
    ranges = {"face": (1, scene.die.n_faces), "steps": (0, n_steps),
              "time": (0.0, n_steps * scene.step), "impacts": (0, np.inf)}
    for name, (low, high) in ranges.items():
        inside = (o[name] >= low) & (o[name] <= high)  # False for NaN
        if not inside.all():
            return f"{name} {o[name][~inside][0].item()!r} outside [{low}, {high}]"
    if not np.array_equal(o["counted"], counted(types.SimpleNamespace(**o))):
        return "counted disagrees with decided, settled, unstable and sunk"
    return ""


def _save_chunk(folder: Path, spec: Spec, index: int, outcomes: dict[str, np.ndarray]) -> None:
    record = np.array(json.dumps(spec.chunk_record(index)))
    write_atomically(_chunk_path(folder, index),
                     lambda f: np.savez(f, chunk=record, **outcomes))

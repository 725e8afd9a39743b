"""An oracle: per observation, a global screen and cross-entropy searches under the env's noise.

For each observation (target, hand) the search simulates candidate actions under the env's own
hand noise with the batched kernel (:meth:`ThrowTask.throw`), all observations of a chunk in one
kernel call:

1. **screen**: every given start (the other throwers' actions: the hand-written thrower's always,
   a trained policy's when there is one) and ``global_candidates`` actions drawn uniformly over
   the whole action box;
2. **restarts**: the cross-entropy method runs from the best start and from the best screened
   candidates that are not starts, ``restarts`` searches side by side;
3. **final**: every start, every search's mean and the best candidates seen are re-scored on
   fresh validation noise and the best is kept.

Candidates of one round share the same noise draws (common random numbers, so they are compared
on equal terms) and every round draws fresh ones (so the search cannot fit a few draws). The
search ranks by success plus a small tie-break on how far the target turned up, and runs each
throw only until its face is decided (the same face as at rest, 2–3 times faster) where the
table allows. Because every start is a finalist, the oracle keeps another thrower's action
wherever the search finds nothing better, so on the same throws it scores at least about as well
as each of them; its success is measured on fresh throws (:func:`score`), an honest estimate of
the best success the task allows for these observations.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from agents.baselines import HandThrower
from dice_env.envs.throw_task import ThrowTask

SHAPING_TIE_BREAK = 0.1  # weight of the alignment term when ranking candidates (not in scores)


@dataclass(frozen=True)
class CEM:
    """Oracle search settings.

    ``global_candidates`` uniform actions are screened with the starts on ``noise_samples``
    draws; ``restarts`` cross-entropy searches (from the best start and the best other screened
    candidates) run ``iterations`` rounds of ``population`` candidates, the best ``elite``
    fraction refitting a diagonal Gaussian of initial standard deviation ``init_std`` (action
    units, floored at ``min_std``). The finalists (starts, search means and the ``finalists``
    best candidates seen) are re-scored on ``validation_samples`` fresh draws. ``chunk``
    observations share one kernel call.
    """

    global_candidates: int = 48
    restarts: int = 2
    iterations: int = 4
    population: int = 24
    noise_samples: int = 16
    elite: float = 0.25
    init_std: float = 0.1
    min_std: float = 0.01
    finalists: int = 4
    validation_samples: int = 64
    chunk: int = 8

    def __post_init__(self) -> None:
        for name in ("restarts", "iterations", "population", "noise_samples",
                     "validation_samples", "chunk"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)!r}")
        for name in ("global_candidates", "finalists"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        if not 0 < self.elite <= 1:
            raise ValueError(f"elite must be in (0, 1], got {self.elite!r}")

    def throws_per_observation(self, starts: int = 1) -> int:
        """Simulated throws the search spends per observation with ``starts`` starts."""
        screened = (starts + self.global_candidates) * self.noise_samples
        searched = self.restarts * self.iterations * self.population * self.noise_samples
        validated = (starts + self.restarts + self.finalists) * self.validation_samples
        return screened + searched + validated


# The oracle's budget on the named tasks (benchmarks/tasks.py, agents.learned), by dice per
# throw: its default search on that many observations for one die; for several dice, whose
# throws cost far more, a smaller search whose finalists are compared on more draws.
OBSERVATIONS = {1: 32, 2: 12}
GROUP_CEM = CEM(global_candidates=12, restarts=1, iterations=3, population=10, noise_samples=6,
                finalists=2, validation_samples=48)


def task_budget(task: ThrowTask) -> tuple[int, CEM]:
    """The observations the oracle searches on ``task`` and its settings (:data:`OBSERVATIONS`)."""
    return OBSERVATIONS[min(task.n_dice, 2)], CEM() if task.n_dice == 1 else GROUP_CEM


def search(
    task: ThrowTask,
    observations: np.ndarray,
    rng: np.random.Generator,
    cem: CEM | None = None,
    starts: dict[str, np.ndarray] | None = None,
    progress: Callable[[int], None] | None = None,
) -> np.ndarray:
    """The oracle's action for each observation; ``progress(k)`` after k more observations.

    ``starts``: other throwers' actions (n, action size) for the same observations; the
    hand-written thrower's are always added for one die (a one-die rule).
    """
    cem = CEM() if cem is None else cem
    observations = np.atleast_2d(np.asarray(observations, dtype=np.float64))
    given = {"hand-written": HandThrower(task)(observations)} if task.n_dice == 1 else {}
    given.update(starts or {})
    if not given:
        raise ValueError("starts must hold at least one thrower's actions for several dice "
                         "(the hand-written thrower is a one-die rule)")
    start_actions = np.stack([np.asarray(a, np.float64) for a in given.values()], axis=1)
    ranked = search_task(task)
    actions = np.empty((len(observations), start_actions.shape[2]))
    for first in range(0, len(observations), cem.chunk):
        part = slice(first, first + cem.chunk)
        actions[part] = _search_chunk(ranked, observations[part], start_actions[part], rng, cem)
        if progress is not None:
            progress(len(actions[part]))
    return actions


def search_task(task: ThrowTask) -> ThrowTask:
    """The task the search ranks on: the tie-break term, throws ended when their face is decided.

    The face decided is the face at rest (``until="decided"``); where the table allows no
    decision (a slope) the throws run to rest.
    """
    ranked = dataclasses.replace(task, shaping=SHAPING_TIE_BREAK)
    try:
        return dataclasses.replace(ranked, until="decided")
    except ValueError:
        return ranked


def score(
    task: ThrowTask, observations: np.ndarray, actions: np.ndarray, noise: np.ndarray
) -> np.ndarray:
    """Success (n, k) of ``actions`` (n, a) for ``observations`` under ``noise`` (n, k, d).

    Give every thrower the same ``noise`` (:func:`score_noise`) to compare them on the same
    throws.
    """
    targets, hands = task.decode(observations)
    n, k = noise.shape[:2]
    throw = task.throw(np.repeat(actions, k, axis=0), np.repeat(targets, k, axis=0),
                       np.repeat(hands, k, axis=0), noise.reshape(n * k, -1))
    return throw.info["is_success"].reshape(n, k)


def score_noise(task: ThrowTask, rng: np.random.Generator, n: int, samples: int) -> np.ndarray:
    """Fresh hand noise (n, samples, d) for :func:`score`."""
    return task.sample_noise(rng, n * samples).reshape(n, samples, -1)


def _search_chunk(
    task: ThrowTask, observations: np.ndarray, starts: np.ndarray, rng: np.random.Generator,
    cem: CEM,
) -> np.ndarray:
    n, n_starts, dim = starts.shape
    k, pop, restarts = cem.noise_samples, cem.population, cem.restarts
    # 1. Screen the starts and uniform candidates over the whole action box.
    screen = np.concatenate([starts, rng.uniform(-1.0, 1.0, (n, cem.global_candidates, dim))],
                            axis=1)
    values = _evaluate(task, observations, screen, rng, k)
    best_start = values[:, :n_starts].argmax(axis=1)
    others = np.argsort(-values[:, n_starts:], axis=1)[:, :restarts - 1] + n_starts
    picks = np.concatenate([best_start[:, None], others], axis=1)
    mean = np.take_along_axis(screen, picks[..., None], axis=1)  # (n, r, dim)
    r = mean.shape[1]
    std = np.full_like(mean, cem.init_std)
    seen_actions, seen_values = [screen], [values]
    n_elite = max(2, round(cem.elite * pop))
    # 2. Cross-entropy searches side by side, one per restart.
    for _ in range(cem.iterations):
        candidates = np.clip(mean[:, :, None] + std[:, :, None] * rng.standard_normal(
            (n, r, pop, dim)), -1.0, 1.0)
        candidates[:, :, 0] = mean  # each search's mean always competes
        values = _evaluate(task, observations, candidates.reshape(n, r * pop, dim), rng, k)
        order = np.argsort(-values.reshape(n, r, pop), axis=2)[..., :n_elite]
        elite = np.take_along_axis(candidates, order[..., None], axis=2)
        mean = elite.mean(axis=2)
        std = np.maximum(elite.std(axis=2), cem.min_std)
        seen_actions.append(candidates.reshape(n, r * pop, dim))
        seen_values.append(values)
    # 3. Finalists: every start, every search's mean and the best candidates seen.
    pool = np.concatenate(seen_actions, axis=1)
    best = np.argsort(-np.concatenate(seen_values, axis=1), axis=1)[:, :cem.finalists]
    finalists = np.concatenate(
        [starts, mean, np.take_along_axis(pool, best[..., None], axis=1)], axis=1)
    values = _evaluate(task, observations, finalists, rng, cem.validation_samples)
    return finalists[np.arange(n), values.argmax(axis=1)]


def _evaluate(
    task: ThrowTask, observations: np.ndarray, candidates: np.ndarray,
    rng: np.random.Generator, samples: int,
) -> np.ndarray:
    """Mean reward (n, c) of candidates (n, c, a), all sharing ``samples`` noise draws per obs."""
    n, c = candidates.shape[:2]
    targets, hands = task.decode(observations)
    noise = task.sample_noise(rng, n * samples).reshape(n, 1, samples, -1)
    noise = np.broadcast_to(noise, (n, c, samples, noise.shape[-1])).reshape(n * c * samples, -1)
    throw = task.throw(np.repeat(candidates.reshape(n * c, -1), samples, axis=0),
                       np.repeat(targets, c * samples, axis=0),
                       np.repeat(hands, c * samples, axis=0), noise)
    return throw.reward.reshape(n, c, samples).mean(axis=2)

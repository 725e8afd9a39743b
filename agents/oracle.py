"""An oracle: per observation, the cross-entropy method searches the throw under the env's noise.

For each observation (target, hand) the search simulates candidate actions under the env's own
hand noise with the batched kernel (:meth:`ThrowTask.throw`), all observations of a chunk in one
kernel call. Candidates of one iteration share the same noise samples (common random numbers, so
they are compared on equal terms) and every iteration draws fresh ones (so the search cannot fit
a few samples). The search starts from the hand-written thrower. At the end the mean and the best
candidates are re-scored on fresh validation noise and the best is kept; the estimate of the
oracle's success comes from yet another set of fresh samples (:func:`score`), so it is an honest
lower bound on the best success the task allows for these observations.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from agents.baselines import HandThrower, decode
from dice_env.envs.task import ACTION_DIM, ThrowTask

SHAPING_TIE_BREAK = 0.1  # weight of the alignment term when ranking candidates (not in scores)


@dataclass(frozen=True)
class CEM:
    """Cross-entropy-method settings.

    ``iterations`` rounds of ``population`` candidates, each simulated under ``noise_samples``
    hand-noise draws; the best ``elite`` fraction refits a diagonal Gaussian starting at the
    hand-written action with standard deviation ``init_std`` (in action units, floored at
    ``min_std``). The ``finalists`` (the hand-written action, the final mean and the best
    candidates seen) are re-scored on ``validation_samples`` fresh draws. ``chunk``
    observations share one kernel call.
    """

    iterations: int = 5
    population: int = 24
    noise_samples: int = 16
    elite: float = 0.25
    init_std: float = 0.1
    min_std: float = 0.01
    finalists: int = 5
    validation_samples: int = 64
    chunk: int = 8

    @property
    def throws_per_observation(self) -> int:
        """Simulated throws the search spends per observation."""
        return (self.iterations * self.population * self.noise_samples
                + self.finalists * self.validation_samples)


def search(
    task: ThrowTask,
    observations: np.ndarray,
    rng: np.random.Generator,
    cem: CEM | None = None,
    progress: Callable[[int], None] | None = None,
) -> np.ndarray:
    """The oracle's action (n, 6) for each observation (n, 15); ``progress(k)`` after k more."""
    cem = CEM() if cem is None else cem
    observations = np.asarray(observations, dtype=np.float64).reshape(-1, 15)
    actions = np.empty((len(observations), ACTION_DIM))
    for start in range(0, len(observations), cem.chunk):
        part = slice(start, start + cem.chunk)
        actions[part] = _search_chunk(task, observations[part], rng, cem)
        if progress is not None:
            progress(len(observations[part]))
    return actions


def score(
    task: ThrowTask,
    observations: np.ndarray,
    actions: np.ndarray,
    rng: np.random.Generator,
    samples: int,
) -> np.ndarray:
    """Success (n, samples) of ``actions`` for ``observations`` under fresh hand noise."""
    targets, hands = decode(observations)
    n = len(targets)
    throw = task.throw(np.repeat(actions, samples, axis=0), np.repeat(targets, samples),
                       np.repeat(hands, samples, axis=0), task.sample_noise(rng, n * samples))
    return throw.info["is_success"].reshape(n, samples)


def _search_chunk(
    task: ThrowTask, observations: np.ndarray, rng: np.random.Generator, cem: CEM
) -> np.ndarray:
    n, pop, k = len(observations), cem.population, cem.noise_samples
    ranked = dataclasses.replace(task, shaping=SHAPING_TIE_BREAK)
    hand = mean = HandThrower(task)(observations)
    std = np.full_like(mean, cem.init_std)
    n_elite = max(2, round(cem.elite * pop))
    seen_actions, seen_values = [], []
    for _ in range(cem.iterations):
        candidates = np.clip(mean[:, None] + std[:, None] * rng.standard_normal(
            (n, pop, ACTION_DIM)), -1.0, 1.0)
        candidates[:, 0] = mean  # the current mean always competes
        values = _evaluate(ranked, observations, candidates, rng, k)
        order = np.argsort(-values, axis=1)
        elite = np.take_along_axis(candidates, order[:, :n_elite, None], axis=1)
        mean = elite.mean(axis=1)
        std = np.maximum(elite.std(axis=1), cem.min_std)
        seen_actions.append(candidates)
        seen_values.append(values)
    # Finalists: the start, the final mean and the best candidates seen; fresh noise decides.
    all_actions = np.concatenate(seen_actions, axis=1)
    best = np.argsort(-np.concatenate(seen_values, axis=1), axis=1)[:, :cem.finalists - 2]
    finalists = np.concatenate(
        [hand[:, None], mean[:, None], np.take_along_axis(all_actions, best[..., None], axis=1)],
        axis=1)
    values = _evaluate(ranked, observations, finalists, rng, cem.validation_samples)
    return finalists[np.arange(n), values.argmax(axis=1)]


def _evaluate(
    task: ThrowTask, observations: np.ndarray, candidates: np.ndarray,
    rng: np.random.Generator, samples: int,
) -> np.ndarray:
    """Mean reward (n, c) of candidates (n, c, 6), all sharing ``samples`` noise draws per obs."""
    n, c = candidates.shape[:2]
    targets, hands = decode(observations)
    noise = task.sample_noise(rng, n * samples).reshape(n, 1, samples, -1)
    noise = np.broadcast_to(noise, (n, c, samples, noise.shape[-1])).reshape(n * c * samples, -1)
    throw = task.throw(np.repeat(candidates.reshape(n * c, -1), samples, axis=0),
                       np.repeat(targets, c * samples),
                       np.repeat(hands, c * samples, axis=0), noise)
    return throw.reward.reshape(n, c, samples).mean(axis=2)

"""How much control DiceThrow-v0 leaves: learnable at the defaults, chance when vigorous and fair.

Slow (about a minute on 2 cores); prints the figures whose bounds docs/environment.md states:

    .venv/bin/pytest -m slow tests/test_env_difficulty.py -s

A random-search oracle gives a thrower's best case without any learning: per observation
(target, hand) it draws ``CANDIDATES`` uniform actions, scores each on ``SAMPLES`` hand-noise
draws (shared by the candidates), keeps the best and re-scores it on ``VALIDATION`` fresh draws.
Only the re-scored success is reported, so the selection does not inflate it.
"""

import numpy as np
import pytest

from dice_env.envs.throw_task import ThrowTask, make_task

OBSERVATIONS = 12
CANDIDATES = 192
SAMPLES = 8
VALIDATION = 48
VIGOROUS_FAIR = {"release_height": 0.15, "min_speed": 1.0, "min_spin": 20.0}


def random_search_oracle(task: ThrowTask, seed: int) -> tuple[float, float]:
    """(success of uniform random actions, success of the random-search oracle's choice)."""
    rng = np.random.default_rng(seed)
    targets, hands = task.sample_hands([rng] * OBSERVATIONS)
    n, c, s = OBSERVATIONS, CANDIDATES, SAMPLES
    candidates = rng.uniform(-1.0, 1.0, (n, c, 6))
    noise = np.broadcast_to(task.sample_noise(rng, n * s).reshape(n, 1, s, -1), (n, c, s, 9))
    throw = task.throw(np.repeat(candidates.reshape(n * c, 6), s, axis=0),
                       np.repeat(targets, c * s), np.repeat(hands, c * s, axis=0),
                       noise.reshape(n * c * s, 9))
    random_success = float(throw.info["is_success"].mean())
    best = candidates[np.arange(n), throw.reward.reshape(n, c, s).mean(axis=2).argmax(axis=1)]
    check = task.throw(np.repeat(best, VALIDATION, axis=0), np.repeat(targets, VALIDATION),
                       np.repeat(hands, VALIDATION, axis=0),
                       task.sample_noise(rng, n * VALIDATION))
    return random_success, float(check.info["is_success"].mean())


@pytest.mark.slow
def test_default_is_learnable_vigorous_fair_is_chance():
    default = random_search_oracle(make_task(), seed=0)
    vigorous = random_search_oracle(make_task(**VIGOROUS_FAIR), seed=0)
    print(f"\ndefaults: random actions {default[0]:.3f}, random-search oracle {default[1]:.3f}")
    print(f"vigorous fair {VIGOROUS_FAIR}: random actions {vigorous[0]:.3f}, "
          f"random-search oracle {vigorous[1]:.3f} (chance 1/6 = 0.167)")
    assert abs(default[0] - 1 / 6) < 0.05  # random actions: chance
    assert default[1] > 0.25  # a search finds throws that work under the hand noise
    assert vigorous[1] < 0.27  # even the best of the random throws: near chance

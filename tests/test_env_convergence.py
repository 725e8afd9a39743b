"""The default task's reward is physics, not step-size noise: gentle throws converge in dt.

``pytest tests/test_env_convergence.py -s`` prints the share whose bound docs/environment.md
states.
"""

import numpy as np

from agents.baselines import HandThrower
from dice_env import Scene
from dice_env.envs.throw_task import make_task


def landed_faces(safety: float, n: int = 600) -> tuple[np.ndarray, float]:
    rng = np.random.default_rng(0)
    task = make_task(safety=safety)
    targets, hands = task.sample_hands([rng] * n)
    noise = task.sample_noise(rng, n)
    actions = HandThrower(make_task())(task.observe(targets, hands))
    throw = task.throw(actions, targets, hands, noise)
    return throw.info["face"], float(throw.info["is_success"].mean())


def test_default_throws_land_on_the_same_face_at_a_quarter_step():
    safety = Scene().safety  # the automatic step
    faces, success = landed_faces(safety=safety)
    finer, finer_success = landed_faces(safety=safety / 4)
    print(f"same face at dt and dt/4: {np.mean(faces == finer):.4f}; "
          f"success {success:.4f} vs {finer_success:.4f}")
    assert np.mean(faces == finer) >= 0.98
    assert abs(success - finer_success) < 0.03

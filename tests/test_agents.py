import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from agents.baselines import HandThrower, RandomThrower, decode
from agents.config import Config, parse_config
from agents.evaluate import summary, wilson
from agents.oracle import CEM, score, search
from dice_env.die import FACE_NORMALS
from dice_env.envs import make_task
from dice_env.rotations import random_rotations

ROOT = Path(__file__).resolve().parents[1]


def test_help_shows_field_docs(capsys):
    with pytest.raises(SystemExit):
        parse_config(["--help"])
    out = capsys.readouterr().out
    assert "Throws to train on" in out and "--resume" in out and "--no-evaluate" in out


def test_env_keywords_are_literals_not_code():
    config = parse_config(["--env", "friction=0.6", "--env", "contact_law=paper",
                           "--env", "target_face=3"])
    assert config.env_kwargs() == {"friction": 0.6, "contact_law": "paper", "target_face": 3}
    with pytest.raises(ValueError, match="KEY=VALUE"):
        Config(env=["friction"]).env_kwargs()
    with pytest.raises(ValueError, match="preset"):
        parse_config(["--preset", "nope"])


def test_hand_thrower_spins_the_target_toward_up():
    task = make_task()
    hands = random_rotations(np.random.default_rng(0), 50)
    targets = np.arange(50) % 6 + 1
    obs = task.observe(targets, hands)
    t, h = decode(obs)
    assert np.array_equal(t, targets) and np.allclose(h, hands, atol=1e-6)
    actions = HandThrower(task)(obs)
    assert actions.shape == (50, 6) and np.all(np.abs(actions) <= 1)
    normal = np.einsum("nij,nj->ni", hands, FACE_NORMALS[targets - 1])
    # d n / dt = w x n points up (toward z) for every target not already up
    assert np.all(np.cross(actions[:, 3:], normal)[:, 2] >= -1e-9)
    assert RandomThrower(0)(obs).shape == (50, 6)


def test_intervals():
    lo, hi = wilson(50, 100)
    assert lo < 0.5 < hi and hi - lo == pytest.approx(0.19, abs=0.01)
    assert wilson(0, 10)[0] == 0.0
    s = summary(np.array([[1, 0], [1, 1], [0, 0]], bool), np.array([1, 2, 1]))
    assert s["rate"] == pytest.approx(0.5) and s["observations"] == 3
    assert s["per_target"][2]["rate"] == 1.0


def test_oracle_search_runs_and_scores_fresh_noise():
    task = make_task()
    rng = np.random.default_rng(1)
    obs = task.observe(np.array([1, 6]), random_rotations(rng, 2))
    cem = CEM(iterations=1, population=4, noise_samples=2, finalists=3, validation_samples=2)
    actions = search(task, obs, rng, cem)
    assert actions.shape == (2, 6) and np.all(np.abs(actions) <= 1)
    assert score(task, obs, actions, rng, 3).shape == (2, 3)


def test_train_py_end_to_end_and_resume(tmp_path):
    tiny = ["--n-envs", "64", "--eval-freq", "128", "--eval-episodes", "64",
            "--checkpoint-freq", "128", "--eval-throws", "60", "--oracle-observations", "1",
            "--robustness-throws", "12", "--gifs", "0", "--no-progress"]
    cmd = [sys.executable, str(ROOT / "train.py"), "--total-timesteps", "512", "--runs",
           str(tmp_path), "--name", "smoke", *tiny]
    subprocess.run(cmd, check=True, cwd=ROOT, timeout=600)
    run = tmp_path / "smoke"
    for name in ("config.json", "model.zip", "report.md", "evaluation.json", "confusion.png",
                 "strategy.png", "robustness.png", "eval/evaluations.npz"):
        assert (run / name).exists(), name
    assert list((run / "tb").iterdir()) and list((run / "checkpoints").glob("ppo_*_steps.zip"))
    evaluation = json.loads((run / "evaluation.json").read_text())
    assert set(evaluation["summary"]) == {"PPO", "random", "hand-written", "oracle"}
    resumed = subprocess.run([sys.executable, str(ROOT / "train.py"), "--resume", str(run),
                              "--total-timesteps", "1024", "--no-evaluate"], check=True,
                             cwd=ROOT, timeout=600, capture_output=True, text=True)
    assert "resuming" in resumed.stdout and "(512 throws)" in resumed.stdout
    sessions = [json.loads(line) for line in (run / "training.jsonl").read_text().splitlines()]
    assert [s["throws"] for s in sessions] == [512, 1024]

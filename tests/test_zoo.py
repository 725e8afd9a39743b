"""rl-zoo3 trains and replays DiceThrow-v0 from the shipped file, as a user types it."""

import subprocess
import sys

import pytest

from agents import zoo

CONF = zoo.ZOO / "ppo.yml"


def test_zoo_file_is_the_hyperparameter_table():
    assert zoo.main(["--check"]) == 0
    assert zoo.ppo_yaml() == CONF.read_text()


def test_zoo_check_reports_a_file_changed_by_hand(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(zoo, "ZOO", tmp_path)
    (tmp_path / "ppo.yml").write_text(CONF.read_text().replace("n_epochs: 10", "n_epochs: 3"))
    assert zoo.main(["--check"]) == 1
    assert "differs" in capsys.readouterr().out


def _run(module: str, *args: str, cwd) -> str:
    done = subprocess.run([sys.executable, "-m", module, *args], cwd=cwd, capture_output=True,
                          text=True, timeout=240)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-4000:]
    return done.stdout + done.stderr


def test_rl_zoo3_train_then_enjoy(tmp_path):
    pytest.importorskip("rl_zoo3")
    common = ["--algo", "ppo", "--env", "DiceThrow-v0", "--gym-packages", "dice_env"]
    # a tiny budget: 8 envs x 4 steps per rollout, two rollouts
    _run("rl_zoo3.train", *common, "--conf-file", str(CONF), "-f", str(tmp_path / "logs"),
         "--seed", "0", "-n", "64", "--eval-freq", "-1", "--hyperparams", "n_envs:8",
         "batch_size:32", cwd=tmp_path)
    run = tmp_path / "logs" / "ppo" / "DiceThrow-v0_1"
    assert (run / "DiceThrow-v0.zip").is_file()
    out = _run("rl_zoo3.enjoy", *common, "-f", str(tmp_path / "logs"), "--exp-id", "1",
               "-n", "16", "--no-render", "--deterministic", cwd=tmp_path)
    assert "Traceback" not in out

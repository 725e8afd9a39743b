"""rl-zoo3 trains and replays the named tasks from the shipped files, as a user types it."""

import subprocess
import sys

import pytest
import yaml

from agents import zoo

ALGOS = ("ppo", "a2c", "sac", "td3")


def test_zoo_files_are_the_hyperparameter_table():
    assert zoo.main(["--check"]) == 0
    for algo in ALGOS:
        assert zoo.zoo_yaml(algo) == (zoo.ZOO / f"{algo}.yml").read_text()


def test_zoo_files_name_every_task():
    from dice_env.envs.tasks import TASKS

    for algo in ALGOS:
        entries = yaml.safe_load((zoo.ZOO / f"{algo}.yml").read_text())
        assert list(entries) == [t.id for t in TASKS]


def test_zoo_check_reports_a_file_changed_by_hand(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(zoo, "ZOO", tmp_path)
    zoo.main([])
    capsys.readouterr()
    ppo = tmp_path / "ppo.yml"
    ppo.write_text(ppo.read_text().replace("n_epochs: 10", "n_epochs: 3"))
    (tmp_path / "td3.yml").unlink()
    assert zoo.main(["--check"]) == 1
    out = capsys.readouterr().out
    assert "ppo.yml differs" in out and "td3.yml differs" in out and "sac.yml" not in out


def _run(module: str, *args: str, cwd) -> str:
    done = subprocess.run([sys.executable, "-m", module, *args], cwd=cwd, capture_output=True,
                          text=True, timeout=240)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-4000:]
    return done.stdout + done.stderr


# One task per algorithm, each with a budget of two small updates.
TRAINED = {"ppo": ("DiceThrow-v0", ["n_envs:8", "batch_size:32"]),
           "a2c": ("DiceThrowTray2d6Sum-v0", ["n_envs:4"]),
           "sac": ("DiceThrowD20-v0", ["n_envs:4", "learning_starts:16", "gradient_steps:1"]),
           "td3": ("DiceThrowHigh-v0", ["n_envs:4", "learning_starts:16", "gradient_steps:1"])}


@pytest.mark.parametrize("algo", ALGOS)
def test_rl_zoo3_train_then_enjoy(tmp_path, algo):
    pytest.importorskip("rl_zoo3")
    env_id, hyperparams = TRAINED[algo]
    common = ["--algo", algo, "--env", env_id, "--gym-packages", "dice_env"]
    _run("rl_zoo3.train", *common, "--conf-file", str(zoo.ZOO / f"{algo}.yml"), "-f",
         str(tmp_path / "logs"), "--seed", "0", "-n", "64", "--eval-freq", "-1",
         "--hyperparams", *hyperparams, cwd=tmp_path)
    run = tmp_path / "logs" / algo / f"{env_id}_1"
    assert (run / f"{env_id}.zip").is_file()
    out = _run("rl_zoo3.enjoy", *common, "-f", str(tmp_path / "logs"), "--exp-id", "1",
               "-n", "16", "--no-render", "--deterministic", cwd=tmp_path)
    assert "Traceback" not in out

"""train.py as a user runs it: options refused before any folder, Ctrl-C, resume, groups."""

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from subprocess_signals import interruptible

from agents.config import parse_config

ROOT = Path(__file__).resolve().parents[1]
TINY = ["--n-envs", "64", "--eval-freq", "128", "--eval-episodes", "64", "--checkpoint-freq",
        "128", "--eval-throws", "60", "--oracle-observations", "1", "--robustness-throws", "12",
        "--gifs", "2", "--no-progress"]
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "NUMBA_NUM_THREADS": "1"}


def train_py(*args, **kwargs):
    return subprocess.run([sys.executable, str(ROOT / "train.py"), *map(str, args)], cwd=ROOT,
                          env=ENV, capture_output=True, text=True, timeout=300, **kwargs)


@pytest.mark.parametrize(("args", "message"), [
    (["--n-envs", "0"], "argument --n-envs: must be an integer >= 1, got 0"),
    (["--seed", "-1"], "argument --seed: must be an integer in [0, 2147483647], got -1"),
    (["--num-threads", "999"], "argument --num-threads: must be an int in [1, "),
    (["--eval-episodes", "0"], "argument --eval-episodes: must be an integer >= 1"),
    (["--total-timesteps", "-5"], "argument --total-timesteps: must be an integer >= 1"),
    (["--name", "../../x"], "argument --name: must be a plain folder name"),
    (["--name", ".."], "argument --name: must be a plain folder name"),
    (["--env", "releas_height=0.03"], "argument --env: unknown keyword(s) ['releas_height']"),
    (["--env", "release_height=0.001"], "argument --env: release_height must be >"),
    (["--sweep", "hand_noise=0.02,-1"], "argument --sweep: hand_noise"),
    (["--preset", "nope"], "argument --preset: must be one of"),
])
def test_bad_options_are_refused_before_any_folder(tmp_path, capsys, args, message):
    runs = tmp_path / "runs"
    with pytest.raises(SystemExit) as exit_info:
        parse_config(["--runs", str(runs), *args], prog="train.py")
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "usage: train.py" in err and message in err and "Traceback" not in err
    assert not runs.exists() and not (tmp_path / "x").exists()


def test_an_existing_name_needs_overwrite(tmp_path, capsys):
    (tmp_path / "taken").mkdir()
    (tmp_path / "taken" / "config.json").write_text("{}")
    with pytest.raises(SystemExit):
        parse_config(["--runs", str(tmp_path), "--name", "taken"])
    assert "pass --overwrite to replace it" in capsys.readouterr().err
    assert parse_config(["--runs", str(tmp_path), "--name", "taken", "--overwrite"]).overwrite
    (tmp_path / "other").mkdir()  # not a run folder: never removed
    with pytest.raises(SystemExit):
        parse_config(["--runs", str(tmp_path), "--name", "other", "--overwrite"])
    assert "is not a run folder" in capsys.readouterr().err


def test_resume_refuses_options_it_cannot_change(tmp_path, capsys):
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "config.json").write_text("{}")
    with pytest.raises(SystemExit):
        parse_config(["--resume", str(tmp_path / "run"), "--seed", "3"])
    assert "--seed cannot be changed" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        parse_config(["--resume", str(tmp_path / "nothing")])
    assert "not a run folder" in capsys.readouterr().err


@pytest.mark.parametrize("text", ["{", "[]", '{"presett": "quick"}'])
def test_resume_refuses_a_config_that_is_not_a_run_s(tmp_path, capsys, text):
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "config.json").write_text(text)
    with pytest.raises(SystemExit) as exit_info:
        parse_config(["--resume", str(tmp_path / "run")], prog="train.py")
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "argument --resume: " in err and "config.json is not a run's config" in err
    assert "Traceback" not in err


def test_a_bad_option_exits_2_without_a_traceback(tmp_path):
    done = train_py("--runs", tmp_path / "runs", "--env", "releas_height=0.03")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "argument --env" in done.stderr and not (tmp_path / "runs").exists()


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    runs = tmp_path_factory.mktemp("runs")
    done = train_py("--total-timesteps", 512, "--runs", runs, "--name", "smoke", *TINY)
    assert done.returncode == 0, done.stderr
    return runs / "smoke"


def test_train_and_evaluate_write_the_report(trained):
    run = trained
    for name in ("config.json", "model.zip", "report.md", "evaluation.json", "learning.png",
                 "turn.png", "strategy.png", "confusion.png", "robustness.png",
                 "eval/evaluations.npz", "eval/start.json"):
        assert (run / name).exists(), name
    evaluation = json.loads((run / "evaluation.json").read_text())
    assert set(evaluation["summary"]) == {"PPO", "random", "hand-written"}
    assert set(evaluation["common"]) == {"PPO", "random", "hand-written", "oracle"}
    assert len(evaluation["gifs"]) == 2 and "failure" in evaluation["gifs"][0]
    report = (run / "report.md").read_text()
    for title in ("## Headline", "## Learning curve", "## Success by how far the target face",
                  "## Strategy", "## Robustness: success when one keyword departs"):
        assert title in report


@pytest.mark.slow
@pytest.mark.parametrize(("env_id", "views", "targets"), [
    ("DiceThrowHigh-v0", ("## Strategy", "## Release"), range(1, 7)),
    ("DiceThrowD20-v0", ("## Strategy", "## Release"), range(1, 21)),
    ("DiceThrowTray2d6Sum-v0", ("## Release",), range(2, 13)),
    ("DiceThrowCraps-v0", ("## Release", "## P(7) against the hand's noise"), (7,)),
])
def test_every_named_task_trains_and_reports_for_its_dice(tmp_path, env_id, views, targets):
    done = train_py("--env-id", env_id, "--total-timesteps", 64, "--runs", tmp_path, "--name",
                    "run", *TINY, "--n-envs", "8", "--eval-throws", "16",
                    "--robustness-throws", "4", "--gifs", "0")
    assert done.returncode == 0, done.stderr
    report = (tmp_path / "run" / "report.md").read_text()
    assert f"PPO on {env_id}" in report
    columns = {int(t) for t in re.findall(r"\| target (\d+) ", report)}
    assert columns <= set(targets) and max(columns) > (6 if len(targets) > 6 else 0)
    for title in views:
        assert title in report
    one_die = "Tray" not in env_id and "Craps" not in env_id
    assert ("## Strategy" in report) == one_die and ("## Success by how far" in report) == one_die


def test_replay_writes_a_gif(trained):
    replay = subprocess.run([sys.executable, "-m", "agents.replay", str(trained), "--throws",
                             "1"], cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=120)
    assert replay.returncode == 0, replay.stderr
    assert len(list((trained / "replay").glob("replay_s0_0_PPO_target*.gif"))) == 1


def test_resume_falls_back_past_a_corrupt_checkpoint(trained):
    run = trained
    (run / "checkpoints" / "ppo_9999_steps.zip").write_bytes(b"PK\x03\x04 truncated")
    resumed = train_py("--resume", run, "--total-timesteps", 1024, "--no-evaluate",
                       "--no-progress")
    assert resumed.returncode == 0, resumed.stderr
    assert "ppo_9999_steps.zip is unreadable" in resumed.stderr
    assert "(512 throws)" in resumed.stdout
    sessions = [json.loads(line) for line in (run / "training.jsonl").read_text().splitlines()]
    assert [s["throws"] for s in sessions] == [512, 1024]
    with np.load(run / "eval" / "evaluations.npz") as curve:  # earlier evaluations kept
        assert list(curve["timesteps"]) == [128, 256, 384, 512, 640, 768, 896, 1024]


def test_ctrl_c_saves_says_so_and_exits_130(tmp_path):
    cmd = [sys.executable, "-u", str(ROOT / "train.py"), "--total-timesteps", 10**7, "--runs",
           tmp_path, "--name", "stop", *TINY]
    proc = subprocess.Popen(list(map(str, cmd)), cwd=ROOT, env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=interruptible)
    try:
        for line in proc.stdout:  # the line printed just before training
            if line.startswith("success before PPO's first update"):
                break
        time.sleep(3)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=300)  # saving and the report: seconds on a free machine
    finally:
        proc.kill()  # never leave a training process behind a failed test
    assert proc.returncode == 130, err
    run = tmp_path / "stop"
    report = (run / "report.md").read_text()
    assert "interrupted" in report and f"--resume {run}" in report
    assert "not evaluated" in report and not (run / "evaluation.json").exists()
    assert (run / "model.zip").exists() and list((run / "checkpoints").glob("ppo_*_steps.zip"))
    assert json.loads((run / "training.jsonl").read_text().splitlines()[-1])["interrupted"]


def test_seeds_write_one_table_with_mean_and_spread(tmp_path):
    done = train_py("--total-timesteps", 128, "--runs", tmp_path, "--name", "group",
                    "--seeds", 2, *TINY, "--robustness-throws", 0, "--gifs", 0,
                    "--eval-throws", 24, "--oracle-observations", 0)
    assert done.returncode == 0, done.stderr
    report = (tmp_path / "group" / "report.md").read_text()
    assert "## PPO over 2 seeds (0–1)" in report and " ± " in report
    assert (tmp_path / "group" / "learning.png").exists()
    summary = json.loads((tmp_path / "group" / "summary.json").read_text())
    (setting,) = summary["settings"]
    assert len(setting["rates"]["PPO"]) == 2 and summary["config"]["seeds"] == 2
    for seed in (0, 1):
        assert (tmp_path / "group" / f"seed{seed}" / "report.md").exists()


def test_expert_iteration_clones_the_oracle_s_labels_into_a_run_of_its_own(trained, tmp_path):
    from agents.recipe import rows, run_entry

    cmd = [sys.executable, "-m", "agents.expert", str(trained), "--runs", str(tmp_path),
           "--name", "expert", "--observations", "3", "--steps", "4", "--iterations", "2"]
    done = subprocess.run(cmd, cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    run = tmp_path / "expert"
    for name in ("model.zip", "report.md", "evaluation.json", "expert.json",
                 "eval/evaluations.npz"):
        assert (run / name).exists(), name
    expert = json.loads((run / "expert.json").read_text())
    assert len(expert["rounds"]) == 2 and expert["simulated_throws"] > 0
    sessions = [json.loads(s) for s in (run / "training.jsonl").read_text().splitlines()]
    assert sessions[-1]["throws"] == sessions[-2]["throws"] + expert["simulated_throws"]
    (row,) = rows([run_entry(run)])
    assert row["method"] == "expert iteration" and "python -m agents.expert RUN" in row["command"]
    assert "--oracle-observations 1" in row["command"]
    again = subprocess.run(cmd, cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=60)
    assert again.returncode == 2 and "exists" in again.stderr

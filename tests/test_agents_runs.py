"""Runs of agents.benchmark, tune, learned and replay are what they say, whole, and refused by
name (exit 2, one line) when they are not: other folders, settings, smoke runs, truncated files.
"""

import io
import json
import os
import shutil
import signal
import subprocess
import sys
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from subprocess_signals import interruptible

from agents import benchmark, learned, replay, tune
from agents.config import Config
from agents.hyperparams import BUDGETS, entry

TASK, OTHER = list(BUDGETS)[:2]
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(autouse=True)
def _no_checkout_runs(tmp_path, monkeypatch):
    """Nothing a test trains lands in the checkout's runs/ folder."""
    monkeypatch.setattr(benchmark, "RUNS", tmp_path / "checkout-runs")


def bench(out, *args, tasks=(TASK,), seeds=("0",)):
    return benchmark.main(["--quick", "--out", str(out), "--tasks", *tasks, "--algos", "ppo",
                           "--seeds", *seeds, *args])


def refused(capsys, call):
    """The last line of ``call``'s usage error (exit 2, no traceback)."""
    with pytest.raises(SystemExit) as stop:
        call()
    err = capsys.readouterr().err
    assert stop.value.code == 2, err
    assert "Traceback" not in err and err.startswith("usage: ")
    line = err.strip().splitlines()[-1]
    assert " error: " in line
    return line


def after_ctrl_c(call):
    """``call``'s return value, or the word that Ctrl-C escaped it (never pytest's own stop)."""
    try:
        return call()
    except KeyboardInterrupt:
        return "KeyboardInterrupt escaped"


def result_of(out, name="ppo-0", task=TASK):
    return out / "baselines" / task / f"{name}.json"


def test_two_outs_of_the_same_name_are_two_runs_and_say_what_made_them(tmp_path):
    assert bench(tmp_path / "a" / "res") == 0
    assert bench(tmp_path / "b" / "res") == 0
    second = json.loads(result_of(tmp_path / "b" / "res").read_text())
    assert second["resumed"] == 0  # trained, not the first one's copied
    assert (second["quick"], second["budget"], second["curve_throws"], second["curve_seed"],
            second["final_throws"], second["final_seed"]) == (True, 320, 16, 1, 16, 0)
    assert second["hyperparams"] == json.loads(json.dumps(entry(TASK, "ppo")))
    assert second["curve_points"] == benchmark.CURVE_POINTS and second["commit"]


def test_results_and_checkpoints_are_renamed_into_place_whole(tmp_path, monkeypatch):
    real, renamed = os.replace, []

    def rename(source, target):
        renamed.append(Path(target).name)
        real(source, target)

    monkeypatch.setattr(os, "replace", rename)
    bench(tmp_path / "res")
    assert {"ppo-0.json", "progress.json"} <= set(renamed)
    assert any(name.startswith("checkpoint-320") for name in renamed)


def test_a_smoke_result_is_refused_by_a_real_run(tmp_path, capsys):
    out = tmp_path / "res"
    bench(out, seeds=("0", "1"))
    line = refused(capsys, lambda: benchmark.main(["--out", str(out), "--tasks", TASK, "--algos",
                                                   "ppo", "--seeds", "0", "1"]))
    assert str(result_of(out)) in line and "quick True there, False here" in line
    assert "budget 320 there" in line and "pass --fresh" in line
    assert line.endswith("(1 more refused too)")


@pytest.mark.parametrize(("key", "value", "said"), [
    ("hyperparams", {"n_envs": 64}, "other hyperparameters"),
    ("commit", "0000000", "commit '0000000' there")])
def test_a_result_of_other_settings_or_code_is_refused_then_trained_afresh(tmp_path, capsys,
                                                                           key, value, said):
    out = tmp_path / "res"
    bench(out)
    path = result_of(out)
    path.write_text(json.dumps({**json.loads(path.read_text()), key: value}))
    line = refused(capsys, lambda: bench(out))
    assert str(path) in line and said in line and "pass --fresh" in line
    assert bench(out, "--fresh") == 0
    again = json.loads(path.read_text())
    assert again[key] != value and again["resumed"] == 0


def test_smoke_variants_are_refused_by_the_real_search(tmp_path, capsys):
    out = tmp_path / "res"
    assert tune.main(["--quick", "--out", str(out), "--algos", "ppo"]) == 0
    line = refused(capsys, lambda: tune.main(["--out", str(out), "--algos", "ppo"]))
    assert "tune-ppo-0.json" in line and "quick True there, False here" in line
    assert not (out / "tuning.json").exists()


@pytest.mark.parametrize("method", ["save", "save_replay_buffer"])
def test_ctrl_c_after_one_file_of_a_checkpoint_drops_no_curve_point(tmp_path, monkeypatch,
                                                                   method):
    from stable_baselines3 import SAC

    def run():
        return benchmark.Run(TASK, "sac", 0, tmp_path / "res", 320, 8, (16, 0))

    real, saved = getattr(SAC, method), []

    def then_ctrl_c(self, path, *args, **kwargs):  # Ctrl-C just after the third point's file
        real(self, path, *args, **kwargs)
        saved.append(path)
        if len(saved) == 3:
            raise KeyboardInterrupt

    with monkeypatch.context() as patch:
        patch.setattr(SAC, method, then_ctrl_c)
        assert after_ctrl_c(lambda: benchmark.train(run(), log=lambda _: None)) \
            == "KeyboardInterrupt escaped"
    result = benchmark.train(run(), log=lambda _: None)
    assert [p["throws"] for p in result["curve"]] == [64, 128, 192, 256, 320]
    assert result["resumed"] == 1


def test_a_truncated_result_is_refused_by_name_in_runs_and_tables(tmp_path, capsys):
    out = tmp_path / "res"
    bench(out)
    path = result_of(out)
    path.write_text(path.read_text()[:40])
    line = refused(capsys, lambda: bench(out))
    assert str(path) in line and "--fresh" in line
    shutil.copy(benchmark.RESULTS / "tasks.json", out)
    assert str(path) in refused(capsys, lambda: bench(out, "--table"))
    assert bench(out, "--fresh") == 0
    assert json.loads(path.read_text())["final"]["n"] == benchmark.QUICK_THROWS


@pytest.mark.parametrize("name", ["progress.json", "model.zip"])
def test_a_truncated_checkpoint_is_refused_by_name(tmp_path, capsys, monkeypatch, name):
    out = tmp_path / "res"
    real, points = benchmark.success, []

    def ctrl_c_at_the_third_point(*args):
        points.append(1)
        if len(points) == 3:
            raise KeyboardInterrupt
        return real(*args)

    with monkeypatch.context() as patch:
        patch.setattr(benchmark, "success", ctrl_c_at_the_third_point)
        assert after_ctrl_c(lambda: bench(out)) == 130
    assert "the same command continues" in capsys.readouterr().err
    path = next(tmp_path.rglob(name))
    path.write_bytes(path.read_bytes()[:len(path.read_bytes()) // 2])
    line = refused(capsys, lambda: bench(out))
    assert name in line and "pass --fresh" in line
    assert bench(out, "--fresh") == 0
    again = json.loads(result_of(out).read_text())
    assert again["resumed"] == 0 and len(again["curve"]) == benchmark.CURVE_POINTS


@pytest.mark.slow  # two commands' start: about 30 s on a busy 2-core machine
def test_ctrl_c_in_a_command_keeps_a_run_that_the_same_command_finishes(tmp_path):
    command = [sys.executable, "-u", "-m", "agents.benchmark", "--quick", "--out",
               str(tmp_path / "res"), "--tasks", TASK, "--algos", "sac", "--seeds", "0"]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "NUMBA_NUM_THREADS": "1"}
    proc = subprocess.Popen(command, cwd=ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=interruptible)
    try:
        for line in proc.stdout:  # the first curve point: a checkpoint is being kept
            if " throws, success " in line:
                break
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130 and "Traceback" not in err, err
    assert "interrupted (Ctrl-C)" in err and "the same command continues" in err
    done = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    kept = json.loads(result_of(tmp_path / "res", "sac-0").read_text())
    assert [p["throws"] for p in kept["curve"]] == [64, 128, 192, 256, 320]


@pytest.mark.parametrize("under", ["", "sub"])
def test_an_out_that_is_a_file_is_refused_before_training(tmp_path, capsys, under):
    (tmp_path / "file").write_text("mine")
    line = refused(capsys, lambda: bench(tmp_path / "file" / under))
    assert "argument --out" in line and "a file" in line
    assert not list(tmp_path.rglob("*.zip")) and (tmp_path / "file").read_text() == "mine"


def test_a_table_needs_tasks_json(tmp_path, capsys):
    line = refused(capsys, lambda: benchmark.main(["--table", "--out", str(tmp_path / "res")]))
    assert "argument --table" in line and "tasks.json" in line


def test_a_table_refuses_other_budgets_and_short_curves(tmp_path, capsys):
    out = tmp_path / "res"
    bench(out, seeds=("0", "1"))
    shutil.copy(benchmark.RESULTS / "tasks.json", out)
    assert bench(out, "--table") == 0
    path = result_of(out, "ppo-1")
    kept = json.loads(path.read_text())
    path.write_text(json.dumps({**kept, "budget": 640}))
    line = refused(capsys, lambda: bench(out, "--table"))
    assert str(path) in line and "budget 640 there, 320 here" in line
    path.write_text(json.dumps({**kept, "curve": kept["curve"][1:]}))
    assert "curves of different points" in refused(capsys, lambda: bench(out, "--table"))


def report(task_id):
    return {"task": task_id, "algo": "ppo", "seed": 0, "learned": 0.5,
            "on_oracle_throws": {"oracle": {"rate": 1.0}, "learned": {"rate": 0.5}}}


@pytest.fixture
def two_tasks(tmp_path):
    out = tmp_path / "res"
    bench(out, tasks=(TASK, OTHER))
    return out


def test_learned_keeps_each_task_as_soon_as_it_is_analysed(two_tasks, monkeypatch):
    def analyse(task_id, out, quick):
        if task_id == OTHER:
            raise KeyboardInterrupt
        return report(task_id)

    monkeypatch.setattr(learned, "analyse", analyse)
    assert after_ctrl_c(lambda: learned.main(["--quick", "--out", str(two_tasks)])) == 130
    kept = json.loads((two_tasks / "learned.json").read_text())
    assert [r["task"] for r in kept["tasks"]] == [TASK]


def test_learned_keeps_the_rows_other_commands_wrote(two_tasks, monkeypatch):
    monkeypatch.setattr(learned, "analyse", lambda task_id, out, quick: report(task_id))
    others = {"sharpness": [{"task": OTHER}], "recipe": [{"task": TASK}]}
    (two_tasks / "learned.json").write_text(json.dumps(others))
    assert learned.main(["--quick", "--out", str(two_tasks), "--tasks", TASK]) == 0
    kept = json.loads((two_tasks / "learned.json").read_text())
    assert {key: kept[key] for key in others} == others
    assert [r["task"] for r in kept["tasks"]] == [TASK]


def test_learned_checks_every_model_and_setting_before_any_analysis(two_tasks, capsys,
                                                                    monkeypatch, tmp_path):
    analysed = []
    monkeypatch.setattr(learned, "analyse", lambda task_id, *_: analysed.append(task_id))
    line = refused(capsys, lambda: learned.main(["--out", str(two_tasks)]))
    assert "ppo-0.json" in line and "budget 320 there" in line
    shutil.rmtree(next(p for p in tmp_path.rglob("ppo-0") if p.is_dir() and OTHER in p.parts))
    line = refused(capsys, lambda: learned.main(["--quick", "--out", str(two_tasks)]))
    assert f"--tasks {OTHER} --algos ppo --seeds 0 --fresh --quick" in line
    assert not analysed and not (two_tasks / "learned.json").exists()


def test_learned_refuses_a_missing_results_folder(tmp_path, capsys):
    line = refused(capsys, lambda: learned.main(["--quick", "--out", str(tmp_path / "none")]))
    assert "argument --out" in line and "baselines/" in line


def make_run(path, model=None, config=None):
    path.mkdir()
    if config is None:
        Config().save(path / "config.json")
    else:
        (path / "config.json").write_text(config)
    if model is not None:
        (path / "model.zip").write_bytes(model)
    return path


@pytest.mark.parametrize("config", ["{", "[]", '{"presett": "quick"}'])
def test_replay_refuses_a_config_that_is_not_a_run_s(tmp_path, capsys, config):
    run = make_run(tmp_path / "run", config=config)
    line = refused(capsys, lambda: replay.main([str(run), "--thrower", "random"]))
    assert "argument run" in line and "config.json is not a run's config" in line


def _zip_of_something_else():
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("notes.txt", "not a model")
    return buffer.getvalue()


@pytest.mark.parametrize(("model", "said"), [
    (b"PK\x03\x04 truncated", "is not a readable zip archive"),
    (_zip_of_something_else(), "is not a PPO model")])
def test_replay_refuses_a_model_that_cannot_be_loaded(tmp_path, capsys, model, said):
    run = make_run(tmp_path / "run", model=model)
    line = refused(capsys, lambda: replay.main([str(run), "--throws", "1"]))
    assert "model.zip" in line and said in line and "--thrower random" in line


def test_replay_s_target_advice_names_options_that_exist(tmp_path, capsys):
    run = make_run(tmp_path / "run", config=json.dumps({"env": ["num_dice=2"]}))
    line = refused(capsys, lambda: replay.main([str(run), "--thrower", "random",
                                                "--target", "3"]))
    assert "the run throws 2 dice" in line and "train.py's --env target_sum" in line


def test_replay_s_page_puts_every_failure_first(monkeypatch):
    import dice_env.viewer.html as html
    import dice_env.viewer.throws as throws

    success = [False, True, False, False, True, False]
    recordings = [SimpleNamespace(outcome={"success": s, "target": i, "faces": [1]})
                  for i, s in enumerate(success)]
    monkeypatch.setattr(throws, "task_throws", lambda *args: recordings)
    pages = []
    monkeypatch.setattr(html, "write_html", lambda ordered, path, title: pages.append(ordered))
    task = SimpleNamespace(dice=[SimpleNamespace(name="d6")], scene=SimpleNamespace(walls=[]))
    batch = SimpleNamespace(targets=None, hands=None, noise=None)
    replay.write_page(task, batch, np.zeros((6, 6)), "random", None)
    assert [rec.outcome["target"] for rec in pages[0]] == [0, 2, 3, 5, 1, 4]

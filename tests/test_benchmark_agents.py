"""python -m agents.benchmark and agents.learned: runs, resuming, the summary, the analysis."""

import json
import shutil

import pytest

from agents import benchmark, learned
from agents.hyperparams import BUDGETS, HYPERPARAMS, algorithm_kwargs, entry
from agents.kept import RunError
from dice_env.envs.tasks import TASKS

TASK = "DiceThrow-v0"


def _run(tmp_path, algo, budget=320):  # five env steps of 64 throws
    return benchmark.Run(TASK, algo, 0, tmp_path / "results", budget, 8, (16, 0))


def test_every_task_has_a_budget_and_every_algorithm_an_entry():
    assert list(BUDGETS) == list(HYPERPARAMS) == [t.id for t in TASKS]
    for env_id, algos in HYPERPARAMS.items():
        assert tuple(algos) == benchmark.ALGOS
        for algo in algos:
            assert entry(env_id, algo)["n_timesteps"] == BUDGETS[env_id]
    noise = algorithm_kwargs(entry(TASK, "td3"), 6)["action_noise"]
    assert noise._sigma.shape == (6,)
    with pytest.raises(ValueError, match="action_dim"):
        algorithm_kwargs(entry(TASK, "td3"))
    with pytest.raises(ValueError, match="algo must be one of"):
        entry(TASK, "dqn")
    with pytest.raises(ValueError, match="env_id must be one of"):
        entry("CartPole-v1", "sac")
    with pytest.raises(ValueError, match="preset must be one of"):
        entry(TASK, "sac", "quick")


@pytest.mark.parametrize("algo", ["ppo", "sac"])
def test_a_run_evaluates_at_each_curve_point_and_on_the_final_throws(tmp_path, algo):
    result = benchmark.train(_run(tmp_path, algo), log=lambda _: None)
    curve = result["curve"]
    assert len(curve) == benchmark.CURVE_POINTS
    assert [p["throws"] for p in curve] == sorted(p["throws"] for p in curve)
    assert [p["throws"] for p in curve] == [64, 128, 192, 256, 320]
    assert result["throws"] >= 320
    assert all(p["n"] == 8 and 0 <= p["rate"] <= 1 for p in curve)
    assert result["final"]["n"] == 16 and result["resumed"] == 0
    assert curve[-1]["train_seconds"] == result["train_seconds"] > 0


def test_an_interrupted_run_continues_from_its_last_checkpoint(tmp_path):
    seen = []

    def stop_after_two(line):
        seen.append(line)
        if len(seen) == 2:
            raise KeyboardInterrupt

    run = _run(tmp_path, "sac")
    with pytest.raises(KeyboardInterrupt):
        benchmark.train(run, log=stop_after_two)
    kept = json.loads((run.work / "progress.json").read_text())
    assert len(kept["curve"]) == 2
    result = benchmark.train(_run(tmp_path, "sac"), log=lambda _: None)
    assert result["resumed"] == 1
    assert result["curve"][:2] == kept["curve"]
    assert len(result["curve"]) == benchmark.CURVE_POINTS
    assert result["throws"] >= 320


def test_the_command_keeps_one_json_per_run_and_skips_kept_ones(tmp_path, capsys):
    out = tmp_path / "results"
    args = ["--quick", "--out", str(out), "--tasks", TASK, "--algos", "td3", "--seeds", "0"]
    assert benchmark.main(args) == 0
    kept = out / "baselines" / TASK / "td3-0.json"
    first = kept.read_text()
    assert json.loads(first)["algo"] == "td3"
    assert benchmark.main(args) == 0
    assert kept.read_text() == first
    assert "final" in capsys.readouterr().out


def test_quick_runs_must_not_replace_the_kept_results():
    with pytest.raises(SystemExit) as stop:
        benchmark.main(["--quick"])
    assert stop.value.code == 2


def test_the_summary_is_made_from_the_kept_runs_and_tasks_json(tmp_path):
    out = tmp_path / "results"
    folder = out / "baselines" / TASK
    folder.mkdir(parents=True)
    shutil.copy(benchmark.RESULTS / "tasks.json", out)
    for seed, rate in enumerate((0.5, 0.7)):
        curve = [{"throws": 10 * (i + 1), "train_seconds": float(i + 1), "rate": rate}
                 for i in range(benchmark.CURVE_POINTS)]
        identity = benchmark.benchmark_run(TASK, "sac", seed, out, False).identity
        (folder / f"sac-{seed}.json").write_text(json.dumps(
            {**identity, "curve": curve, "final": {"rate": rate, "ci": [0.0, 1.0], "n": 16},
             "train_seconds": 5.0}))
    summary = benchmark.table(out)
    row = next(r for r in summary["rows"] if r["task"] == TASK)
    sac = row["learned"]["sac"]
    assert sac["mean"] == pytest.approx(0.6) and sac["min"] == 0.5 and sac["max"] == 0.7
    assert sac["sd"] == pytest.approx(0.1414, abs=1e-3) and sac["seeds"] == [0, 1]
    assert sac["train_seconds"] == 10.0
    assert set(row["fixed"]) >= {"random", "oracle"} and "ppo" not in row["learned"]
    assert sac["curve"][0] == [10.0, 1.0, pytest.approx(0.6)]


def test_learned_analyses_the_best_run_against_the_oracle(tmp_path):
    out = tmp_path / "results"
    benchmark.main(["--quick", "--out", str(out), "--tasks", TASK, "--algos", "ppo",
                    "--seeds", "0", "1"])
    assert learned.main(["--quick", "--out", str(out)]) == 0
    report = json.loads((out / "learned.json").read_text())["tasks"][0]
    assert report["task"] == TASK and report["algo"] == "ppo"
    finals = [json.loads((out / "baselines" / TASK / f"ppo-{s}.json").read_text())["final"]["rate"]
              for s in (0, 1)]
    assert report["seed"] == finals.index(max(finals))
    assert set(report["on_oracle_throws"]) >= {"learned", "oracle", "random", "hand-written"}
    assert set(report["strategy"]) == {"learned", "oracle"}
    assert set(report["release"]["oracle"]) == {"speed", "vz", "horizontal", "spin"}
    assert sum(report["void_reasons"].values()) == learned.QUICK["throws"]


def test_learned_names_the_command_that_rebuilds_a_missing_model(tmp_path):
    run = {"task": TASK, "algo": "sac", "seed": 2}
    with pytest.raises(RunError, match="--tasks DiceThrow-v0 --algos sac --seeds 2"):
        learned.model_path(run, tmp_path / "results")


def test_the_kept_runs_cover_every_task_algorithm_and_seed_with_todays_settings():
    for task_id, budget in BUDGETS.items():
        for algo in benchmark.ALGOS:
            params = json.loads(json.dumps(entry(task_id, algo)))
            for seed in benchmark.SEEDS:
                path = benchmark.RESULTS / "baselines" / task_id / f"{algo}-{seed}.json"
                run = json.loads(path.read_text())
                assert (run["budget"], run["hyperparams"]) == (budget, params), path
                assert run["throws"] >= budget and len(run["curve"]) == benchmark.CURVE_POINTS
                assert run["final"]["n"] == benchmark.FINAL_THROWS
    summary = json.loads((benchmark.RESULTS / "baselines.json").read_text())
    today = json.loads(json.dumps(benchmark.table(benchmark.RESULTS)))
    assert {**summary, "commit": None} == {**today, "commit": None}

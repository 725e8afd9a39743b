import numpy as np
import pytest

import agents.oracle as oracle_module
from agents.baselines import HandThrower, RandomThrower, decode, n_faces
from agents.config import Config, OptionError, parse_config
from agents.evaluate import clustered, paired_difference, summary, turn_class
from agents.oracle import CEM, score, score_noise, search
from agents.replay import pick_throws
from dice_env.envs import make_task
from dice_env.intervals import wilson_bounds as wilson
from dice_env.model.rotations import random_rotations


def test_help_shows_field_docs(capsys):
    with pytest.raises(SystemExit):
        parse_config(["--help"])
    out = capsys.readouterr().out
    assert "Throws to train on" in out and "--resume" in out and "--no-evaluate" in out
    assert "--sweep" in out and "--seeds" in out and "--overwrite" in out


def test_env_keywords_are_literals_not_code(tmp_path):
    config = parse_config(["--env", "friction=0.6", "--env", "until=decided",
                           "--env", "target_face=3", "--runs", str(tmp_path)])
    assert config.env_kwargs() == {"friction": 0.6, "until": "decided", "target_face": 3}
    with pytest.raises(ValueError, match="KEY=VALUE"):
        Config(env=["friction"]).env_kwargs()


def test_train_takes_every_named_task_by_id_and_refuses_an_unknown_one(tmp_path, capsys):
    from agents.episodes import make_eval_task
    from agents.hyperparams import HYPERPARAMS
    from dice_env.envs.tasks import TASKS

    for named in TASKS:
        config = parse_config(["--env-id", named.id, "--runs", str(tmp_path)])
        assert config.hyperparams() == HYPERPARAMS[named.id]["ppo"]["quick"]
        task, episode = make_eval_task(config)  # the id's keywords, as gym.make(id) has them
        assert task.n_dice == named.keywords.get("num_dice", 1)
        assert task.scene.die.n_faces == (20 if named.keywords.get("die") == "d20" else 6)
        assert episode == {k: v for k, v in named.keywords.items() if k == "target_sum"}
    d20 = parse_config(["--env-id", "DiceThrowD20-v0", "--env", "release_height=0.03",
                        "--runs", str(tmp_path)])
    assert make_eval_task(d20)[0].release_height == 0.03  # --env overrides the id's keywords
    with pytest.raises(SystemExit) as exit_info:
        parse_config(["--env-id", "DiceThrowD8-v0", "--runs", str(tmp_path)], prog="train.py")
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert f"argument --env-id: must be one of {sorted(t.id for t in TASKS)}" in err
    with pytest.raises(SystemExit):  # the craps preset imitates the set throw: dice set
        parse_config(["--env-id", "DiceThrowCraps-v0", "--env", "set_dice=False",
                      "--runs", str(tmp_path)])
    assert "has none" in capsys.readouterr().err


def test_sweep_and_seeds_expand_into_member_runs():
    config = Config(name="g", runs="r", seeds=2, seed=5,
                    sweep=["release_height=0.015,0.03", "hand_noise=0.02,0.05"])
    assert config.sweep_grid()[1] == {"release_height": 0.015, "hand_noise": 0.05}
    members = config.members()
    assert len(members) == 8 and [m.seed for m in members[:2]] == [5, 6]
    assert members[3].env == ["release_height=0.015", "hand_noise=0.05"]
    assert members[3].runs == "r/g"
    assert members[3].name == "release_height-0.015_hand_noise-0.05_seed6"
    with pytest.raises(OptionError, match="also given by --env"):
        Config(env=["hand_noise=0.1"], sweep=["hand_noise=0.02"]).sweep_grid()


def test_hand_thrower_spins_the_target_toward_up():
    task = make_task()
    hands = random_rotations(np.random.default_rng(0), 50)
    targets = np.arange(50) % 6 + 1
    obs = task.observe(targets, hands)
    t, h = decode(obs)
    assert np.array_equal(t, targets) and np.allclose(h, hands, atol=1e-6)
    actions = HandThrower(task)(obs)
    assert actions.shape == (50, 6) and np.all(np.abs(actions) <= 1)
    normal = np.einsum("nij,nj->ni", hands, task.scene.die.face_normals[targets - 1])
    # d n / dt = w x n points up (toward z) for every target not already up
    assert np.all(np.cross(actions[:, 3:], normal)[:, 2] >= -1e-9)
    assert RandomThrower(0)(obs).shape == (50, 6)


def test_agents_size_themselves_from_the_observation():
    obs = np.zeros((2, 8 + 9))  # an eight-faced die's one-hot before the orientation
    obs[0, 7] = obs[1, 2] = 1.0
    obs[:, 8:] = np.eye(3).ravel()
    targets, hands = decode(obs)
    assert list(targets) == [8, 3] and np.allclose(hands, np.eye(3))
    assert n_faces(15) == 6 and RandomThrower(0, action_size=4)(obs).shape == (2, 4)
    with pytest.raises(ValueError, match="observation size"):
        n_faces(9)


def test_intervals():
    lo, hi = wilson(50, 100)
    assert lo < 0.5 < hi and hi - lo == pytest.approx(0.19, abs=0.01)
    assert wilson(0, 10)[0] == 0.0
    s = summary(np.array([[1, 0], [1, 1], [0, 0]], bool), np.array([1, 2, 1]), 6)
    assert s["rate"] == pytest.approx(0.5) and s["observations"] == 3
    assert s["per_target"][2]["rate"] == 1.0


def test_oracle_interval_does_not_collapse_when_every_throw_succeeds():
    lo, hi = clustered(np.ones((64, 16), bool))
    assert hi == 1.0 and 0.99 < lo < 1.0  # the old interval was [1.000, 1.000]
    # Observations that differ widen it beyond the pooled throws' Wilson interval.
    mixed = np.repeat(np.array([[1], [0]] * 32, bool), 16, axis=1)
    assert clustered(mixed)[1] - clustered(mixed)[0] > 2 * np.diff(wilson(512, 1024))[0]
    assert clustered(np.ones((1, 16), bool))[0] < 0.5  # one observation: its throws count once


def test_paired_difference_and_turn_classes():
    d = paired_difference(np.array([1, 1, 0, 1]), np.array([1, 0, 0, 1]))
    assert d["diff"] == pytest.approx(0.25) and not d["same"]
    assert paired_difference(np.ones(5), np.ones(5))["same"]
    assert list(turn_class(np.radians([10.0, 90.0, 170.0]))) == [0, 1, 2]


def test_gifs_show_failures_first():
    success = np.array([True, False, True, True, False, True])
    assert pick_throws(success, 4) == [1, 4, 0, 2]
    assert pick_throws(success, 1) == [1]
    assert pick_throws(np.ones(3, bool), 2) == [0, 1]


def test_oracle_keeps_a_start_that_nothing_beats(monkeypatch):
    # The ranking is faked (no simulation): closeness to one hidden best action.
    best = np.array([0.3, -0.2, 0.1, 0.5, -0.4, 0.2])

    def fake(task, observations, candidates, rng, samples):
        return -np.linalg.norm(candidates - best, axis=2)

    monkeypatch.setattr(oracle_module, "_evaluate", fake)
    task = make_task()
    rng = np.random.default_rng(0)
    obs = task.observe(np.array([1, 4, 6]), random_rotations(rng, 3))
    cem = CEM(global_candidates=8, restarts=2, iterations=2, population=6, finalists=2)
    actions = search(task, obs, rng, cem, starts={"PPO": np.tile(best, (3, 1))})
    assert np.array_equal(actions, np.tile(best, (3, 1)))
    # Without that start the search still improves on the hand-written thrower.
    found = search(task, obs, rng, cem)
    hand = HandThrower(task)(obs)
    assert np.all(np.linalg.norm(found - best, axis=1) <= np.linalg.norm(hand - best, axis=1))


def test_oracle_search_runs_and_scores_the_same_throws():
    task = make_task()
    rng = np.random.default_rng(1)
    obs = task.observe(np.array([1, 6]), random_rotations(rng, 2))
    cem = CEM(global_candidates=2, restarts=1, iterations=1, population=4, noise_samples=2,
              finalists=1, validation_samples=2)
    assert cem.throws_per_observation(2) == 4 * 2 + 4 * 2 + 4 * 2
    actions = search(task, obs, rng, cem, starts={"random": RandomThrower(0)(obs)})
    assert actions.shape == (2, 6) and np.all(np.abs(actions) <= 1)
    noise = score_noise(task, rng, 2, 3)
    first = score(task, obs, actions, noise)
    assert first.shape == (2, 3) and np.array_equal(first, score(task, obs, actions, noise))


def test_the_views_size_themselves_to_the_dice(tmp_path):
    from agents import plots
    from agents.baselines import task_rule
    from agents.evaluate import fair_totals, target_values

    two = make_task(num_dice=2, target="sum")
    assert np.isclose(fair_totals(two).sum(), 1.0) and np.isclose(fair_totals(two)[7 - 2], 1 / 6)
    assert target_values(two) == list(range(2, 13)) and task_rule(two)[0] == "hand-written"
    assert task_rule(make_task(num_dice=2, target="faces")) is None
    assert target_values(make_task(die="d20")) == list(range(1, 21))
    assert task_rule(make_task(num_dice=2, set_dice=True, target="avoid_sum"))[0] == "set"
    path = plots.confusion(tmp_path / "totals.png", np.array([2, 7, 7]),
                           {"PPO": np.array([2, 7, 8])}, list(two.totals), "total")
    assert path.exists()


def test_the_recipe_rows_give_each_task_s_seeds_mean_and_spread(tmp_path):
    import json

    from agents.kept import RunError
    from agents.recipe import main, rows, run_entry

    def run(seed, ppo, oracle, common=True):
        folder = tmp_path / f"d20_s{seed}"
        folder.mkdir()
        Config(env_id="DiceThrowD20-v0", seed=seed, name=folder.name).save(folder / "config.json")
        (folder / "training.jsonl").write_text(json.dumps(
            {"throws": 151552, "seconds": 100.0, "cpu_seconds": 150.0}) + "\n")
        score = {"rate": ppo, "ci": [ppo - 0.05, ppo + 0.05], "n": 1000}
        (folder / "evaluation.json").write_text(json.dumps({
            "summary": {"PPO": score}, "oracle_observations": 64,
            "common": {"PPO": score, "oracle": {**score, "rate": oracle}} if common else {},
            "differences": {"oracle": {"diff": ppo - oracle, "ci": [-0.1, 0.0]}}}))
        return folder

    runs = [run(0, 0.45, 0.5), run(1, 0.55, 0.5)]
    (row,) = rows([run_entry(r) for r in runs])
    assert row["seeds"] == [0, 1] and row["throws"] == 151552 and row["cpu_seconds"] == 300.0
    assert np.isclose(row["ratio"]["mean"], 1.0) and np.isclose(row["ratio"]["sd"], 0.1 * 2**0.5)
    assert row["command"] == "python train.py --env-id DiceThrowD20-v0 --preset quick --seed S"
    with pytest.raises(RunError, match="without the oracle"):
        run_entry(run(2, 0.5, 0.5, common=False))
    out = tmp_path / "learned.json"
    out.write_text(json.dumps({"tasks": ["kept"]}))
    kept_row = {**row, "task": "DiceThrowHigh-v0"}
    out.write_text(json.dumps({"tasks": ["kept"], "recipe": [kept_row, {**row, "seeds": [9]}]}))
    assert main([*map(str, runs), "--out", str(out)]) == 0
    written = json.loads(out.read_text())
    assert written["tasks"] == ["kept"]
    # The same task, preset and budget replaced; another task's row kept, in the tasks' order.
    assert [(r["task"], r["seeds"]) for r in written["recipe"]] == [
        ("DiceThrowHigh-v0", [0, 1]), ("DiceThrowD20-v0", [0, 1])]
    config = Config.load(runs[0] / "config.json")
    config.oracle_observations = 12
    config.save(runs[0] / "config.json")
    assert rows([run_entry(runs[0])])[0]["command"].endswith("--seed S --oracle-observations 12")


def test_sharpness_scores_the_oracle_s_action_as_the_hand_turns(monkeypatch, tmp_path):
    import json

    import agents.sharpness as sharp

    tiny = CEM(global_candidates=2, restarts=1, iterations=1, population=2, noise_samples=1,
               finalists=1, validation_samples=2)
    monkeypatch.setattr(sharp, "search", lambda task, obs, rng: search(task, obs, rng, tiny))
    monkeypatch.setattr(sharp, "SAMPLES", 2)
    out = tmp_path / "learned.json"
    out.write_text(json.dumps({"tasks": ["kept"]}))
    assert sharp.main(["--tasks", "DiceThrow-v0", "--observations", "2", "--out", str(out)]) == 0
    kept = json.loads(out.read_text())
    (row,) = kept["sharpness"]
    assert kept["tasks"] == ["kept"] and row["task"] == "DiceThrow-v0"
    assert [t["degrees"] for t in row["turned"]] == list(sharp.ANGLES)
    assert [m["step"] for m in row["moved"]] == list(sharp.STEPS)
    assert all(0 <= r["ci"][0] <= r["rate"] <= r["ci"][1] <= 1
               for r in row["turned"] + row["moved"])


def test_the_total_thrower_spins_a_pair_that_makes_the_total_up():
    from agents.baselines import TotalThrower, spin_up

    task = make_task(num_dice=2, target="sum")
    identity = np.tile(np.eye(3), (1, 2, 1, 1))  # both dice as placed: faces read alike
    for total, face in ((12, 6), (2, 1)):  # the only pairs: (6, 6) and (1, 1)
        obs = task.observe(np.array([total]), identity)
        assert np.allclose(TotalThrower(task)(obs),
                           spin_up(task, task.scene.die.reading[face - 1][None]))
    actions = TotalThrower(task)(task.observe(np.arange(2, 13), np.tile(identity, (11, 1, 1, 1))))
    assert actions.shape == (11, 6) and np.all(np.abs(actions) <= 1)
    with pytest.raises(ValueError, match="two dice thrown from one hand for a total"):
        TotalThrower(make_task())


def test_pair_normal_hands_the_policy_the_direction_the_tray_s_rule_spins_up():
    import gymnasium as gym
    import torch

    from agents.baselines import TotalThrower, spin_up
    from agents.episodes import Batch
    from agents.policy import PairNormal

    task = make_task(num_dice=2, target="sum")
    batch = Batch.sample(task, 64, np.random.default_rng(0))
    features = PairNormal(gym.spaces.Box(-1, 1, (task.obs_dim,)))(
        torch.as_tensor(batch.observations)).numpy()
    assert np.allclose(features[:, :-3], batch.observations)
    assert np.allclose(spin_up(task, features[:, -3:].astype(np.float64)),
                       TotalThrower(task)(batch.observations), atol=1e-5)
    with pytest.raises(ValueError, match="not a total of two dice"):
        PairNormal(gym.spaces.Box(-1, 1, (15,)))

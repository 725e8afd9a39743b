"""agents.replay on several dice: the hand-written rule refused, actions of the env's size."""

import pytest

from agents.baselines import HandThrower
from agents.config import Config
from agents.replay import main
from dice_env.envs.throw_task import make_task
from dice_env.viewer import load

RUNS = {"one die": [], "2d6": ["num_dice=2"], "2d6 sum 5": ["num_dice=2", "target_sum=5"],
        "set_dice": ["num_dice=2", "set_dice=True"]}


def make_run(path, name):
    path.mkdir()
    Config(preset="scratch", env=RUNS[name]).save(path / "config.json")
    return path


@pytest.mark.parametrize("name", ["2d6", "2d6 sum 5", "set_dice"])
def test_hand_written_is_refused_for_several_dice(tmp_path, capsys, name):
    run = make_run(tmp_path / "run", name)
    with pytest.raises(SystemExit) as exit_info:
        main([str(run), "--thrower", "hand-written", "--throws", "1"])
    assert exit_info.value.code == 2
    assert "--thrower: hand-written is a one-die rule; the run throws 2 dice" in \
        capsys.readouterr().err
    assert not (run / "replay").exists()


def test_hand_thrower_refuses_a_task_of_several_dice():
    with pytest.raises(ValueError, match="one-die rule; this task throws 3 dice"):
        HandThrower(make_task(num_dice=3))


@pytest.mark.parametrize(("name", "thrower"), [("set_dice", "random"),
                                               ("one die", "hand-written")])
def test_replay_throws_with_the_env_s_actions(tmp_path, capsys, name, thrower):
    run = make_run(tmp_path / "run", name)
    main([str(run), "--thrower", thrower, "--throws", "1", "--out", str(tmp_path / "gifs")])
    gifs = list((tmp_path / "gifs").glob(f"replay_s0_0_{thrower}_*.gif"))
    assert len(gifs) == 1 and "throw 0: target" in capsys.readouterr().out


@pytest.mark.parametrize(("name", "message"), [
    ("one die", "--target: must be a face of the run's die, in [1, 6], got 99"),
    ("2d6", "--target: fixes one die's face; the run throws 2 dice")])
def test_a_target_face_not_on_the_die_is_a_usage_error(tmp_path, capsys, name, message):
    run = make_run(tmp_path / "run", name)
    with pytest.raises(SystemExit) as exit_info:
        main([str(run), "--thrower", "random", "--throws", "1", "--target", "99"])
    assert exit_info.value.code == 2 and message in capsys.readouterr().err


def test_replay_writes_one_page_of_the_throws_failures_first(tmp_path, capsys):
    run = make_run(tmp_path / "run", "2d6")
    main([str(run), "--thrower", "random", "--throws", "3", "--html"])
    recordings = load(run / "replay" / "throws.html")
    success = [rec.outcome["success"] for rec in recordings]
    assert len(recordings) == 3 and (not success[0] or all(success))
    assert all(rec.n_dice == 2 for rec in recordings)
    assert "page: " in capsys.readouterr().out and not list((run / "replay").glob("*.gif"))

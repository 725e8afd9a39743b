import dataclasses
import json
import time

import numpy as np
import pytest

from dice_env import Die, Scene, State, simulate
from dice_env.envs.throw_task import make_task
from dice_env.model.rotations import matrix_to_quaternion, quaternion_to_matrix, random_rotations
from dice_env.model.scene import FrictionLaw, Ground
from dice_env.model.surroundings import walls
from dice_env.simulation.codec import from_data, to_data
from dice_env.simulation.group import DieContact, GroupState
from dice_env.viewer import Recording, ReplayError, files, load, record, replay, save
from dice_env.viewer.files import RecordingError
from dice_env.viewer.throws import random_throws


def _release(scene, x=0.0, y=0.0, spin=(10.0, 5.0, 3.0)):
    return State.release(scene, np.array([x, y, 0.05]), np.array([0.5, 0.0, 0.0]),
                         np.array(spin))


@pytest.mark.parametrize("scene", [
    Scene(),
    Scene(die=Die.standard("d20"), walls=walls("tray"), ground=Ground.tilted(3.0)),
    Scene(die=Die.standard("d6", pips="casino19"), friction_law=FrictionLaw.REGULARIZED),
    Scene(die=Die().load(3), dt=1e-5, t_max=2.0),
    Scene(die=Die.cuboid((0.02, 0.016, 0.012))),
])
def test_scenes_come_back_from_json_exactly(scene):
    again = from_data(json.loads(json.dumps(to_data(scene))))
    assert again == scene
    assert again.step == scene.step
    contact = DieContact(stiffness=1e5, friction_law="regularized")
    assert from_data(json.loads(json.dumps(to_data(contact)))) == contact


def test_codec_refuses_what_it_does_not_know():
    with pytest.raises(TypeError, match="value must be one of"):
        to_data(object())
    with pytest.raises(ValueError, match="type must be one of"):
        from_data({"type": "Plane", "normal": [0, 0, 1]})
    data = to_data(Ground())
    data["hardness"] = 1.0
    with pytest.raises(ValueError, match="must hold the fields"):
        from_data(data)
    data = to_data(Scene())
    data["die"]["mass"] = -1.0
    with pytest.raises(ValueError, match="mass"):
        from_data(data)


def test_quaternions_invert_the_rotation_matrices():
    rot = random_rotations(np.random.default_rng(0), 2000)
    rot[0] = np.diag([1.0, -1.0, -1.0])  # half turns, where w = 0
    rot[1] = np.diag([-1.0, -1.0, 1.0])
    quat = matrix_to_quaternion(rot)
    assert np.allclose(np.linalg.norm(quat, axis=-1), 1.0, atol=1e-15)
    assert np.all(quat[:, 0] >= 0)
    assert np.abs(quaternion_to_matrix(quat) - rot).max() < 1e-14


def test_a_recording_follows_the_unrecorded_throw_and_replays():
    scene = Scene()
    state = _release(scene)
    plain = simulate(scene, state)
    rec, = record(scene, scene.die, state)
    assert rec.outcome["faces"] == plain.face.tolist()
    assert rec.position.shape == (len(rec.t), 1, 3) and rec.t[0] == 0.0
    assert np.array_equal(rec.position[0, 0], state.position[0])
    assert np.allclose(rec.position[-1, 0], plain.final.position[0], atol=1e-12)
    assert rec.t[-1] == pytest.approx(rec.outcome["time"], abs=1 / rec.fps)
    again, = replay(rec)
    assert again.outcome == rec.outcome
    assert np.array_equal(again.position, rec.position)


def test_several_dice_are_recorded_saved_and_replayed(tmp_path):
    scene = Scene(walls=walls("tray"))
    state = GroupState.of([_release(scene), _release(scene, y=0.03, spin=(-10.0, 5.0, 3.0))])
    rec, = record(scene, (Die.standard("d8"), Die()), state, fps=30.0, titles=["two"])
    assert rec.n_dice == 2 and rec.position.shape[1:] == (2, 3)
    assert rec.title == "two" and rec.outcome["void"] in ("", "leaning")
    path = save(rec, tmp_path / "throw.json")
    back, = load(path)
    assert back.scene == scene and back.dice == rec.dice and back.contact == rec.contact
    assert np.array_equal(back.release.position, rec.release.position)
    assert np.allclose(back.orientation, rec.orientation, atol=1e-9)  # R drifts ~1e-13
    assert replay(path)[0].outcome["faces"] == rec.outcome["faces"]


def test_a_file_from_before_until_replays_with_its_run():
    rec, = record(Scene(), Die(), _release(Scene()), until="decided")
    data = rec.to_data()
    assert data["run"] == {"t_max": None, "until": "decided"}
    for old, until in (((True, False), "decided"), ((False, True), "early_rest"),
                       ((False, False), "rest")):
        data["run"] = {"t_max": None, "stop_when_decided": old[0], "early_rest": old[1]}
        assert Recording.from_data(data).run == {"t_max": None, "until": until}
    assert replay(Recording.from_data(data))[0].run["until"] == "rest"


def test_a_replay_that_lands_elsewhere_is_refused(tmp_path):
    rec, = record(Scene(), Die(), _release(Scene()))
    data = rec.to_data()
    data["outcome"]["faces"] = [7 - data["outcome"]["faces"][0]]
    path = tmp_path / "edited.json"
    path.write_text(json.dumps([data]))
    with pytest.raises(ReplayError, match="throw 0: faces"):
        replay(path)


def test_task_throws_keep_the_task_s_outcome():
    task = make_task(die="d20", walls="tray", min_speed=0.9)
    recs = random_throws(task, 3, seed=1)
    assert len(recs) == 3
    for rec in recs:
        assert rec.scene == task.scene and rec.dice == (task.scene.die,)
        assert rec.outcome["void"] in ("", "foul") and "target" not in rec.outcome  # aimed at none
    assert any(r.outcome["void"] == "foul" for r in recs)  # a release slower than 0.9 m/s


def test_bad_arguments_name_the_parameter(tmp_path):
    scene = Scene()
    with pytest.raises(ValueError, match="fps"):
        record(scene, scene.die, _release(scene), fps=0.0)
    with pytest.raises(TypeError, match="state must be a State"):
        record(scene, (Die(), Die()), _release(scene))
    with pytest.raises(ValueError, match="titles and voids"):
        record(scene, scene.die, _release(scene), titles=["a", "b"])
    with pytest.raises(ValueError, match="early_rest"):
        record(scene, (Die(), Die()), GroupState.of([_release(scene), _release(scene, y=0.03)]),
               until="early_rest")
    with pytest.raises(ValueError, match="path must end in"):
        load(tmp_path / "throw.txt")
    with pytest.raises(ValueError, match="data must be a recording"):
        Recording.from_data({"format": "other"})
    with pytest.raises(ValueError, match="count"):
        random_throws(make_task(), 0, seed=0)


def test_a_frame_rate_below_one_frame_by_t_max_is_refused_by_name():
    scene = Scene()
    for fps in (0.1, 1e-3, 5e-324, 1001.0, float("nan")):
        with pytest.raises(ValueError, match=r"fps must be in \[1, 1000\]"):
            record(scene, scene.die, _release(scene), fps=fps)
    with pytest.raises(ValueError, match=r"fps must be in \[2\.5, 1000\].*t_max = 0\.4 s"):
        record(scene, scene.die, _release(scene), fps=2.0, t_max=0.4)
    rec, = record(scene, scene.die, _release(scene), fps=2.5, t_max=0.4)  # one frame
    assert len(rec.t) == 2 and rec.outcome["time"] <= 0.4


def _tampered(rec, **changes):
    data = rec.to_data()
    data.update(changes)
    return data


@pytest.fixture(scope="module")
def two_dice():
    scene = Scene(walls=walls("tray"))
    state = GroupState.of([_release(scene), _release(scene, y=0.03, spin=(-10.0, 5.0, 3.0))])
    return record(scene, (Die(), Die()), state, fps=30.0)[0]


def test_load_refuses_frames_no_throw_has(two_dice, tmp_path):
    data = two_dice.to_data()
    n = len(data["t"])
    backwards = data["t"][:]
    backwards[2], backwards[3] = backwards[3], backwards[2]
    three = [[*frame, frame[0]] for frame in data["position"]]
    unit = [[[2 * q for q in die] for die in frame] for frame in data["quaternion"]]
    nan = [[[float("nan")] * 3] * 2, *data["position"][1:]]
    for changes, message in (
            ({"t": data["t"][:-1]}, rf"position must have shape \({n - 1}, 2, 3\).*got \({n}, "),
            ({"position": data["position"][:-1]}, r"position must have shape"),
            ({"quaternion": data["quaternion"][1:]}, r"orientation must have shape"),
            ({"t": backwards}, "t must start at 0 and increase strictly"),
            ({"position": three}, rf"position must have shape \({n}, 2, 3\)"),
            ({"position": nan}, "position must be finite"),
            ({"quaternion": unit}, "quaternion must hold finite unit quaternions"),
            ({"fps": 1e-3}, r"fps must be in \[1, 1000\]"),
            ({"outcome": {"faces": [1], "void": ""}}, "outcome.s faces must be a list of 2 ints"),
            ({"run": {"t_max": -1.0, "until": "rest"}}, "run's t_max must be None or a finite"),
            ({"run": {"t_max": None, "until": "early_rest"}}, "run's until must be one of")):
        path = tmp_path / "bad.json"
        path.write_text(json.dumps([_tampered(two_dice, **changes)]))
        with pytest.raises(RecordingError, match="recording 0: " + message):
            load(path)
    with pytest.raises(ValueError, match="position must be finite"):  # none to write either
        dataclasses.replace(two_dice, position=two_dice.position * np.nan)


def test_a_replay_simulates_no_further_than_its_frames_and_rest_hold(two_dice, monkeypatch):
    limits = []

    def spy(*args, **keywords):
        limits.append(keywords["t_max"])
        assert keywords["t_max"] is None or keywords["t_max"] < 10  # not the file's 6000 s
        return record(*args, **keywords)

    monkeypatch.setattr(files, "record", spy)
    data = _tampered(two_dice, run={"t_max": 6e3, "until": "t_max"}, fps=1.0)
    data["t"], data["position"], data["quaternion"] = (data[k][:2] for k in
                                                       ("t", "position", "quaternion"))
    data["t"][1] = 1.0
    start = time.perf_counter()
    again, = files.replay(Recording.from_data(data))  # at rest by then: the faces recorded
    assert time.perf_counter() - start < 30 and len(limits) == 1
    assert again.run == data["run"]
    assert limits[0] == pytest.approx(3 * 1.0 + 0.1, rel=1e-3)  # 2 frames, 1 more, the hold
    honest, = files.replay(two_dice)  # to its own end and hold, as recorded
    assert limits[1] > two_dice.outcome["time"] + two_dice.scene.rest.hold
    assert np.array_equal(honest.position, two_dice.position) and honest.run == two_dice.run


def test_a_throw_that_cannot_be_thrown_again_is_named(two_dice):
    overlapping = two_dice.to_data()
    overlapping["release"]["position"][1] = overlapping["release"]["position"][0]
    below = two_dice.to_data()
    below["release"]["position"][0][2] = -0.1
    for data in (overlapping, below):
        with pytest.raises(RecordingError, match="throw 0 cannot be thrown again: "):
            files.replay(Recording.from_data(data))


def test_pages_and_recordings_are_written_whole_or_not_at_all(two_dice, tmp_path, monkeypatch):
    pytest.importorskip("pygltflib")
    from dice_env.viewer import write_glb, write_html

    for name, write in (("a.json", save), ("a.html", write_html), ("a.glb", write_glb)):
        path = tmp_path / name
        write(two_dice, path)
        whole = path.read_bytes()
        with monkeypatch.context() as patch:
            patch.setattr("dice_env.disk.open", _HalfThenStopped, raising=False)
            with pytest.raises(KeyboardInterrupt):
                write(two_dice, path)
        assert path.read_bytes() == whole
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.glb", "a.html", "a.json"]


class _HalfThenStopped:
    """A file opened as ``open`` does whose ``write`` writes half its data, then is stopped."""

    def __init__(self, path, mode):
        self.file = open(path, mode)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.file.close()

    def write(self, data):
        self.file.write(data[:len(data) // 2])
        raise KeyboardInterrupt

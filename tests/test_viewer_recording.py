import json

import numpy as np
import pytest

from dice_env import Die, Scene, State, simulate
from dice_env.envs.task import make_task
from dice_env.model.rotations import matrix_to_quaternion, quaternion_to_matrix, random_rotations
from dice_env.model.scene import FrictionLaw, Ground
from dice_env.model.surroundings import walls
from dice_env.simulation.codec import from_data, to_data
from dice_env.simulation.group import DieContact, GroupState
from dice_env.viewer import Recording, ReplayError, load, record, replay, save
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
        assert rec.outcome["void"] in ("", "foul") and rec.title.startswith("target")
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

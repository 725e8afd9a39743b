"""One answer to "does this throw count": the env, a recording and its replay give the same void."""

import numpy as np
import pytest

from dice_env.envs.hand import face_up_rotation
from dice_env.envs.throw_task import decided_reads, judge, make_task
from dice_env.model.die import STANDARD_SIZES, Die
from dice_env.model.rotations import axis_angle
from dice_env.model.scene import Scene
from dice_env.simulation.simulate import simulate
from dice_env.throws import counted, hand_throws
from dice_env.viewer import record, replay


def _env_throws(task, n, seed=0):
    """``n`` random throws of ``task`` as the viewer draws them: the throw and its release."""
    rng = np.random.default_rng(seed)
    targets, hands = task.sample_hands([np.random.default_rng([seed, k]) for k in range(n)])
    actions = rng.uniform(-1.0, 1.0, (n, task.action_dim))
    noise = task.sample_noise(rng, n)
    return task.throw(actions, targets, hands, noise), task.release(actions, hands, noise)[0]


def test_a_recording_voids_what_the_env_voids_and_its_replay_agrees():
    # one die to rest within 0.35 s: a rest whose hold runs past t_max does not count
    task = make_task(t_max=0.35)
    throw, state = _env_throws(task, 48)
    env_voids = throw.info["void_reason"].tolist()
    assert "not_settled" in env_voids and "" in env_voids
    recordings = record(task.scene, task.scene.die, state, until=task.run_until)
    assert [r.outcome["void"] for r in recordings] == env_voids
    assert [r.outcome["settled"] for r in recordings] == throw.info["settled"].tolist()
    assert [r.outcome["void"] for r in replay(recordings)] == env_voids


def _top_gap(die, orientation):
    """Each orientation's lead of the face read over the next face, along up."""
    up = np.sort(np.einsum("bij,fj->bfi", orientation, die.reading)[..., 2], axis=1)
    return up[:, -1] - up[:, -2]


def test_a_face_that_round_off_decides_is_not_counted_on_a_steep_table():
    task = make_task(tilt_deg=45.0, walls="tray")
    throw, _ = _env_throws(task, 16)
    void = throw.info["void_reason"]
    gap = _top_gap(task.scene.die, throw.result.final.orientation)
    assert np.all(void[gap < 1e-3] == "not_decided")  # a d6 flat on the slope ties two faces
    assert np.all(gap[void == ""] > 0.25)
    assert not throw.info["is_success"][void != ""].any()


def test_decided_reads_keep_a_quarter_of_the_way_to_a_tie():
    d6 = Die()
    tilts = np.radians([0.0, 30.0, 34.0, 35.5, 45.0])  # the d6's margin: 0.25 = cos - sin at 34.8
    orientation = np.stack([axis_angle([0.0, 1.0, 0.0], t) for t in tilts])[:, None]
    assert decided_reads((d6,), orientation)[:, 0].tolist() == [True, True, True, False, False]


@pytest.mark.parametrize("name", list(STANDARD_SIZES))
def test_every_face_of_a_standard_die_lying_flat_is_read(name):
    die = Die.standard(name)
    flat = np.stack([face_up_rotation(die, f) for f in die.labels])[:, None]
    assert decided_reads((die,), flat).all()


@pytest.mark.parametrize("name", ["d4", "d6", "d20"])
def test_a_face_decided_by_energy_is_always_read(name):
    # the decided-face rule keeps a die further from a tie than the read's margin asks
    scene = Scene(die=Die.standard(name))
    result = simulate(scene, hand_throws(scene, 200, np.random.default_rng(3)), until="decided")
    _, void = judge(scene, (scene.die,), result, "decided")
    assert counted(result).sum() > 150
    np.testing.assert_array_equal(void == "", counted(result))


def test_judge_reads_several_dice_and_names_the_first_reason():
    task = make_task(num_dice=2, walls="tray", tilt_deg=45.0)
    throw, _ = _env_throws(task, 12, seed=1)
    result, void = judge(task.scene, task.dice, throw.result, task.run_until)
    np.testing.assert_array_equal(void, throw.info["void_reason"])
    read = decided_reads(task.dice, result.final.orientation)
    assert np.all(void[~read.all(axis=1)] != "")

"""Bad input refused where it is given; no hang, no crash, no impossible throw counted."""

import os
import re
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
from subprocess_signals import interruptible

from dice_env import ContactLaw, Die, FrictionLaw, Ground, Scene, Scheme, State
from dice_env import simulate as run
from dice_env.model.rotations import random_rotations
from dice_env.model.scene import MAX_STEPS
from dice_env.simulation import paper

SCENE = Scene()
ONE = np.zeros((1, 3))


def drop(scene=SCENE, height=0.05, velocity=(0.0, 0.0, 0.0)):
    return State.release(scene, [0.0, 0.0, height], velocity)


def throws(scene, n, seed=0):
    rng = np.random.default_rng(seed)
    return State.release(scene, [0.0, 0.0, 0.03], rng.uniform(-1, 1, (n, 3)),
                         rng.uniform(-40, 40, (n, 3)), random_rotations(rng, n))


@pytest.mark.parametrize("build, message", [
    (lambda: State(np.tile([0, 0, 0.05], (1000, 1)), ONE, ONE, np.eye(3)[None], ONE),
     "one batch size"),
    (lambda: State(ONE, ONE, ONE, 2 * np.eye(3)[None], ONE), "orientation must be rotation"),
    (lambda: State(ONE + np.nan, ONE, ONE, np.eye(3)[None], ONE), "State.position must be finite"),
    (lambda: State(np.zeros(3), ONE, ONE, np.eye(3)[None], ONE), "State.position must have shape"),
    (lambda: State(*(np.zeros((0, 3)),) * 3, np.zeros((0, 3, 3)), np.zeros((0, 3))), "B >= 1"),
    (lambda: State.release(SCENE, np.zeros((0, 3)), np.zeros((0, 3))), "at least one die"),
])
def test_inconsistent_states_are_refused_when_built(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def test_a_state_changed_after_it_was_built_is_checked_again_by_simulate():
    state = drop()
    state.orientation = np.tile(np.eye(3), (2, 1, 1))
    with pytest.raises(ValueError, match="one batch size"):
        run(SCENE, state)


def test_integer_arrays_become_floats_instead_of_being_truncated():
    state = State(np.array([[0, 0, 1]]), np.zeros((1, 3), int), np.zeros((1, 3), int),
                  np.eye(3, dtype=int)[None], np.zeros((1, 3), int))
    result = run(SCENE, state, t_max=0.1, until="t_max")
    z = result.final.position[0, 2]
    assert z == pytest.approx(1 - 0.5 * 9.81 * 0.1**2, abs=1e-3)  # falling, not stuck at 1


@pytest.mark.parametrize("make", [
    lambda: Scene(ground=Ground(stiffness=1e12)),
    lambda: Scene(ground=Ground(stiffness=1e30)),
    lambda: Scene(ground=Ground(damping=1e6)),
    lambda: Scene(ground=Ground(damping=1e15)),
    lambda: Scene(die=Die(mass=1e-9)),
    lambda: Scene(safety=1e-9),
    lambda: Scene(t_max=1e30),
    lambda: Scene(die=Die(inertia=tuple(map(tuple, np.eye(3) * 1e-30)))),
    lambda: run(SCENE, drop(), t_max=1e30),
])
def test_runs_too_long_to_finish_are_refused_before_any_work(make):
    limit = re.escape(f"t_max / step must be <= {MAX_STEPS:.0e} steps")
    with pytest.raises(ValueError, match=limit):
        make()


@pytest.mark.parametrize("make, message", [
    (lambda: Scene(die=Die(mass=1e30)), r"step must be in \(0, t_max"),
    (lambda: Die.loaded(face=2.5), r"face must be an int in \[1, 6\]"),
    (lambda: Scene(rest="x"), "rest must be a Rest"),
    (lambda: Scene(rotation="no"), "rotation must be a bool"),
    (lambda: Scene(allow_unstable="yes"), "allow_unstable must be a bool"),
    (lambda: Scene(scheme="rk4"), "scheme must be a Scheme or one of 'paper', 'midpoint'"),
    (lambda: run(SCENE, drop(), num_threads=1000), r"num_threads must be an int in \[1, "),
    (lambda: run(SCENE, drop(), num_threads=0), "num_threads"),
    (lambda: run(SCENE, drop(), record="enrgy", record_every=10), "record must name only"),
    (lambda: run(SCENE, drop(), record=3, record_every=10), "record must be a name"),
    (lambda: run(SCENE, drop(), until="no"),
     "until must be one of 'rest', 'early_rest', 'decided', 't_max', got 'no'"),
    (lambda: run(SCENE, drop(), until=["rest"]), "until must be one of"),
    (lambda: run(SCENE, throws(SCENE, 64), record_every=1, record=("nodes",)),
     "more than the limit"),
])
def test_bad_values_are_refused_with_their_name(make, message):
    with pytest.raises((ValueError, TypeError), match=message):
        make()


def test_enums_their_names_and_values_are_one_choice_everywhere():
    assert Ground(contact_law="paper").contact_law is ContactLaw.PAPER
    assert Scene(friction_law="REGULARIZED", scheme=0).scheme is Scheme.PAPER
    assert Scene(friction_law=FrictionLaw.REGULARIZED).friction_law is FrictionLaw.REGULARIZED
    gated = paper.ground_cube(contact_law="gated", clockmax=100, tmax=0.01)
    same = paper.ground_cube(contact_law=ContactLaw.GATED, clockmax=100, tmax=0.01)
    np.testing.assert_array_equal(gated.x_cm, same.x_cm)


def test_a_single_record_name_is_not_read_as_letters():
    result = run(SCENE, drop(), record="energy", record_every=100)
    assert result.energy.shape == result.x_cm.shape[:2]


@pytest.mark.parametrize("stiffness", [1e2, 1e3, 1e4])
def test_soft_tables_are_not_flagged_unstable(stiffness):
    # a slip re-ties the sticking spring to carry mu fn, damping share included: on a soft,
    # damped table that bookkeeping stored many times the throw's energy and flagged 60-100 %
    scene = Scene(ground=Ground(stiffness=stiffness))
    result = run(scene, throws(scene, 48), until="decided")
    assert not result.unstable.any()
    assert result.energy_rise.max() < 0.1


def test_an_energy_gain_is_still_flagged():
    scene = Scene(dt=0.95 * SCENE.critical_dt, ground=Ground(damping=0.0))
    result = run(scene, throws(scene, 16), t_max=1.0)
    assert result.unstable.any()


def test_a_release_inside_the_table_is_refused():
    for z in (-1.0, 0.0, 0.0079):  # the corners 0.1 mm deep, a thousand times its weight's
        with pytest.raises(ValueError, match="position must hold every corner"):
            drop(height=z)
    with pytest.raises(ValueError, match="x0 must hold every corner above the ground"):
        paper.real_throw_cube(x0=(0.0, 0.0, 0.2), seed=0, clockmax=10, tmax=0.001)
    with pytest.raises(ValueError, match="x0 must hold every corner above the ground"):
        paper.ground_cube(x0=(0.0, 0.0, 0.2), clockmax=10, tmax=0.001)


def test_a_hand_built_state_deep_in_the_table_is_refused_by_simulate():
    state = State(np.array([[0.0, 0.0, 0.0]]), ONE, ONE, np.eye(3)[None], ONE)
    with pytest.raises(ValueError, match="sink limit"):
        run(SCENE, state)


def test_a_resting_die_may_start_slightly_in_the_table():
    rest = run(SCENE, drop(height=0.009)).final
    assert SCENE.sink(rest.position, rest.orientation)[0] > 0  # corners sunk by its weight
    again = run(SCENE, rest)
    assert again.settled[0] and not again.sunk[0]


@pytest.mark.parametrize("scene, velocity", [
    (Scene(gravity=1e6), (0.0, 0.0, 0.0)),
    (SCENE, (0.0, 0.0, -1e6)),
])
def test_impossible_sinks_are_flagged(scene, velocity):
    result = run(scene, drop(scene, velocity=velocity), t_max=0.5)
    assert result.sunk[0]
    assert result.max_penetration[0] > scene.sink_limit * scene.die.size


def test_realistic_throws_never_sink():
    result = run(SCENE, throws(SCENE, 64), until="decided")
    assert not result.sunk.any()


def test_paper_listings_take_one_vector_only():
    with pytest.raises(ValueError, match=r"L0 must be one vector of shape \(3,\)"):
        paper.real_throw_cube(L0=np.ones((2, 3)), clockmax=10, tmax=0.001)


def _script(body: str) -> list[str]:
    prelude = textwrap.dedent("""
        import numpy as np, sys
        from dice_env import Scene, State
        from dice_env import simulate
        from dice_env.model.rotations import random_rotations
        scene = Scene()
        def throws(n, seed):
            rng = np.random.default_rng(seed)
            return State.release(scene, [0, 0, 0.05], rng.normal(0, .5, (n, 3)),
                                 rng.normal(0, 20, (n, 3)), random_rotations(rng, n))
    """)
    return [sys.executable, "-c", prelude + textwrap.dedent(body)]


def test_ctrl_c_ends_a_long_run_promptly():
    code = _script("""
        simulate(scene, throws(1, 0), t_max=0.01)  # both kernels compiled before the timed
        simulate(scene, throws(2, 0), t_max=0.01)  # run: a compile cannot be interrupted
        print("running", flush=True)
        try:
            simulate(scene, throws(2, 0), t_max=9000.0, until="t_max")
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            sys.exit(3)
    """)
    proc = subprocess.Popen(code, stdout=subprocess.PIPE, text=True, preexec_fn=interruptible)
    try:
        assert proc.stdout.readline().strip() == "running"
        time.sleep(1.0)
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=60)
    finally:
        proc.kill()  # never leave a 9000 s run behind a failed test
    assert proc.returncode == 3 and "interrupted" in out
    assert time.monotonic() - sent < 10


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork-started pools need os.fork")
def test_a_fork_started_pool_works_after_a_batched_run():
    code = _script("""
        import multiprocessing as mp
        def work(seed):
            return int(simulate(scene, throws(32, seed), until="decided").face.sum())
        if __name__ == "__main__":
            before = [work(s) for s in (1, 2, 3)]
            with mp.get_context("fork").Pool(2) as pool:
                assert pool.map(work, [1, 2, 3]) == before
            print("done")
    """)
    out = subprocess.run(code, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "done" in out.stdout and "unsafe" not in out.stderr


def test_the_paper_law_with_stick_slip_ties_a_vertex_in_the_air_without_dividing_by_zero():
    scene = Scene(ground=Ground(contact_law=ContactLaw.PAPER), gravity=0.0, t_max=1.0)
    start = State.release(scene, [0, 0, 0.015], [[0.3, 0.2, -0.5]], [[5.0, -3.0, 2.0]])
    result = run(scene, start)
    assert np.isfinite(result.final.position).all()

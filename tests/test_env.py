"""DiceThrow-v0: checkers, determinism, bad input, void throws, rendering."""

import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from scipy import ndimage

import dice_env  # noqa: F401
from dice_env import Die, Scene
from dice_env.envs import DiceThrowEnv
from dice_env.envs.dice_throw import RENDER_FPS
from dice_env.envs.hand import face_up_rotation
from dice_env.envs.render import render_die
from dice_env.envs.throw_task import make_task
from dice_env.envs.video import save_video

FAST = {"t_max": 2.0}  # gentle throws settle in under 2 s


def make(**kwargs):
    return gym.make("DiceThrow-v0", **{**FAST, **kwargs})


def test_make_without_prior_import():
    code = ("import sys; import gymnasium as gym; e = gym.make('dice_env:DiceThrow-v0'); "
            "print(type(e.unwrapped).__name__, 'stable_baselines3' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["DiceThrowEnv", "False"]  # SB3 (and torch) only when asked


def test_step_types_and_info():
    env = make()
    obs, info = env.reset(seed=0)
    assert obs in env.observation_space and info == {}
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert obs.dtype == np.float32 and obs in env.observation_space
    assert type(reward) is float and terminated is True and truncated is False
    assert type(info["is_success"]) is bool and info["face"] in range(1, 7)
    assert info["void_reason"] in ("", "foul", "unstable", "not_settled")
    assert info["reward_success"] + info["reward_shaping"] == reward
    assert info["release_velocity"].shape == (3,) and info["release_orientation"].shape == (3, 3)
    assert info["is_success"] == (info["face"] == info["target_face"] and not info["void_reason"])


def test_gymnasium_check_env_no_warnings():
    env = make()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)  # the unwrapped env still carries the spec for the render modes


def test_sb3_check_env_no_warnings():
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb3_check_env(make().unwrapped)


def test_same_seed_same_throws():
    actions = np.random.default_rng(0).uniform(-1, 1, (2, 6))
    runs = []
    for seed in (4, 4, 5):
        env = make()
        obs, _ = env.reset(seed=seed)
        steps = [obs, *(env.step(a)[::4] for a in actions)]  # second step: same hand, new noise
        runs.append(steps)
    same = [np.array_equal(runs[0][0], runs[j][0]) for j in (1, 2)]
    assert same == [True, False]
    for k in (1, 2):
        assert np.array_equal(runs[0][k][0], runs[1][k][0])
        assert all(np.array_equal(runs[0][k][1][key], runs[1][k][1][key]) for key in runs[0][k][1])
    assert not np.array_equal(runs[0][1][1]["release_velocity"], runs[0][2][1]["release_velocity"])


def test_bad_actions():
    env = make()
    env.reset(seed=0)
    for bad in (np.nan, np.inf, -np.inf):
        with pytest.raises(ValueError, match="action must be finite"):
            env.step(np.array([bad, 0, 0, 0, 0, 0]))
    with pytest.raises(ValueError, match="action must have shape"):
        env.step(np.zeros(5))
    _, _, _, _, info = env.step(np.array([3.0, 0, 0, 0, 0, 0]))
    assert info["action_clipped"] is True
    assert np.allclose(info["release_velocity"][0], 1.0, atol=0.3)  # max_speed 1, 5% noise
    _, _, _, _, info = env.step(np.full(6, 0.5))
    assert info["action_clipped"] is False


@pytest.mark.parametrize(("keyword", "value", "match"), [
    ("release_height", 0.005, "release_height"),
    ("hand_noise", -0.1, "hand_noise"),
    ("max_speed", 0.0, "max_speed"),
    ("max_spin", np.inf, "max_spin"),
    ("target_face", 7, "target_face"),
    ("orientation_mode", "sideways", "orientation_mode"),
    ("stiffness", -1.0, "stiffness"),
    ("friction", np.nan, "friction"),
    ("mass", 0.0, "mass"),
    ("t_max", 0.0, "t_max"),
    ("dt", 1.0, "dt"),
    ("contact_law", "soft", "contact_law"),
    ("scheme", "rk4", "scheme"),
    ("friction_law", "viscous", "friction_law"),
    ("friction_vmin", 0.0, "friction_vmin"),
    ("tilt_deg", 95.0, "tilt_deg"),
    ("load_fraction", 1.5, "load_fraction"),
    ("num_threads", 0, "num_threads"),
    ("device", "gpu", "device must be one of"),
    ("until", "landed", "until must be one of"),
    ("stifness", 1e5, "unknown keyword"),
])
def test_bad_keywords(keyword, value, match):
    with pytest.raises(ValueError, match=match):
        make(**{keyword: value})


def test_the_gpu_device_is_refused_where_it_cannot_run(monkeypatch):
    if not numba_cuda_usable():  # no GPU: refused at make, not at the first step
        with pytest.raises((ImportError, RuntimeError), match="device='cuda'"):
            make(device="cuda")
    monkeypatch.setattr("dice_env.envs.dice_throw.require_device", lambda device: None)
    for keywords in ({"num_dice": 2}, {"render_mode": "rgb_array"}):
        with pytest.raises(ValueError, match="device='cuda' runs one die a throw"):
            make(device="cuda", **keywords)


def numba_cuda_usable() -> bool:
    """Whether numba-cuda is installed and finds a GPU."""
    try:
        from numba import cuda
    except ImportError:
        return False
    return cuda.is_available()


def test_until_decided_lands_the_same_faces_sooner():
    rest, decided = (gym.make_vec("DiceThrow-v0", num_envs=32, until=until)
                     for until in ("rest", "decided"))
    actions = np.random.default_rng(0).uniform(-1, 1, (32, 6))
    infos = []
    for venv in (rest, decided):
        venv.reset(seed=4)
        infos.append(venv.step(actions)[4]["final_info"])
    at_rest, at_decision = infos
    np.testing.assert_array_equal(at_rest["face"], at_decision["face"])
    np.testing.assert_array_equal(at_rest["is_success"], at_decision["is_success"])
    assert at_rest["settled"].all() and not at_decision["settled"].any()
    assert (at_decision["void_reason"] == "").all()
    assert (at_decision["rest_time"] < at_rest["rest_time"]).all()
    env = make(until="decided", t_max=0.02)
    env.reset(seed=0)
    assert env.step(np.zeros(6))[4]["void_reason"] == "not_decided"
    with pytest.raises(ValueError, match="until='decided' needs a horizontal table"):
        make(until="decided", tilt_deg=5.0)


def test_physical_keywords_reach_the_scene():
    scene = make(scheme="midpoint", friction_law="regularized", friction_vmin=0.05,
                 stiffness=2e5).unwrapped.task.scene
    assert scene.scheme.name == "MIDPOINT" and scene.friction_law.name == "REGULARIZED"
    assert scene.friction_vmin == 0.05 and scene.ground.stiffness == 2e5


def test_bad_render_mode():
    with pytest.raises(ValueError, match="render_mode"):
        DiceThrowEnv(render_mode="ascii")


def test_vector_bad_input():
    for kwargs, match in (({"num_envs": 0}, "num_envs"), ({"stifness": 1e5}, "unknown keyword"),
                          ({"hand_noise": -1.0}, "hand_noise"),
                          ({"render_mode": "human"}, "render_mode")):
        with pytest.raises(ValueError, match=match):
            gym.make_vec("DiceThrow-v0", **{"num_envs": 2, **kwargs})
    venv = gym.make_vec("DiceThrow-v0", num_envs=2, **FAST)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="action must be finite"):
        venv.step(np.full((2, 6), np.inf))
    with pytest.raises(ValueError, match=r"actions must have shape \(2, 6\)"):
        venv.step(np.zeros((3, 6)))
    with pytest.raises(ValueError, match="seed"):
        venv.reset(seed=[1, 2, 3])
    _, rewards, terminated, truncated, info = venv.step(np.full((2, 6), 2.0))
    assert info["final_info"]["action_clipped"].all() and rewards.dtype == np.float64
    assert terminated.all() and not truncated.any()


def test_keywords_reach_the_scene():
    task = make(stiffness=2e5, friction=0.3, edge=0.02, tilt_deg=10.0,
                release_height=0.03).unwrapped.task
    assert task.scene.ground.stiffness == 2e5 and task.scene.ground.friction == 0.3
    assert task.scene.die.size == 0.02 and task.scene.ground.normal[0] > 0
    assert make_task().scene.die == Scene().die  # defaults flow from Scene()
    assert make_task(load_fraction=0.2).scene.die.com[2] < 0  # toward face 6 (-z)


def test_void_throws_are_not_rewarded():
    env = make(t_max=0.02, target_face=1)
    env.reset(seed=0)
    _, reward, _, _, info = env.step(np.zeros(6))
    assert info["void_reason"] == "not_settled" and reward == 0.0 and not info["is_success"]
    env = make(min_speed=5.0)
    env.reset(seed=0)
    _, reward, _, _, info = env.step(np.zeros(6))
    assert info["void_reason"] == "foul" and info["fair"] is False and reward == 0.0
    # Flagged unstable (a tolerance no real throw meets) while landing on the target: still 0.
    env = make(energy_tol=1e-9)
    env.reset(seed=0, options={"target_face": 1})
    face = env.step(np.ones(6))[4]["face"]
    env.reset(seed=0, options={"target_face": face})
    _, reward, _, _, info = env.step(np.ones(6))
    assert info["face"] == face and info["unstable"] is True
    assert info["void_reason"] == "unstable" and reward == 0.0 and info["is_success"] is False


def test_reset_options():
    env = make()
    obs, _ = env.reset(seed=0, options={"target_face": 4, "orientation": np.eye(3)})
    assert obs[3] == 1.0 and np.array_equal(obs[6:], np.eye(3, dtype=np.float32).ravel())
    with pytest.raises(ValueError, match="orientation"):
        env.reset(options={"orientation": 2 * np.eye(3)})


def test_placed_die_lands_as_held():
    # No noise, no velocity, face 3 held up a few mm above the table: it lands with 3 up.
    env = make(hand_noise=0.0, orientation_noise=0.0, release_height=0.015, target_face=3)
    env.reset(seed=0, options={"orientation": face_up_rotation(Die(), 3)})
    _, reward, _, _, info = env.step(np.zeros(6))
    assert info["face"] == 3 and reward == 1.0 and info["settled"]


def count_pips(image):
    dark = image.max(axis=-1) < 80
    return ndimage.label(dark)[1]


def test_render_top_face_shows_its_number():
    scene = Scene()
    position = np.array([0.0, 0.0, scene.die.size / 2])
    for k in range(6):
        image = render_die(scene, position, face_up_rotation(scene.die, k + 1), size=(96, 96),
                           elevation=90.0)
        assert image.shape == (96, 96, 3) and image.dtype == np.uint8
        assert count_pips(image) == k + 1


def test_render_modes(tmp_path, monkeypatch):
    for name in ("DISPLAY", "WAYLAND_DISPLAY"):  # "human" must be a no-op without a display
        monkeypatch.delenv(name, raising=False)
    env = make(render_mode="rgb_array", render_width=64, render_height=48)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (48, 64, 3) and frame.dtype == np.uint8
    env.step(np.zeros(6))
    assert not np.array_equal(env.render(), frame)  # the die moved
    env = make(render_mode="rgb_array_list", render_width=64, render_height=48)
    env.reset(seed=0)
    env.step(np.array([0, 0, 1.0, 0, 0.5, 0]))  # tossed up: a few tenths of a second in the air
    frames = env.render()
    assert len(frames) > 5 and all(f.shape == (48, 64, 3) for f in frames)
    assert len(frames) < 3 * RENDER_FPS  # up to rest, not the whole t_max
    assert env.render() == []
    path = save_video(frames, tmp_path / "throw.gif")
    assert path.stat().st_size > 0
    env = make(render_mode="human")
    env.reset(seed=0)
    env.step(np.zeros(6))
    assert env.render() is None and env.unwrapped._viewer._figure is None
    venv = gym.make_vec("DiceThrow-v0", num_envs=2, render_mode="rgb_array", **FAST)
    venv.reset(seed=0)
    assert len(venv.render()) == 2


def test_no_rendering_cost_without_render_mode(monkeypatch):
    def fail(*args, **kwargs):
        raise AssertionError("drew a frame without a render mode")

    monkeypatch.setattr("dice_env.envs.render.render_die", fail)
    env = make()
    env.reset(seed=0)
    env.step(np.zeros(6))
    assert env.render() is None and env.unwrapped._record_every() == 0


def test_frames_at_render_fps():
    env = make(render_mode="rgb_array_list", render_width=32, render_height=24)
    env.reset(seed=1)
    _, _, _, _, info = env.step(np.array([0.2, 0, 0.3, 5, 0, 0]) / 8)
    frames = env.render()  # in the hand, every 1/fps s of the throw, at rest
    fps = env.metadata["render_fps"]
    assert abs(len(frames) - 2 - info["rest_time"] * fps) <= 2


@pytest.mark.parametrize("mode", ["flat", "identity"])
def test_orientation_modes_hold_a_face_up(mode):
    venv = gym.make_vec("DiceThrow-v0", num_envs=4, orientation_mode=mode, **FAST)
    obs, _ = venv.reset(seed=0)
    up = obs[:, 6:].reshape(-1, 3, 3)[:, 2, :]  # world z in the body frame, per die
    assert np.allclose(np.sort(np.abs(up), axis=1)[:, -1], 1.0, atol=1e-6)
    single = make(orientation_mode=mode)
    assert np.array_equal(single.reset(seed=2)[0], obs[2])


def test_save_video(tmp_path):
    import imageio.v3 as iio

    frames = [np.full((24, 32, 3), 40 * i, np.uint8) for i in range(4)]
    path = save_video(frames, tmp_path / "throw.gif", fps=25)
    assert iio.imread(path, index=None).shape == (4, 24, 32, 3)
    assert iio.immeta(path)["duration"] == 40  # ms per frame
    for bad, match in (({"frames": []}, "frames"), ({"path": tmp_path / "x.avi"}, "path"),
                       ({"fps": 0}, "fps")):
        with pytest.raises(ValueError, match=match):
            save_video(**{"frames": frames, "path": tmp_path / "x.gif", **bad})
    try:
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError, match="video extra"):
            save_video(frames, tmp_path / "throw.mp4")
    else:
        assert save_video(frames, tmp_path / "throw.mp4").stat().st_size > 0

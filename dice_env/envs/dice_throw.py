"""DiceThrow-v0: throw a die so that a target face lands up (one throw per episode)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from dice_env.envs.hand import ORIENTATION_MODES
from dice_env.envs.throw_task import ORIENTATION_DIM, ThrowTask, check_rotation, make_task
from dice_env.model.checks import check_choice, check_int
from dice_env.simulation.simulate import require_device, thread_count

RENDER_MODES = ("human", "rgb_array", "rgb_array_list")
RENDER_FPS = 30
MAX_FRAME_BYTES = 2**30  # the frames one throw may keep in "rgb_array_list" mode


def observation_space(task: ThrowTask) -> spaces.Box:
    """The target's encoding in [0, 1], then each die's orientation in [-1, 1] (9 per die)."""
    low = np.r_[np.zeros(task.goal.dim),
                -np.ones(ORIENTATION_DIM * task.n_dice)].astype(np.float32)
    return spaces.Box(low, np.ones(task.obs_dim, np.float32), dtype=np.float32)


def action_space(task: ThrowTask) -> spaces.Box:
    """Actions in [-1, 1]: velocity and spin, and with ``set_dice`` 3 per die."""
    return spaces.Box(-1.0, 1.0, (task.action_dim,), np.float32)


@dataclass(frozen=True)
class EnvSettings:
    """The env's keywords beyond the task's: the episodes, the rendering, the execution.

    ``target_face``/``target_sum``/``orientation_mode``: each episode's (``reset`` options
    override one); ``render_*``: the frames; ``num_threads``: the kernel's threads (None: all);
    ``device``: where the kernel runs (``"cuda"``: one die a throw, no frames).
    Checked against a task by :meth:`check`; the meanings: ``docs/environment.md``.
    """

    render_mode: str | None = None
    target_face: Any = None
    target_sum: int | None = None
    orientation_mode: str = "uniform"
    render_width: int = 320
    render_height: int = 240
    num_threads: int | None = None
    device: str = "cpu"

    @property
    def render_size(self) -> tuple[int, int]:
        """The frames' (height, width) in pixels."""
        return self.render_height, self.render_width

    def check_rendering(self, modes: tuple[str, ...]) -> None:
        """Refuse a render mode not in ``modes`` or a frame size out of 16 … 4096 pixels."""
        if self.render_mode is not None and not (isinstance(self.render_mode, str)
                                                 and self.render_mode in modes):
            raise ValueError(f"render_mode must be None or one of {modes}, "
                             f"got {self.render_mode!r}")
        check_int("render_width", self.render_width, 16, 4096)
        check_int("render_height", self.render_height, 16, 4096)

    def check(self, task: ThrowTask, modes: tuple[str, ...]) -> EnvSettings:
        """These settings, if an env of ``task`` with render modes ``modes`` takes them."""
        self.check_rendering(modes)
        t_max, frame = task.scene.t_max, self.render_width * self.render_height * 3
        size = (math.ceil(t_max * RENDER_FPS) + 2) * frame  # in the hand, the throw, at rest
        if self.render_mode == "rgb_array_list" and size > MAX_FRAME_BYTES:
            raise ValueError(
                f"t_max must be at most {MAX_FRAME_BYTES / (frame * RENDER_FPS):.4g} s with "
                f"render_mode='rgb_array_list' at {self.render_width}x{self.render_height} (at "
                f"most 1 GiB of frames), got t_max={t_max:g} s ({size / 2**30:.3g} GiB); lower "
                "t_max or the render size")
        task.goal.fix(self.target_face, self.target_sum)
        check_choice("orientation_mode", self.orientation_mode, ORIENTATION_MODES)
        thread_count(self.num_threads)  # refuses a count numba does not have
        require_device(self.device)
        if self.device == "cuda" and (task.n_dice > 1 or self.render_mode is not None):
            raise ValueError("device='cuda' runs one die a throw and keeps no frames: it needs "
                             f"num_dice=1 and render_mode=None, got num_dice={task.n_dice} and "
                             f"render_mode={self.render_mode!r}")
        return self


def configure(modes: tuple[str, ...], render_mode: str | None = None, *,
              target_face: Any = None, target_sum: int | None = None,
              orientation_mode: str = "uniform", render_width: int = 320,
              render_height: int = 240, num_threads: int | None = None, device: str = "cpu",
              **task_keywords: Any) -> tuple[ThrowTask, EnvSettings]:
    """The single or vector env's task and settings from its keywords, each validated."""
    settings = EnvSettings(render_mode, target_face, target_sum, orientation_mode,
                           render_width, render_height, num_threads, device)
    settings.check_rendering(modes)
    task = make_task(**task_keywords)
    return task, settings.check(task, modes)


RESET_OPTIONS = ("target_face", "target_sum", "orientation", "orientation_mode")


def episode_hand(task: ThrowTask, settings: EnvSettings, rng: np.random.Generator,
                 options: dict[str, Any] | None) -> tuple[Any, np.ndarray]:
    """One episode's target and hand orientation(s), ``reset`` options over ``settings``."""
    options = {} if options is None else options
    if not isinstance(options, dict) or set(options) - set(RESET_OPTIONS):
        raise ValueError(f"options must be None or a dict with keys among {RESET_OPTIONS}, "
                         f"got {options!r}")
    fixed = task.goal.fix(options.get("target_face", settings.target_face),
                          options.get("target_sum", settings.target_sum))
    target, hand = task.sample_hand(rng, fixed,
                                    options.get("orientation_mode", settings.orientation_mode))
    if "orientation" in options:
        hand = check_rotation("options['orientation']", options["orientation"], task.hand.die_shape)
    return target, hand


class DiceThrowEnv(gym.Env):
    """Throw a die from the hand so that the target face ends up; one throw per episode.

    Out-of-range actions are clipped, NaN/inf or another shape raise ``ValueError``; ``step``
    ends the episode. The spaces, rewards, ``info``, ``reset`` options and every keyword:
    ``docs/environment.md``; named tasks: :data:`dice_env.envs.tasks.TASKS`.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": list(RENDER_MODES),
                                          "render_fps": RENDER_FPS}

    def __init__(self, render_mode: str | None = None, **keywords: Any) -> None:
        self.task, self.settings = configure(RENDER_MODES, render_mode, **keywords)
        self.render_mode = self.settings.render_mode
        self.observation_space = observation_space(self.task)
        self.action_space = action_space(self.task)
        # Placeholders until reset: the dice in the hand, unturned.
        self._target, self._hand = self.task.sample_hand(np.random.default_rng(0),
                                                         orientation_mode="identity")
        self._pose = (self.task.hand_position, self._hand)
        self._frames: list[np.ndarray] = []
        self._viewer: Any = None

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Put the die in the hand and draw the target; options override one episode."""
        super().reset(seed=seed)
        self._target, self._hand = episode_hand(self.task, self.settings, self.np_random,
                                                options)
        self._pose = (self.task.hand_position, self._hand)
        self._frames = []
        self._draw([self._pose])
        return self.task.observe(self._target, self._hand)[0], {}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Throw once and simulate to rest."""
        throw = self.task.throw(action, [self._target], self._hand[None], [self.np_random],
                                record_every=self._record_every(),
                                action_shape=self.action_space.shape,
                                num_threads=self.settings.num_threads,
                                device=self.settings.device)
        result = throw.result
        self._pose = (result.final.position[0], result.final.orientation[0])
        if result.orientations is not None:  # the frames until the die stopped, then at rest
            shown = int(result.steps[0]) // self._record_every()
            self._draw([*zip(result.x_cm[0, :shown], result.orientations[0, :shown],
                             strict=True), self._pose])
        # Per-throw numpy scalars as Python bool/int/float/str; per-die arrays unchanged.
        info = {key: value[0] if np.ndim(value[0]) else value[0].item()
                for key, value in throw.info.items()}
        return throw.observation[0], float(throw.reward[0]), True, False, info

    def render(self) -> np.ndarray | list[np.ndarray] | None:
        """The current frame ("rgb_array"), the frames since the last call ("rgb_array_list")."""
        if self.render_mode == "rgb_array":
            return self._frame(*self._pose)
        if self.render_mode == "rgb_array_list":
            frames, self._frames = self._frames, []
            return frames
        return None

    def close(self) -> None:
        """Close the window of the "human" mode, if any."""
        if self._viewer is not None:
            self._viewer.close()
            self._viewer = None

    def _record_every(self) -> int:
        if self.render_mode not in ("rgb_array_list", "human"):
            return 0
        return max(1, round(1.0 / (RENDER_FPS * self.task.step)))

    def _frame(self, position: np.ndarray, orientation: np.ndarray) -> np.ndarray:
        from dice_env.envs.render import render_task

        return render_task(self.task, position, orientation, size=self.settings.render_size)

    def _draw(self, poses: list[tuple[np.ndarray, np.ndarray]]) -> None:
        """Keep ("rgb_array_list") or show ("human") the frames of these poses."""
        if self.render_mode == "rgb_array_list":
            self._frames.extend(self._frame(*pose) for pose in poses)
        elif self.render_mode == "human":
            from dice_env.envs.render import Viewer

            if self._viewer is None:
                self._viewer = Viewer(RENDER_FPS)
            for pose in poses:
                self._viewer.show(self._frame(*pose))

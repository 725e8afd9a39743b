"""Reference results on fixed seeds: the faces and final states a refactor must keep.

``python tests/reference_results.py`` rewrites ``tests/data/reference_results.npz`` from the
code as it stands; do so only for a change meant to alter results, and say so in its commit.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import llvmlite.binding
import numba
import numpy as np

from dice_env import Die, Scene, simulate
from dice_env.envs import TASKS
from dice_env.model.surroundings import tray
from dice_env.simulation.group import DieContact, simulate_group
from dice_env.simulation.paper import paper_scene
from dice_env.throws import group_throws, vigorous_throws

PATH = Path(__file__).with_name("data") / "reference_results.npz"
THROWS = 16


def host() -> str:
    """What the bits depend on besides the code: the CPU numba compiles for, numpy, numba."""
    cpu = llvmlite.binding.get_host_cpu_name()
    return f"{cpu}, numpy {np.__version__}, numba {numba.__version__}"


def _single(scene: Scene, **run: object) -> Callable[[], dict[str, np.ndarray]]:
    def case() -> dict[str, np.ndarray]:
        state = vigorous_throws(scene, THROWS, np.random.default_rng(7))
        result = simulate(scene, state, num_threads=1, **run)
        final = result.final
        return {"face": result.face, "steps": result.steps,
                "state": np.concatenate([final.position, final.velocity,
                                         final.angular_momentum,
                                         final.orientation.reshape(THROWS, 9)], axis=1)}
    return case


def _group(n: int, islands: bool) -> Callable[[], dict[str, np.ndarray]]:
    def case() -> dict[str, np.ndarray]:
        scene, dice = Scene(walls=tray(), t_max=3.0), (Die(),) * n
        state = group_throws(scene, dice, 4, np.random.default_rng(11))
        result = simulate_group(scene, dice, state, until="decided", num_threads=1,
                                contact=DieContact(islands=islands))
        final = result.final
        return {"face": result.face, "steps": result.steps,
                "state": np.concatenate([final.position, final.velocity,
                                         final.angular_momentum,
                                         final.orientation.reshape(4, n, 9)], axis=2)}
    return case


def _env(task_id: str) -> Callable[[], dict[str, np.ndarray]]:
    def case() -> dict[str, np.ndarray]:
        envs = gym.make_vec(task_id, num_envs=16, num_threads=1)
        first, _ = envs.reset(seed=5)
        actions = np.random.default_rng(13).uniform(-1, 1, (16, *envs.single_action_space.shape))
        then, reward, _, _, info = envs.step(actions)
        info = info.get("final_info", info)  # where the vector env resets in the same step
        return {"observation": np.concatenate([first, then]), "reward": reward,
                "face": info["face"], "void": info["void_reason"].astype("U")}
    return case


CASES: dict[str, Callable[[], dict[str, np.ndarray]]] = {
    "default_rest": _single(Scene()),
    "default_decided": _single(Scene(), until="decided"),
    "paper_vector": _single(paper_scene().with_(t_max=3.0)),
    "d20_tray": _single(Scene(die=Die.standard("d20"), walls=tray())),
    "loaded": _single(Scene(die=Die.loaded())),
    "drilled": _single(Scene(die=Die.standard("d6", pips="drilled16"))),
    "two_d6": _group(2, islands=False),
    "twelve_d6": _group(12, islands=False),
    "two_d6_islands": _group(2, islands=True),
    "twelve_d6_islands": _group(12, islands=True),
    **{f"env_{task.id}": _env(task.id) for task in TASKS},
}


def compute() -> dict[str, np.ndarray]:
    """Every case's arrays, keyed ``case/array``."""
    return {f"{name}/{key}": value for name, case in CASES.items()
            for key, value in case().items()}


if __name__ == "__main__":
    PATH.parent.mkdir(exist_ok=True)
    np.savez_compressed(PATH, host=np.array(host()), **compute())
    print(f"wrote {PATH}")

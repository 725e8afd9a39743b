"""Gymnasium environments: DiceThrow-v0 (single and natively batched), its named tasks, SB3.

Importing :mod:`dice_env` registers ``DiceThrow-v0`` and the named tasks
(:data:`dice_env.envs.tasks.TASKS`); ``gym.make("dice_env:DiceThrow-v0")`` imports it.
"""

from gymnasium.envs.registration import register, registry

from dice_env.envs.dice_throw import DiceThrowEnv
from dice_env.envs.tasks import TASKS, NamedTask
from dice_env.envs.throw_task import Throw, ThrowTask, make_task
from dice_env.envs.vector import DiceThrowVectorEnv

ENV_ID = "DiceThrow-v0"


for _named in TASKS:
    if _named.id not in registry:  # once per process: a reload keeps the registration
        register(id=_named.id, entry_point="dice_env.envs.dice_throw:DiceThrowEnv",
                 vector_entry_point="dice_env.envs.vector:DiceThrowVectorEnv",
                 kwargs=dict(_named.keywords))
del _named

__all__ = ["ENV_ID", "TASKS", "DiceThrowEnv", "DiceThrowSB3VecEnv", "DiceThrowVectorEnv",
           "NamedTask", "Throw", "ThrowTask", "make_sb3_env", "make_task"]


def __getattr__(name: str) -> object:
    """The SB3 adapter on first use, so importing dice_env does not import SB3 and torch."""
    if name in ("DiceThrowSB3VecEnv", "make_sb3_env"):
        from dice_env.envs import sb3

        return getattr(sb3, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

"""Training configuration: one dataclass whose field docstrings are the ``--help``.

Per-env-id hyperparameters live in :data:`HYPERPARAMS` (like rl-zoo3's ``hyperparams/ppo.yml``):
a preset name ("quick", "best") maps to PPO keywords, the training budget and the env keywords
used for training. Values given on the command line win over the preset.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import importlib
import inspect
import itertools
import json
import textwrap
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

# PPO for a one-step task (a contextual bandit): every episode ends after one throw, so the
# advantage is the reward minus the value (gamma and lambda do not matter); large batches of
# throws per update, a few epochs, a small initial action noise around the hand-sized throws.
_PPO_COMMON: dict[str, Any] = {
    "n_steps": 8, "batch_size": 512, "n_epochs": 10, "gamma": 0.0, "gae_lambda": 1.0,
    "learning_rate": 1e-4, "clip_range": 0.2, "target_kl": 0.05, "ent_coef": 0.0, "vf_coef": 0.5,
    "max_grad_norm": 0.5,
    "policy_kwargs": {"net_arch": [256, 256], "log_std_init": -2.5,
                      "features_extractor_class": "agents.policy:TargetNormal"},
}

# The task: DiceThrow-v0 with its defaults (any gym.make keyword can be added per preset).
_TASK: dict[str, Any] = {}
# Training only: the dense term n_target . n_table at rest speeds learning; evaluation has none.
_TRAIN = {"shaping": 0.5}
# Warm start: before PPO, the policy's mean imitates the hand-written thrower on this many
# observations for this many gradient steps (0: PPO from scratch). From 5 cm the landing is
# sharp (a 10% error in spin costs about 0.1 of success), so PPO from scratch found no signal
# in 40k throws; from the hand's throws it refines them.
_WARM = {"imitation_throws": 20_000, "imitation_steps": 1500}

HYPERPARAMS: dict[str, dict[str, dict[str, Any]]] = {
    "DiceThrow-v0": {
        "quick": {"total_timesteps": 150_000, "n_envs": 256, "ppo": _PPO_COMMON,
                  "env": _TASK, "train_env": _TRAIN, **_WARM},
        "best": {"total_timesteps": 500_000, "n_envs": 256, "ppo": _PPO_COMMON,
                 "env": _TASK, "train_env": _TRAIN, **_WARM},
    },
}


@dataclass
class Config:
    """Train PPO to throw a die so that a target face lands up, then evaluate it."""

    env_id: str = "DiceThrow-v0"
    """Gymnasium id of the environment (hyperparameters per id in agents/config.py)."""
    preset: str = "quick"
    """Hyperparameter preset: "quick" (the README's default, minutes) or "best" (longer)."""
    seed: int = 0
    """Seed of the policy, the training envs and the evaluation."""
    total_timesteps: int | None = None
    """Throws to train on (None: the preset's)."""
    n_envs: int | None = None
    """Throws simulated together per step, in one kernel call (None: the preset's)."""
    env: list[str] = field(default_factory=list)
    """gym.make keyword for every env (training and evaluation), as KEY=VALUE with a Python
    literal VALUE; repeat the option for several (e.g. --env release_height=0.03)."""
    runs: str = "runs"
    """Folder holding one folder per run."""
    name: str | None = None
    """Run folder name (None: env id, preset, seed and time)."""
    resume: str | None = None
    """Continue the run in this folder from its last checkpoint (its config is reused; a given
    --total-timesteps extends it)."""
    eval_freq: int = 10_000
    """Throws between evaluations during training."""
    eval_episodes: int = 512
    """Throws per evaluation during training."""
    checkpoint_freq: int = 20_000
    """Throws between checkpoints."""
    eval_throws: int = 1000
    """Throws per thrower in the final evaluation."""
    oracle_observations: int = 64
    """Observations searched by the oracle in the final evaluation (each costs 2240 throws)."""
    robustness_throws: int = 400
    """Throws per thrower and setting in the final evaluation's robustness sweeps."""
    gifs: int = 3
    """Throws of the trained policy saved as GIF in the final evaluation."""
    evaluate: bool = True
    """Run the final evaluation and write report.md (--no-evaluate to skip)."""
    progress: bool = True
    """Show a progress bar (--no-progress to hide)."""
    num_threads: int | None = None
    """Threads of the simulation kernel (None: all cores)."""

    def hyperparams(self) -> dict[str, Any]:
        """The preset's hyperparameters for ``env_id``, with this config's overrides applied."""
        try:
            presets = HYPERPARAMS[self.env_id]
        except KeyError:
            raise ValueError(f"env_id must be one of {sorted(HYPERPARAMS)}, "
                             f"got {self.env_id!r}") from None
        if self.preset not in presets:
            raise ValueError(f"preset must be one of {sorted(presets)}, got {self.preset!r}")
        params = json.loads(json.dumps(presets[self.preset]))
        for key in ("total_timesteps", "n_envs"):
            if getattr(self, key) is not None:
                params[key] = getattr(self, key)
        return params

    def ppo_kwargs(self) -> dict[str, Any]:
        """The preset's PPO keywords, ``"module:Name"`` classes in policy_kwargs imported."""
        ppo = self.hyperparams()["ppo"]
        policy = ppo.get("policy_kwargs", {})
        for key, value in policy.items():
            if key.endswith("_class") and isinstance(value, str):
                module, _, name = value.partition(":")
                policy[key] = getattr(importlib.import_module(module), name)
        return ppo

    def env_kwargs(self) -> dict[str, Any]:
        """The preset's env keywords updated by ``--env`` (values parsed as Python literals)."""
        kwargs = dict(self.hyperparams()["env"])
        for item in self.env:
            key, sep, value = item.partition("=")
            if not sep or not key.isidentifier():
                raise ValueError(f"env must be KEY=VALUE, got {item!r}")
            try:
                kwargs[key] = ast.literal_eval(value)
            except (ValueError, SyntaxError):
                kwargs[key] = value  # a bare string such as contact_law=paper
        return kwargs

    def num_threads_kwargs(self) -> dict[str, Any]:
        """``num_threads`` as an env keyword when it is set."""
        return {} if self.num_threads is None else {"num_threads": self.num_threads}

    def save(self, path: Path) -> None:
        """Write the config as JSON."""
        path.write_text(json.dumps(dataclasses.asdict(self), indent=2) + "\n")

    @classmethod
    def load(cls, path: Path) -> Config:
        """Read a config written by :meth:`save`."""
        return cls(**json.loads(Path(path).read_text()))


def field_docs(cls: type) -> dict[str, str]:
    """The docstring under each field of a dataclass, by field name."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    body = tree.body[0].body  # type: ignore[attr-defined]
    docs = {}
    for node, after in itertools.pairwise(body):
        if (isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name)
                and isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant)):
            docs[node.target.id] = " ".join(str(after.value.value).split())
    return docs


def parse_config(argv: list[str] | None = None, prog: str | None = None) -> Config:
    """A :class:`Config` from command-line arguments; ``--help`` lists every field."""
    parser = argparse.ArgumentParser(prog=prog, description=Config.__doc__,
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    docs = field_docs(Config)
    for f in dataclasses.fields(Config):
        flag = "--" + f.name.replace("_", "-")
        default = f.default_factory() if callable(f.default_factory) else f.default
        if f.type == "bool":
            parser.add_argument(flag, default=default, help=docs[f.name],
                                action=argparse.BooleanOptionalAction)
        elif f.type == "list[str]":
            parser.add_argument(flag, default=default, help=docs[f.name], action="append",
                                metavar="KEY=VALUE")
        else:
            kind = int if f.type.startswith("int") else str
            parser.add_argument(flag, default=default, type=kind, help=docs[f.name])
    config = Config(**vars(parser.parse_args(argv)))
    config.hyperparams()  # validate env id and preset now, not after minutes of work
    config.env_kwargs()
    return config

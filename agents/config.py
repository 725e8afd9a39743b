"""Training configuration: one dataclass whose field docstrings are the ``--help``.

The hyperparameters are PPO's entries of :data:`agents.hyperparams.HYPERPARAMS` for the env id
and a preset (:data:`PRESETS`): PPO's keywords, the training budget, the env keywords used for
training and the imitation warm start. Values given on the command line win over the preset.

:func:`parse_config` checks every option before any work and before any folder is made (the env
is built once per setting to check its keywords); a bad value ends with argparse's usage error
naming the option. ``--seeds`` and ``--sweep`` make a group: one run per setting and seed in
the ``--name`` folder (:meth:`Config.members`).
"""

from __future__ import annotations

import argparse
import ast
import copy
import dataclasses
import inspect
import itertools
import json
import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from agents.hyperparams import HYPERPARAMS, algorithm_kwargs
from agents.kept import write_json
from dice_env.envs.throw_task import ThrowTask
from dice_env.model.die import Die

# train.py's presets of PPO in agents.hyperparams.HYPERPARAMS.
PRESETS = ("quick", "best", "scratch")


@dataclass
class Config:
    """Train PPO on a named dice task (a target face, or a total of two dice), then evaluate it."""

    env_id: str = "DiceThrow-v0"
    """Registered task id (dice_env.envs.tasks.TASKS; hyperparameters per id in
    agents/hyperparams.py); --env keywords override the id's."""
    preset: str = "quick"
    """Hyperparameter preset (agents/hyperparams.py): "quick" (the README's default, minutes),
    "best" (longer), or "scratch" (plain MlpPolicy PPO, no imitation warm start)."""
    seed: int = 0
    """Seed of the policy, the training envs and the evaluation (0 to 2**31 - 1)."""
    total_timesteps: int | None = None
    """Throws to train on (None: the preset's), rounded up to whole rollouts."""
    n_envs: int | None = None
    """Throws simulated together per step, in one kernel call (None: the preset's)."""
    env: list[str] = field(default_factory=list)
    """gym.make keyword for every env (training and evaluation), as KEY=VALUE with a Python
    literal VALUE; repeat the option for several (e.g. --env release_height=0.03)."""
    seeds: int = 1
    """Train this many runs, with seeds --seed, --seed + 1, ...; the group's report gives the
    mean and spread over seeds."""
    sweep: list[str] = field(default_factory=list, metadata={"nargs": "+"})
    """Env keywords to sweep, KEY=V1,V2,... (several keywords: every combination), e.g.
    --sweep release_height=0.015,0.03 hand_noise=0.02,0.05; one run per setting (and seed),
    one comparison table."""
    runs: str = "runs"
    """Folder holding one folder per run."""
    name: str | None = None
    """Run folder name, a plain folder name inside --runs (None: env id, preset, seed and time)."""
    overwrite: bool = False
    """Replace the run folder of an existing --name (without it, an existing name is refused)."""
    resume: str | None = None
    """Continue the run (or group) in this folder from its last checkpoint; its config is reused,
    only --total-timesteps (to extend it), --[no-]evaluate and --[no-]progress may be given."""
    eval_freq: int = 10_000
    """Throws between evaluations during training (the learning curve)."""
    eval_episodes: int = 512
    """Throws per evaluation during training."""
    checkpoint_freq: int = 20_000
    """Throws between checkpoints."""
    eval_throws: int = 1000
    """Throws per thrower in the final evaluation."""
    oracle_observations: int = 64
    """Observations searched by the oracle in the final evaluation (0: no oracle)."""
    robustness_throws: int = 400
    """Throws per thrower and setting in the final evaluation's robustness sweeps (0: none)."""
    gifs: int = 4
    """Throws saved as GIF in the final evaluation, failures first (half of them at most)."""
    evaluate: bool = True
    """Run the final evaluation and write report.md (--no-evaluate to skip)."""
    progress: bool = True
    """Show progress bars (--no-progress to hide)."""
    num_threads: int | None = None
    """Threads of the simulation kernel (None: all cores)."""

    def hyperparams(self) -> dict[str, Any]:
        """The preset's entry for ``env_id`` (a fresh copy), with this config's overrides."""
        ids = [e for e, algos in HYPERPARAMS.items() if set(PRESETS) <= set(algos["ppo"])]
        if self.env_id not in ids:
            raise OptionError("env_id", f"must be one of {sorted(ids)}, got {self.env_id!r}")
        if self.preset not in PRESETS:
            raise OptionError("preset", f"must be one of {sorted(PRESETS)}, got {self.preset!r}")
        params = copy.deepcopy(HYPERPARAMS[self.env_id]["ppo"][self.preset])
        if self.total_timesteps is not None:
            params["n_timesteps"] = self.total_timesteps
        if self.n_envs is not None:
            params["n_envs"] = self.n_envs
        return params

    def ppo_kwargs(self, die: Die | None = None) -> dict[str, Any]:
        """The preset's PPO keywords (:func:`agents.hyperparams.algorithm_kwargs`).

        A features extractor that takes ``reading`` (:class:`agents.policy.TargetNormal`) gets
        ``die``'s reading directions unless the preset gives them.
        """
        ppo = algorithm_kwargs(self.hyperparams())
        policy = ppo.get("policy_kwargs", {})
        extractor = policy.get("features_extractor_class")
        if die is not None and extractor is not None and "reading" in inspect.signature(
                extractor).parameters:
            extra = policy.setdefault("features_extractor_kwargs", {})
            extra.setdefault("reading", die.reading.tolist())
        return ppo

    def env_kwargs(self) -> dict[str, Any]:
        """The ``--env`` keywords (values parsed as Python literals)."""
        kwargs = {}
        for item in self.env:
            key, value = _keyword("env", item)
            kwargs[key] = literal(value)
        return kwargs

    def num_threads_kwargs(self) -> dict[str, Any]:
        """``num_threads`` as an env keyword when it is set."""
        return {} if self.num_threads is None else {"num_threads": self.num_threads}

    def sweep_grid(self) -> list[dict[str, Any]]:
        """The settings of ``--sweep``: one dict of env keywords per combination ([{}]: none)."""
        axes = []
        for item in self.sweep:
            key, values = _keyword("sweep", item)
            if key in dict(_keyword("env", e) for e in self.env):
                raise OptionError("sweep", f"{key} is also given by --env; give it in one place")
            if key in (k for k, _ in axes):
                raise OptionError("sweep", f"{key} is given twice")
            if not values:
                raise OptionError("sweep", f"{key} needs values, KEY=V1,V2,..., got {item!r}")
            axes.append((key, [literal(v) for v in values.split(",")]))
        return [dict(zip([k for k, _ in axes], combo, strict=True))
                for combo in itertools.product(*[v for _, v in axes])]

    def is_group(self) -> bool:
        """Whether this config trains several runs (``--seeds`` > 1 or ``--sweep``)."""
        return self.seeds > 1 or bool(self.sweep)

    def members(self) -> list[Config]:
        """One config per setting of the sweep and seed, each a run in the group's folder."""
        members = []
        for setting in self.sweep_grid():
            for seed in range(self.seed, self.seed + self.seeds):
                label = "_".join(f"{k}-{v}" for k, v in setting.items())
                members.append(dataclasses.replace(
                    self, seed=seed, seeds=1, sweep=[], overwrite=False, resume=None,
                    env=[*self.env, *(f"{k}={v!r}" for k, v in setting.items())],
                    runs=str(Path(self.runs) / str(self.name)),
                    name=f"{label + '_' if label else ''}seed{seed}"))
        return members

    def default_name(self) -> str:
        """The run folder's name when ``--name`` is not given."""
        kind = "sweep" if self.sweep else ("seeds" if self.seeds > 1 else "")
        return "_".join(filter(None, [self.env_id, self.preset, kind, f"s{self.seed}",
                                      time.strftime("%Y%m%d-%H%M%S")]))

    def save(self, path: Path) -> None:
        """Write the config as JSON."""
        write_json(path, dataclasses.asdict(self), indent=2)

    @classmethod
    def load(cls, path: Path) -> Config:
        """Read a config written by :meth:`save`."""
        return cls(**json.loads(Path(path).read_text()))


class OptionError(ValueError):
    """A bad value of one option: ``option`` is the Config field, the message its rule."""

    def __init__(self, option: str, message: str) -> None:
        super().__init__(f"{flag(option)}: {message}")
        self.option = option
        self.rule = message


def flag(name: str) -> str:
    """The command-line flag of a Config field (``n_envs`` -> ``--n-envs``)."""
    return "--" + name.replace("_", "-")


def literal(value: str) -> Any:
    """A Python literal, or the bare string (``contact_law=paper``)."""
    try:
        return ast.literal_eval(value)
    except (ValueError, SyntaxError):
        return value


def _keyword(option: str, item: str) -> tuple[str, str]:
    key, sep, value = item.partition("=")
    if not sep or not key.isidentifier():
        raise OptionError(option, f"must be KEY=VALUE, got {item!r}")
    return key, value


# Integer options: (smallest, largest) allowed; None in the config means "the preset's".
_INT_RANGES = {
    "seed": (0, 2**31 - 1), "total_timesteps": (1, None), "n_envs": (1, None), "seeds": (1, None),
    "eval_freq": (1, None), "eval_episodes": (1, None), "checkpoint_freq": (1, None),
    "eval_throws": (1, None), "oracle_observations": (0, None), "robustness_throws": (0, None),
    "gifs": (0, None),
}
# Options that --resume accepts; the rest come from the run's config.json.
RESUME_OPTIONS = ("resume", "total_timesteps", "evaluate", "progress", "runs")


def check(config: Config) -> None:
    """Check every option of ``config``; the first bad one raises :class:`OptionError`.

    Nothing is created: the env is built (and closed) once per setting to check its keywords,
    the run folder is only looked at.
    """
    for key, (low, high) in _INT_RANGES.items():
        value = getattr(config, key)
        if value is None:
            continue
        if high is None and value < low:
            raise OptionError(key, f"must be an integer >= {low}, got {value}")
        if high is not None and not low <= value <= high:
            raise OptionError(key, f"must be an integer in [{low}, {high}], got {value}")
    if config.num_threads is not None:
        from dice_env.simulation.simulate import thread_count

        try:
            thread_count(config.num_threads)
        except ValueError as error:
            raise OptionError("num_threads", str(error).removeprefix("num_threads ")) from None
    if config.resume is not None:
        _check_resume(config)
        return
    config.hyperparams()
    config.ppo_kwargs()
    for setting in config.sweep_grid():
        check_env(config, setting)
    _check_name(config)


def check_env(config: Config, setting: dict[str, Any] | None = None) -> None:
    """Build the run's training and evaluation envs once (keywords checked), then close them."""
    import gymnasium as gym

    import dice_env  # noqa: F401  (registers DiceThrow-v0)

    option = "sweep" if setting else "env"
    kwargs = {**config.env_kwargs(), **(setting or {}), **config.num_threads_kwargs()}
    for extra in ({}, config.hyperparams()["env_kwargs"]):
        try:
            env = gym.make(config.env_id, **{**kwargs, **extra})
        except (ValueError, TypeError) as error:
            raise OptionError(option, str(error)) from None
        task = env.unwrapped.task
        env.close()
        _check_preset_fits(config, option, task)


def _check_preset_fits(config: Config, option: str, task: ThrowTask) -> None:
    """Refuse a preset that imitates a rule the task has not, or that is built for one die."""
    from agents.baselines import task_rule

    params = config.hyperparams()
    extractor = params.get("policy_kwargs", {}).get("features_extractor_class")
    pair = str(extractor).endswith(":PairNormal")
    if task.n_dice > 1 and extractor is not None and not pair:
        raise OptionError(option, f"num_dice={task.n_dice}: preset {config.preset!r} gives the "
                          "policy the target face's direction (TargetNormal), built for one die; "
                          "use --preset scratch (plain MlpPolicy PPO) for several dice")
    if pair and (task.n_dice != 2 or task.target != "sum" or task.set_dice):
        raise OptionError(option, f"num_dice={task.n_dice}, target={task.target!r}: preset "
                          f"{config.preset!r} gives the policy the direction of the pair of "
                          "faces making a total of two dice (PairNormal); use --preset scratch")
    if params.get("imitation_steps") and task_rule(task) is None:
        raise OptionError(option, f"num_dice={task.n_dice}, target={task.target!r}: preset "
                          f"{config.preset!r} warm-starts by imitating the task's rule, and this "
                          "throw has none (a rule: one die, or two set dice); use --preset "
                          "scratch (plain MlpPolicy PPO)")


def _check_name(config: Config) -> None:
    if config.name is not None and (Path(config.name).name != config.name
                                    or config.name in ("", ".", "..")):
        raise OptionError("name", f"must be a plain folder name (no '/', not '.' or '..'), "
                          f"got {config.name!r}")
    run = Path(config.runs) / (config.name or config.default_name())
    if run.exists() and not config.overwrite:
        raise OptionError("name", f"{run} exists: pass --overwrite to replace it, "
                          f"--resume {run} to continue it, or another --name")
    if run.exists() and not is_run_folder(run):
        raise OptionError("overwrite", f"{run} is not a run folder (no config.json): "
                          "it is not removed; choose another --name")


def is_run_folder(path: Path) -> bool:
    """Whether ``path`` is a folder made by train.py (a run or a group)."""
    return (path / "config.json").is_file()


def _check_resume(config: Config) -> None:
    run = Path(str(config.resume))
    if not is_run_folder(run):
        raise OptionError("resume", f"{run} is not a run folder (no config.json)")
    try:
        Config.load(run / "config.json")
    except (OSError, ValueError, TypeError) as error:  # not JSON, or not train.py's options
        raise OptionError("resume", f"{run / 'config.json'} is not a run's config "
                          f"({type(error).__name__}: {error})") from None
    defaults = Config()
    given = [f.name for f in dataclasses.fields(Config)
             if f.name not in RESUME_OPTIONS and getattr(config, f.name) != getattr(defaults,
                                                                                    f.name)]
    if given:
        raise OptionError("resume", f"takes the run's options from {run / 'config.json'}; "
                          f"{', '.join(flag(g) for g in given)} cannot be changed (only "
                          "--total-timesteps, --[no-]evaluate, --[no-]progress)")


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
    """A checked :class:`Config` from command-line arguments; ``--help`` lists every field.

    A bad value exits with argparse's usage error (status 2) naming the option, before any work.
    """
    parser = argparse.ArgumentParser(prog=prog, description=Config.__doc__,
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    docs = field_docs(Config)
    for f in dataclasses.fields(Config):
        default = f.default_factory() if callable(f.default_factory) else f.default
        if f.type == "bool":
            parser.add_argument(flag(f.name), default=default, help=docs[f.name],
                                action=argparse.BooleanOptionalAction)
        elif f.type == "list[str]":
            nargs = f.metadata.get("nargs")
            parser.add_argument(flag(f.name), default=default, help=docs[f.name],
                                action="extend" if nargs else "append", nargs=nargs,
                                metavar="KEY=VALUE")
        else:
            kind = int if f.type.startswith("int") else str
            parser.add_argument(flag(f.name), default=default, type=kind, help=docs[f.name])
    config = Config(**vars(parser.parse_args(argv)))
    try:
        check(config)
    except OptionError as error:
        parser.error(f"argument {error}")
    return config

r"""rl-zoo3 files of the benchmark's entries in :data:`agents.hyperparams.HYPERPARAMS`.

    python -m agents.zoo              # rewrites agents/zoo_configs/{ppo,a2c,sac,td3}.yml
    python -m agents.zoo --check      # exit 1 if a file differs from the table

The files are rl-zoo3's format (keyed by env id, one entry per named task; ``policy_kwargs`` as
the Python expression rl-zoo3 evaluates; TD3's exploration as ``noise_type``/``noise_std``),
with the benchmark's budgets (``python -m agents.benchmark``), so a user trains and replays a
benchmark run with rl-zoo3's own commands::

    python -m rl_zoo3.train --algo sac --env DiceThrowD20-v0 --gym-packages dice_env \
        --conf-file agents/zoo_configs/sac.yml -f logs
    python -m rl_zoo3.enjoy --algo sac --env DiceThrowD20-v0 --gym-packages dice_env -f logs \
        --no-render -n 1000

rl-zoo3 steps ``n_envs`` separate Gymnasium envs (one throw per env per step) where the
benchmark steps them as one batched kernel call; the policy and hyperparameters are the same.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import yaml

from agents.hyperparams import ALGOS, HYPERPARAMS, entry
from agents.kept import write_text

ZOO = Path(__file__).resolve().parent / "zoo_configs"
HEADER = "# Written by `python -m agents.zoo` from agents/hyperparams.py; do not edit by hand.\n"


def _python(value: Any) -> str:
    """``value`` as the Python literal rl-zoo3 evaluates for ``policy_kwargs``."""
    if isinstance(value, dict):
        return "dict(" + ", ".join(f"{k}={_python(v)}" for k, v in value.items()) + ")"
    return repr(value)


def zoo_entry(params: dict[str, Any]) -> dict[str, Any]:
    """One env's rl-zoo3 hyperparameters from its table entry."""
    out = dict(params)
    out["n_timesteps"] = float(params["n_timesteps"])
    if "policy_kwargs" in params:
        out["policy_kwargs"] = _python(params["policy_kwargs"])
    return out


def zoo_yaml(algo: str) -> str:
    """The text of ``agents/zoo_configs/<algo>.yml``."""
    table = {env_id: zoo_entry(entry(env_id, algo)) for env_id in HYPERPARAMS}
    return HEADER + yaml.safe_dump(table, sort_keys=False)


def main(argv: list[str] | None = None) -> int:
    """Write ``agents/zoo_configs/*.yml``, or with ``--check`` report whether they are current."""
    texts = {ZOO / f"{algo}.yml": zoo_yaml(algo) for algo in ALGOS}
    parser = argparse.ArgumentParser(prog="python -m agents.zoo",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="change nothing; exit 1 if a file differs from the table")
    if parser.parse_args(argv).check:
        stale = [path for path, text in texts.items()
                 if not path.exists() or path.read_text() != text]
        for path in stale:
            print(f"{path} differs from agents/hyperparams.py (python -m agents.zoo)")
        return 1 if stale else 0
    ZOO.mkdir(exist_ok=True)
    for path, text in texts.items():
        write_text(path, text)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Expert iteration: distil the oracle's searched actions into a trained policy, search again.

    python train.py --env-id DiceThrowD20-v0 --seed 0 --name d20_s0 --no-evaluate
    python -m agents.expert runs/d20_s0 --name d20_s0_expert   # label, clone, evaluate

From a trained ``train.py`` run, each of ``--iterations`` rounds (DAgger-style):

1. **label**: ``--observations`` fresh observations, drawn as the env draws them (their own
   seed, apart from the evaluation's), each labelled with the oracle's searched action
   (:func:`agents.oracle.search` with :data:`LABEL_CEM`, a cheaper search than the
   evaluation's) started from the current policy's action and the task's rule; where the search
   finds nothing better on its validation draws, the label is the policy's own action;
2. **clone**: the policy's mean action is fitted to every label gathered so far and to its own
   current actions on ``--anchors`` fresh observations (which keep it where no label says
   otherwise), MSE, Adam, ``--steps`` batches of 256, starting from the current policy;

then the new policy labels the next round's observations (the search starts from it). The
result is a run folder of its own (``--runs``/``--name``): the source's config (same task,
seed and evaluation), its learning curve, ``model.zip``, ``training.jsonl`` with the source's
sessions and one more whose ``throws`` add the throws the searches simulated and whose CPU
seconds are the labelling's and the cloning's, and ``expert.json`` (the settings, per round
the labels' success against the policy's on the search's validation draws); then the same
evaluation as ``train.py`` (:func:`agents.evaluate.evaluate_run`). ``python -m agents.recipe``
keeps such runs as their own rows. Single-threaded with ``--num-threads 1`` and
``--torch-threads 1``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import argparse
import shutil
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from agents.config import Config, is_run_folder
from agents.kept import RunError, read_sessions, write_json, write_saved, write_sessions
from agents.oracle import CEM, search

# The labelling search: one restart from the best start, fewer candidates and draws than the
# evaluation's oracle (agents.oracle.CEM()), so that a thousand labels cost minutes.
LABEL_CEM = CEM(global_candidates=16, restarts=1, iterations=3, population=16, noise_samples=8,
                finalists=2, validation_samples=32, chunk=32)
SEARCHES = {"label": LABEL_CEM, "oracle": CEM()}
LABEL_SEED = 4 * 10**6  # offset of the labels' observations from the run's seed


def label(task: Any, model: Any, n: int, rng: np.random.Generator, cem: CEM,
          episode: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` observations, the policy's actions and the search's labels for them."""
    from agents.episodes import Batch, PolicyThrower

    batch = Batch.sample(task, n, rng, **episode)
    own = np.asarray(PolicyThrower(model)(batch.observations), np.float64)
    labels = search(task, batch.observations, rng, cem, starts={"policy": own})
    return batch.observations, own, labels


def clone(model: Any, observations: np.ndarray, labels: np.ndarray, steps: int, lr: float,
          seed: int, batch: int = 256) -> float:
    """Fit the policy's mean action to ``labels`` (MSE) in place; the last batch's loss."""
    import torch

    obs = torch.as_tensor(observations, dtype=torch.float32)
    target = torch.as_tensor(labels, dtype=torch.float32)
    policy = model.policy
    policy.set_training_mode(True)
    optimizer = torch.optim.Adam(policy.parameters(), lr=lr)
    generator = torch.Generator().manual_seed(seed)
    loss = torch.zeros(())
    for _ in range(steps):
        idx = torch.randint(0, len(obs), (min(batch, len(obs)),), generator=generator)
        mean = policy.get_distribution(obs[idx]).distribution.mean
        loss = torch.nn.functional.mse_loss(mean, target[idx])
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
    policy.set_training_mode(False)
    return float(loss.item())


def expert_iteration(source: Path, out: Path, observations: int, iterations: int, steps: int,
                     lr: float, anchors: int = 0, cem: CEM = LABEL_CEM, evaluate: bool = True,
                     progress: bool = False) -> dict[str, Any]:
    """Label, clone and (``evaluate``) evaluate; the run folder ``out`` holds the result."""
    import torch
    from stable_baselines3 import PPO

    from agents.episodes import Batch, PolicyThrower, make_eval_task
    from agents.oracle import score, score_noise

    config = Config.load(source / "config.json")
    sessions = read_sessions(source)
    out.mkdir(parents=True)
    config.name, config.runs = out.name, str(out.parent)
    config.save(out / "config.json")
    shutil.copy(source / "hyperparams.json", out / "hyperparams.json")
    if (source / "eval").exists():
        shutil.copytree(source / "eval", out / "eval")
    model = PPO.load(source / "model.zip", device="cpu")
    task, episode = make_eval_task(config)
    rng = np.random.default_rng(config.seed + LABEL_SEED)
    start, cpu = time.perf_counter(), time.process_time()
    all_obs: list[np.ndarray] = []
    all_labels: list[np.ndarray] = []
    rounds = []
    for k in range(iterations):
        t0 = time.perf_counter()
        obs, own, labels = label(task, model, observations, rng, cem, episode)
        noise = score_noise(task, rng, len(obs), 8)
        own_rate = float(score(task, obs, own, noise).mean())
        label_rate = float(score(task, obs, labels, noise).mean())
        all_obs.append(obs)
        all_labels.append(labels)
        # Anchors: the current policy's own actions on fresh observations, so that the
        # cloning moves the policy where the labels say and keeps it elsewhere.
        anchor, anchor_actions = obs[:0], labels[:0]
        if anchors:
            anchor = Batch.sample(task, anchors, rng, **episode).observations
            anchor_actions = np.asarray(PolicyThrower(model)(anchor), np.float64)
        loss = clone(model, np.concatenate([*all_obs, anchor]),
                     np.concatenate([*all_labels, anchor_actions]), steps, lr, config.seed + k)
        moved = float(np.mean(np.linalg.norm(labels - own, axis=1) > 1e-9))
        rounds.append({"observations": len(obs), "labels_moved": moved,
                       "policy_on_fresh_draws": own_rate, "labels_on_fresh_draws": label_rate,
                       "clone_loss": loss, "seconds": time.perf_counter() - t0})
        print(f"round {k + 1}/{iterations}: {len(obs)} labels ({moved:.0%} moved from the "
              f"policy's action); on 8 fresh draws each: policy {own_rate:.3f}, labels "
              f"{label_rate:.3f}; clone MSE {loss:.2e}", flush=True)
    starts = 2 if task.n_dice == 1 else 1  # the policy, and the hand-written thrower for one die
    searched = iterations * observations * cem.throws_per_observation(starts)
    scored = iterations * observations * 8 * 2
    model.num_timesteps = sessions[-1]["throws"]
    write_saved(out / "model.zip", model.save)
    session = {"throws": sessions[-1]["throws"] + searched + scored,
               "seconds": time.perf_counter() - start,
               "cpu_seconds": time.process_time() - cpu, "interrupted": False,
               "stage": "expert iteration"}
    write_sessions(out, [*sessions, session])
    info = {"source": source.name, "iterations": iterations, "observations": observations,
            "anchors": anchors, "steps": steps, "lr": lr, "cem": asdict(cem),
            "label_seed": LABEL_SEED,
            "simulated_throws": searched + scored, "rounds": rounds,
            "torch_threads": torch.get_num_threads(),
            "command": "python -m agents.expert SOURCE " + " ".join(
                f"--{k} {v}" for k, v in (("observations", observations),
                                          ("iterations", iterations), ("anchors", anchors),
                                          ("steps", steps), ("lr", lr)))
            + ("" if cem == LABEL_CEM else " --search oracle" if cem == CEM() else
               " (a search of its own: see cem)")}
    write_json(out / "expert.json", info, indent=2)
    print(f"expert iteration: {session['cpu_seconds']:.0f} CPU s, {searched + scored:,} "
          f"throws simulated; wrote {out}", flush=True)
    if evaluate:
        from agents.evaluate import evaluate_run

        evaluate_run(out, progress=progress)
    return info


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: ``python -m agents.expert SOURCE --name NAME``."""
    parser = argparse.ArgumentParser(prog="python -m agents.expert", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("source", type=Path, help="a trained train.py run (with model.zip)")
    parser.add_argument("--name", required=True, help="the new run's folder name")
    parser.add_argument("--runs", type=Path, default=None,
                        help="folder of the new run (default: the source's)")
    parser.add_argument("--observations", type=int, default=1000,
                        help="observations labelled per round (default 1000)")
    parser.add_argument("--iterations", type=int, default=1, help="rounds (default 1)")
    parser.add_argument("--anchors", type=int, default=2000,
                        help="fresh observations per round whose target is the policy's own "
                             "action (default 2000)")
    parser.add_argument("--steps", type=int, default=500,
                        help="cloning steps per round, batches of 256 (default 500)")
    parser.add_argument("--lr", type=float, default=3e-4, help="cloning's Adam rate")
    parser.add_argument("--search", choices=sorted(SEARCHES), default="label",
                        help="the labelling search: 'label' (LABEL_CEM, default) or 'oracle' "
                             "(the evaluation's oracle, CEM(): about 7 times the throws)")
    parser.add_argument("--torch-threads", type=int, default=None, help="PyTorch's threads")
    parser.add_argument("--no-evaluate", dest="evaluate", action="store_false",
                        help="skip the evaluation")
    args = parser.parse_args(argv)
    if args.anchors < 0:
        parser.error(f"argument --anchors: must be >= 0, got {args.anchors}")
    for key in ("observations", "iterations", "steps"):
        if getattr(args, key) < 1:
            parser.error(f"argument --{key}: must be >= 1, got {getattr(args, key)}")
    if not is_run_folder(args.source) or not (args.source / "model.zip").exists():
        parser.error(f"argument source: {args.source} is not a trained train.py run")
    out = (args.runs or args.source.parent) / args.name
    if out.exists():
        parser.error(f"argument --name: {out} exists")
    if args.torch_threads:
        import torch

        torch.set_num_threads(args.torch_threads)
    try:
        expert_iteration(args.source, out, args.observations, args.iterations, args.steps,
                         args.lr, args.anchors, SEARCHES[args.search], evaluate=args.evaluate)
    except RunError as error:
        parser.error(str(error))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""A features extractor that hands the policy the target face's direction in the world.

The observation holds the target as a one-hot and the die's orientation R as 9 numbers; the
direction the throw must turn toward the table normal is the target's reading direction in the
world, ``n = R r_target`` (its outward normal; minus it for the d4, read face down), a product
of the two that a plain MLP has to discover from many throws. The extractor computes it (the
rest of the observation passes through unchanged). In a trial released 2 cm above the table,
PPO with it passed 0.6 success after 20k throws; a plain MLP was still at chance (0.18) after
30k. It adds no knowledge of the physics.
"""

from __future__ import annotations

from collections.abc import Sequence

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor

from agents.baselines import ROTATION_DIM, n_faces
from dice_env.model.die import STANDARD_SIZES, Die


class TargetNormal(BaseFeaturesExtractor):
    """Features (n, size + 3): the observation and the target's reading direction in the world.

    Sized from the observation space: the one-hot before the 3x3 orientation has one entry per
    face. ``reading`` (faces, 3): the die's body-frame reading directions in label order
    (:attr:`dice_env.Die.reading`; ``train.py`` passes the task's); None: those of the standard
    die with that many faces (a cuboid's are the d6's).
    """

    def __init__(self, observation_space: gym.spaces.Box,
                 reading: Sequence[Sequence[float]] | None = None) -> None:
        size = observation_space.shape[0]
        super().__init__(observation_space, features_dim=size + 3)
        self.faces = n_faces(size)
        if reading is None:
            name = f"d{self.faces}"
            if name not in STANDARD_SIZES:
                raise ValueError(f"observation space of size {size} has a one-hot of "
                                 f"{self.faces} faces, no standard die's: pass reading (the "
                                 "die's Die.reading) in features_extractor_kwargs")
            reading = Die.standard(name).reading
        reading = np.asarray(reading, dtype=np.float32)
        if reading.shape != (self.faces, 3):
            raise ValueError(f"reading must have shape ({self.faces}, 3) for an observation "
                             f"space of size {size}, got {reading.shape}")
        self.register_buffer("normals", torch.as_tensor(reading))

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        """Append ``R @ n_body(target)``, with the one-hot weighting the body normals."""
        faces = self.faces
        body_normal = observations[:, :faces] @ self.normals  # (n, 3), the target's body normal
        rotation = observations[:, faces:faces + ROTATION_DIM].reshape(-1, 3, 3)
        world_normal = torch.einsum("nij,nj->ni", rotation, body_normal)
        return torch.cat([observations, world_normal], dim=1)


class PairNormal(BaseFeaturesExtractor):
    """Features (n, size + 3): two dice thrown for a total, and the direction to spin up.

    The tray's rule (:class:`agents.baselines.TotalThrower`) spins up the mean world direction
    of the pair of faces that makes the target total and whose directions lie closest together;
    that direction is a discontinuous function of the observation (an argmax over the pairs)
    that a plain MLP fits poorly (imitating the rule, it kept about half of the rule's success).
    This extractor computes it, as :class:`TargetNormal` computes one die's target direction;
    the policy then learns the throw as a smooth function of it. The observation: the total's
    one-hot (one column per total from 2), then each die's 3x3 orientation. ``reading``
    (faces, 3): each die's body-frame reading directions (both dice alike; None: the d6's).
    """

    def __init__(self, observation_space: gym.spaces.Box,
                 reading: Sequence[Sequence[float]] | None = None) -> None:
        size = observation_space.shape[0]
        super().__init__(observation_space, features_dim=size + 3)
        reading = np.asarray(Die.standard("d6").reading if reading is None else reading,
                             dtype=np.float32)
        faces = len(reading)
        self.totals = size - 2 * ROTATION_DIM
        if reading.shape != (faces, 3) or self.totals != 2 * faces - 1:
            raise ValueError(f"an observation of size {size} is not a total of two dice of "
                             f"{faces} faces (one-hot of {2 * faces - 1} totals, two 3x3 "
                             "orientations)")
        labels = np.arange(1, faces + 1)
        makes = (labels[None, :, None] + labels[None, None, :]
                 == np.arange(2, 2 * faces + 1)[:, None, None])  # (totals, faces, faces)
        self.register_buffer("normals", torch.as_tensor(reading))
        self.register_buffer("makes", torch.as_tensor(makes.reshape(self.totals, -1),
                                                      dtype=torch.float32))

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        """Append the unit mean direction of the closest pair of faces making the total."""
        n, t = len(observations), self.totals
        first, second = (torch.einsum(
            "nij,fj->nfi", observations[:, t + k * ROTATION_DIM:t + (k + 1) * ROTATION_DIM]
            .reshape(-1, 3, 3), self.normals) for k in (0, 1))
        cosine = torch.einsum("nai,nbi->nab", first, second).reshape(n, -1)
        allowed = observations[:, :t] @ self.makes > 0.5
        best = torch.where(allowed, cosine, torch.full_like(cosine, -torch.inf)).argmax(dim=1)
        faces = first.shape[1]
        rows = torch.arange(n)
        mean = first[rows, best // faces] + second[rows, best % faces]
        norm = mean.norm(dim=1, keepdim=True)
        normal = torch.where(norm > 1e-6, mean / norm.clamp_min(1e-12), first[rows, best // faces])
        return torch.cat([observations, normal], dim=1)

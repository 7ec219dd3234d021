"""The segmenter's data loader: each training step's batch of examples, built in order, optionally by
worker processes ahead of the step that needs it.

A step's batch is a pure function of ``(scenes, config, seed, step)``: the scenes it trains on and
their crops, augmentations and voxels all come from ``numpy.random.default_rng([seed, step])``
(:func:`build_batch`). Workers therefore change when a batch is built, never what it holds: a run
with ``workers=0`` (built in the training process) and one with ``workers=N`` see byte-identical
batches, and a run resumed at step ``k`` sees the batches an uninterrupted run would.

The loader is :class:`assist3d.learn.loader.StepLoader`, the learning side's one loader. Workers are
``torch.utils.data.DataLoader`` worker processes (example building is numpy and scipy
code that holds the GIL for much of its time, so threads would not overlap it). The loader asks for
steps in order and hands batches back in that order, with ``prefetch`` batches per worker in flight,
so memory stays bounded whatever the budget. On a 2-core machine one worker overlaps example
building with the network's step; on a GPU machine with many cores, more workers keep the GPU fed.
"""

from __future__ import annotations

from functools import partial
from typing import Sequence

import numpy as np

from ...core.errors import ConfigError
from ..loader import MAX_WORKERS, StepLoader  # noqa: F401  MAX_WORKERS: the bound, named here since the start
from .config import SegmenterConfig
from .data import Example, Scene, make_example


def mix_probabilities(sizes: Sequence[int], weights: Sequence[float]) -> np.ndarray:
    """Per-scene draw probabilities of training sets of ``sizes`` scenes pooled in that order, each set's
    scenes drawn ``weight`` times as often as a scene of weight 1. A set's share of the draws is then
    ``weight x scenes / sum``: sampling with weight ``alpha`` gives a set's examples the expected share
    of the loss that scaling its loss by ``alpha`` gives (the paper's real + alpha x synthetic)."""
    if len(sizes) != len(weights):
        raise ConfigError(f"{len(weights)} weights for {len(sizes)} training sets: give one per set")
    w = np.asarray(weights, np.float64)
    if not np.all(np.isfinite(w)) or (w < 0).any():
        raise ConfigError(f"training set weights {list(weights)}: expected finite numbers >= 0")
    per_scene = np.repeat(w, np.asarray(sizes, np.int64))
    if per_scene.sum() <= 0:
        raise ConfigError(f"training set weights {list(weights)}: no scene can be drawn (every weight 0)")
    return per_scene / per_scene.sum()


def build_batch(scenes: Sequence[Scene], cfg: SegmenterConfig, seed: int, step: int,
                probs: np.ndarray | None = None) -> list[Example]:
    """The examples of training step ``step``: ``batch_size`` scenes drawn with replacement (uniformly,
    or with the per-scene ``probs`` of :func:`mix_probabilities`), each cropped, augmented and
    voxelised with the step's own random stream."""
    rng = np.random.default_rng([seed, step])
    if probs is None:
        picks = rng.integers(len(scenes), size=cfg.optim.batch_size)
    else:
        picks = rng.choice(len(scenes), size=cfg.optim.batch_size, p=probs)
    return [make_example(scenes[int(i)], cfg, rng) for i in picks]


class BatchLoader(StepLoader[list[Example]]):
    """The segmenter's batches of steps ``start, start + 1, ...`` in order (:func:`build_batch`); use as a
    context manager. ``workers=0`` builds each batch when it is asked for; ``workers=N`` has ``N`` processes
    build up to ``prefetch`` batches each ahead of the training step."""

    def __init__(self, scenes: Sequence[Scene], cfg: SegmenterConfig, seed: int, start: int = 0, *,
                 workers: int = 0, prefetch: int = 2, probs: np.ndarray | None = None):
        if not scenes:
            raise ConfigError("no training scenes")
        if probs is not None and len(probs) != len(scenes):
            raise ConfigError(f"{len(probs)} draw probabilities for {len(scenes)} training scenes")
        super().__init__(partial(build_batch, list(scenes), cfg, seed, probs=probs), start, workers=workers,
                         prefetch=prefetch)

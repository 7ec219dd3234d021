"""Training scenes: reader specs -> prepared (augmented, voxelised) scenes with ground-truth masks."""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ...core.contracts import PointSample
from ...data import open_dataset
from ...core.errors import ConfigError
from .augment import augment_points
from .config import AugmentConfig, DataSpec
from .voxelize import VoxelScene, instance_masks, voxelize

log = logging.getLogger(__name__)


def open_spec(spec: str):
    """Open ``FORMAT:PATH`` through the readers of :mod:`assist3d.data`."""
    return open_dataset(spec)


@dataclass(frozen=True)
class SceneRef:
    """One training scene: dataset position, index inside it, and whether it is synthetic."""

    dataset: int
    index: int
    synthetic: bool


class SceneSource:
    """All training scenes of a list of :class:`DataSpec`, optionally cached in memory."""

    def __init__(self, specs: list[DataSpec], cache: bool = True):
        if not specs:
            raise ConfigError("no training data: give --data FORMAT:PATH or list data.train in the config")
        self.datasets = [open_spec(s.spec) for s in specs]
        self.refs: list[SceneRef] = []
        for d, (spec, ds) in enumerate(zip(specs, self.datasets)):
            synthetic = spec.resolved_kind() == "synthetic"
            if len(ds) == 0:
                raise ConfigError(f"{spec.spec}: the dataset holds no scenes")
            self.refs += [SceneRef(d, i, synthetic) for i in range(len(ds))]
        self.cache = cache
        self._cache: dict[int, PointSample] = {}

    def __len__(self) -> int:
        return len(self.refs)

    def sample(self, i: int) -> PointSample:
        if i in self._cache:
            return self._cache[i]
        ref = self.refs[i]
        s = self.datasets[ref.dataset][ref.index]
        if self.cache:
            self._cache[i] = s
        return s


def crop_points(coord: np.ndarray, max_points: int, *, rng: np.random.Generator) -> np.ndarray:
    """Row indices of the ``max_points`` points nearest (in x, y) to a random point; all rows if fewer."""
    n = len(coord)
    if max_points <= 0 or n <= max_points:
        return np.arange(n)
    centre = coord[rng.integers(n), :2]
    d = ((coord[:, :2] - centre) ** 2).sum(1)
    return np.sort(np.argpartition(d, max_points - 1)[:max_points])


def prepare_scene(sample: PointSample, voxel_size: float, augment: AugmentConfig | None, max_points: int, *,
                  rng: np.random.Generator) -> tuple[VoxelScene, np.ndarray]:
    """Crop, augment and voxelise one scene; returns the voxels and GT masks ``(G, V) bool``."""
    rows = crop_points(sample.coord, max_points, rng=rng)
    coord, color = sample.coord[rows], sample.color[rows]
    instance = np.where(sample.valid[rows], sample.instance[rows], -1)
    if augment is not None and augment.enabled:
        coord, color = augment_points(coord, color, augment, rng=rng)
    vox = voxelize(coord, color, instance, voxel_size)
    masks, _ = instance_masks(vox.instance)
    return vox, masks

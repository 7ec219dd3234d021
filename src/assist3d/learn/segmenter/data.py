"""Training examples for the segmenter: crop, augment, voxelise, features and per-voxel targets.

Every training scene, generated or real, goes through the same steps; the augmentations model what
differs between a rendered scene and a real reconstruction (experiments/fidelity-log.md): point density (a
random fraction of the points is kept), floors that are neither flat nor at z = 0 (tilt, height
shift), sensor noise (jitter), and the usual rotation, mirror and scale.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core.contracts import PointSample
from ..engine.augment import rotation_matrix
from .config import AugmentConfig, SegmenterConfig
from .features import Voxels, voxel_features, voxelize


@dataclass(frozen=True)
class Example:
    """One voxelised scene: ``coords`` (V, 3) int32, ``feats`` (V, C) float32, ``fg`` (V,) float32
    (1 = object), ``offset`` (V, 3) float32 metres from the voxel centre to its instance's centre."""

    coords: np.ndarray
    feats: np.ndarray
    fg: np.ndarray
    offset: np.ndarray


@dataclass(frozen=True)
class Scene:
    """The arrays a training scene needs (compact enough to keep many in memory)."""

    coord: np.ndarray  # (N, 3) float32
    color: np.ndarray  # (N, 3) uint8
    instance: np.ndarray  # (N,) int32, -1 = background or void

    @classmethod
    def from_sample(cls, s: PointSample) -> "Scene":
        inst = np.where(s.valid, s.instance, -1).astype(np.int32)
        return cls(coord=np.asarray(s.coord, np.float32), color=np.asarray(s.color, np.uint8), instance=inst)


def augment(scene: Scene, cfg: AugmentConfig, rng: np.random.Generator) -> Scene:
    """A randomly cropped, thinned, moved and noised copy of ``scene``."""
    xyz = scene.coord.astype(np.float64)
    rows = np.arange(len(xyz))
    if cfg.crop_m > 0:
        lo, hi = xyz[:, :2].min(0), xyz[:, :2].max(0)
        half = cfg.crop_m / 2
        # centre of a window that stays inside the scene (or the scene's middle when it is smaller);
        # written as low + span * u so rounding can never make the span negative
        low = np.minimum(lo + half, (lo + hi) / 2)
        span = np.maximum(np.maximum(hi - half, (lo + hi) / 2) - low, 0.0)
        centre = low + span * np.array([rng.random(), rng.random()])
        inside = np.all(np.abs(xyz[:, :2] - centre) <= half, axis=1)
        rows = rows[inside]
    keep = rng.uniform(cfg.keep_min, max(cfg.keep_min, cfg.keep_max))
    rows = rows[rng.random(len(rows)) < keep]
    if len(rows) < 10:  # a degenerate crop: fall back to the whole scene
        rows = np.arange(len(xyz))
    xyz = xyz[rows]
    xyz[:, :2] -= xyz[:, :2].mean(0)
    if rng.random() < 0.5:
        xyz[:, 0] = -xyz[:, 0]
    t = np.deg2rad(cfg.tilt_deg)
    xyz = xyz @ rotation_matrix(rng.uniform(-t, t), rng.uniform(-t, t), rng.uniform(-np.pi, np.pi)).T
    xyz *= rng.uniform(1 - cfg.scale, 1 + cfg.scale)
    xyz[:, 2] += rng.uniform(*cfg.floor_shift)
    xyz += rng.normal(0.0, rng.uniform(*cfg.jitter), xyz.shape)
    color = scene.color[rows].astype(np.float64)
    if cfg.color_drop > 0 and rng.random() < cfg.color_drop:
        color = np.repeat(color.mean(1, keepdims=True), 3, 1)
    if cfg.color_jitter > 0:
        mean = color.mean()
        color = (color - mean) * (1 + rng.uniform(-cfg.color_jitter, cfg.color_jitter)) + mean
        color += rng.uniform(-cfg.color_jitter, cfg.color_jitter) * 255
    return Scene(coord=xyz.astype(np.float32), color=np.clip(color, 0, 255).astype(np.uint8),
                 instance=scene.instance[rows])


def targets(vox: Voxels) -> tuple[np.ndarray, np.ndarray]:
    """Foreground (V,) float32 and offset to the instance's voxel-centre mean (V, 3) float32 (0 on background)."""
    inst = vox.instance
    fg = inst >= 0
    offset = np.zeros((len(vox), 3), np.float32)
    if fg.any():
        ids, local = np.unique(inst[fg], return_inverse=True)
        cnt = np.bincount(local, minlength=len(ids)).astype(np.float64)
        centre = np.stack([np.bincount(local, weights=vox.centres[fg, a], minlength=len(ids)) for a in range(3)], 1)
        centre /= cnt[:, None]
        offset[fg] = (centre[local] - vox.centres[fg]).astype(np.float32)
    return fg.astype(np.float32), offset


def make_example(scene: Scene, cfg: SegmenterConfig, rng: np.random.Generator | None) -> Example:
    """Voxelise ``scene`` (augmented when ``rng`` is given) into an :class:`Example`."""
    s = augment(scene, cfg.augment, rng) if rng is not None else scene
    vox = voxelize(s.coord, cfg.net.voxel_size, s.color, s.instance)
    feats = voxel_features(vox, use_color=cfg.net.use_color)
    fg, offset = targets(vox)
    return Example(coords=vox.coords, feats=feats, fg=fg, offset=offset)

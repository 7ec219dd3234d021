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
from ..transforms import (CropSquare, Centre, ColorDrop, ColorJitter, Compose, Jitter, Mirror, Points, Rotate,
                          Scale, ShiftZ, Thin)
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
    """A randomly cropped, thinned, moved and noised copy of ``scene`` (the segmenter's recipe of
    :mod:`assist3d.learn.transforms`)."""
    whole = Points.of(scene.coord, scene.color)
    recipe = Compose([
        CropSquare(cfg.crop_m), Thin(cfg.keep_min, cfg.keep_max, fallback=whole), Centre(xy_only=True),
        Mirror((0,)), Rotate(np.deg2rad(cfg.tilt_deg), np.deg2rad(cfg.tilt_deg), np.pi), Scale(cfg.scale),
        ShiftZ(*cfg.floor_shift), Jitter(*cfg.jitter), ColorDrop(cfg.color_drop), ColorJitter(cfg.color_jitter),
    ])
    p = recipe(whole, rng)
    return Scene(coord=p.coord.astype(np.float32), color=p.colors_u8(), instance=scene.instance[p.rows])


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

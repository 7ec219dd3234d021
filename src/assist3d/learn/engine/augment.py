"""Mask3D's training augmentations on point clouds (numpy, explicit generator).

Order: centre + random offset; mirror x and y (p 0.5 each); elastic distortion per (granularity,
magnitude) pair with probability ``elastic_p``; per-axis scale; rotation about z (full turn) and small
rotations about x and y; brightness/contrast jitter and RGB shift. Every parameter comes from
:class:`assist3d.learn.engine.config.AugmentConfig`.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import RegularGridInterpolator
from scipy.ndimage import gaussian_filter

from ..transforms import (Centre, ColorJitter, ColorShift, Compose, Elastic, Mirror, Points, Rotate, Scale,
                          rotation_matrix)  # noqa: F401  rotation_matrix: the name this module exported
from .config import AugmentConfig


def elastic_distortion(xyz: np.ndarray, granularity: float, magnitude: float, *,
                       rng: np.random.Generator) -> np.ndarray:
    """Displace ``xyz`` (N, 3) metres by a smooth random field sampled on a ``granularity`` m grid."""
    lo = xyz.min(0) - granularity * 2
    hi = xyz.max(0) + granularity * 2
    shape = np.maximum(np.ceil((hi - lo) / granularity).astype(int) + 1, 2)
    axes = [lo[i] + granularity * np.arange(shape[i]) for i in range(3)]
    field = rng.standard_normal((*shape, 3)).astype(np.float64)
    for c in range(3):
        field[..., c] = gaussian_filter(field[..., c], sigma=1.0, mode="nearest")
    interp = RegularGridInterpolator(axes, field, bounds_error=False, fill_value=0.0)
    return (xyz + interp(xyz) * magnitude).astype(xyz.dtype)


def augment_points(coord: np.ndarray, color: np.ndarray, cfg: AugmentConfig, *,
                   rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Augmented copies of ``coord`` (N, 3) float32 metres and ``color`` (N, 3) uint8 (Mask3D's recipe of
    :mod:`assist3d.learn.transforms`)."""
    recipe = Compose([
        Centre(offset=cfg.offset_m), *([Mirror((0, 1))] if cfg.mirror else []),
        Elastic(tuple(tuple(pair) for pair in cfg.elastic), cfg.elastic_p, elastic_distortion),
        Scale(cfg.scale, per_axis=True), Rotate(cfg.rotate_xy_rad, cfg.rotate_xy_rad, cfg.rotate_z_rad),
        ColorJitter(cfg.color_jitter), ColorShift(cfg.rgb_shift),
    ])
    p = recipe(Points.of(coord, color), rng)
    return p.coord.astype(np.float32), p.colors_u8()

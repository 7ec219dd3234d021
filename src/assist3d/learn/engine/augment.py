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


def rotation_matrix(ax: float, ay: float, az: float) -> np.ndarray:
    """``Rz @ Ry @ Rx`` for angles in radians about x, y and z."""
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def augment_points(coord: np.ndarray, color: np.ndarray, cfg: AugmentConfig, *,
                   rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Augmented copies of ``coord`` (N, 3) float32 metres and ``color`` (N, 3) uint8."""
    xyz = coord.astype(np.float64)
    xyz = xyz - xyz.mean(0) + rng.uniform(-cfg.offset_m, cfg.offset_m, 3)
    for axis in (0, 1):
        if cfg.mirror and rng.random() < 0.5:
            xyz[:, axis] = -xyz[:, axis]
    if cfg.elastic and rng.random() < cfg.elastic_p:
        for gran, mag in cfg.elastic:
            xyz = elastic_distortion(xyz, gran, mag, rng=rng)
    xyz = xyz * rng.uniform(1 - cfg.scale, 1 + cfg.scale, 3)
    rot = rotation_matrix(rng.uniform(-cfg.rotate_xy_rad, cfg.rotate_xy_rad),
                    rng.uniform(-cfg.rotate_xy_rad, cfg.rotate_xy_rad),
                    rng.uniform(-cfg.rotate_z_rad, cfg.rotate_z_rad))
    xyz = xyz @ rot.T
    rgb = color.astype(np.float64)
    if cfg.color_jitter > 0:
        mean = rgb.mean()
        contrast = 1 + rng.uniform(-cfg.color_jitter, cfg.color_jitter)
        brightness = rng.uniform(-cfg.color_jitter, cfg.color_jitter) * 255
        rgb = (rgb - mean) * contrast + mean + brightness
    if cfg.rgb_shift > 0:
        rgb = rgb + rng.uniform(-cfg.rgb_shift, cfg.rgb_shift, 3)
    return xyz.astype(np.float32), np.clip(rgb, 0, 255).astype(np.uint8)

"""Depth-sensor realism, applied to each rendered view before fusion (all off by default).

* ``max_range``: hits deeper than this are lost.
* ``depth_noise``: Gaussian depth noise with std ``depth_noise * depth^2`` (structured-light
  sensors' error grows with the square of the distance), moving the point along its ray.
* ``grazing_dropout_deg``: surfaces seen at more than this angle from their normal return nothing.
* ``edge_dropout``: pixels next to a depth jump larger than this (or next to a miss) are lost.
* ``color_jitter``: a per-view brightness gain ``1 + N(0, color_jitter)`` (auto-exposure).
"""

from __future__ import annotations

import math

import numpy as np

from ..config import RenderConfig
from ..core.contracts import SceneMesh
from .rgbd import face_normals

__all__ = ["sensor_enabled", "apply_depth_sensor", "view_gains"]


def sensor_enabled(cfg: RenderConfig) -> bool:
    """Whether any per-view depth realism option is on."""
    return (cfg.max_range is not None or cfg.depth_noise > 0 or cfg.grazing_dropout_deg is not None
            or cfg.edge_dropout > 0)


def apply_depth_sensor(scene: SceneMesh, t: np.ndarray, face: np.ndarray, dirs: np.ndarray, width: int,
                       height: int, cfg: RenderConfig, *, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """New (t, face) of one view with the depth realism options applied; dropped pixels get
    face -1 and t inf. t (H*W,) float32 is the depth (rays have camera z = 1); face (H*W,) int32."""
    t = t.copy()
    face = face.copy()
    hit = face >= 0
    if cfg.max_range is not None:
        hit &= t <= np.float32(cfg.max_range)
    if cfg.edge_dropout > 0:
        d = np.where(hit, t, np.float32(np.inf)).reshape(height, width)
        jump = np.zeros((height, width), bool)
        with np.errstate(invalid="ignore"):
            dx = np.abs(d[:, 1:] - d[:, :-1])
            dy = np.abs(d[1:, :] - d[:-1, :])
        ex = ~(dx <= cfg.edge_dropout)  # NaN/inf differences (misses) count as edges
        ey = ~(dy <= cfg.edge_dropout)
        jump[:, 1:] |= ex
        jump[:, :-1] |= ex
        jump[1:, :] |= ey
        jump[:-1, :] |= ey
        hit &= ~jump.reshape(-1)
    if cfg.grazing_dropout_deg is not None:
        idx = np.flatnonzero(hit)
        n = face_normals(scene, face[idx])
        rd = dirs[idx] / np.linalg.norm(dirs[idx], axis=1, keepdims=True)
        cos = np.abs(np.einsum("ij,ij->i", n, rd))
        hit[idx[cos < math.cos(math.radians(cfg.grazing_dropout_deg))]] = False
    # noise is drawn for every pixel so the stream does not depend on which pixels were dropped
    noise = rng.standard_normal(len(t), dtype=np.float32) if cfg.depth_noise > 0 else None
    if noise is not None:
        with np.errstate(invalid="ignore", over="ignore"):
            t = t + np.float32(cfg.depth_noise) * t * t * noise
        hit &= t > 0
    face[~hit] = -1
    t[~hit] = np.inf
    return t, face


def view_gains(n_views: int, cfg: RenderConfig, *, rng: np.random.Generator) -> np.ndarray | None:
    """(n_views,) float32 brightness gains, or None when colour jitter is off."""
    if cfg.color_jitter <= 0:
        return None
    return np.clip(1.0 + cfg.color_jitter * rng.standard_normal(n_views), 0.2, 3.0).astype(np.float32)

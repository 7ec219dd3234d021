"""Pinhole cameras: intrinsics from :class:`RenderConfig`, poses at vantage points, ray bundles.

Camera frame is OpenCV's (x right, y down, z forward); ``Camera.pose`` maps camera to world.
Ray directions are *unnormalised* with a camera-frame z of 1, so a hit's ray parameter ``t`` is
directly the depth along the optical axis.
"""

from __future__ import annotations

import math

import numpy as np

from ..config import RenderConfig
from ..core.contracts import Camera

__all__ = ["intrinsics", "look_pose", "vantage_cameras", "pixel_directions", "rotate_directions", "world_directions"]


def intrinsics(cfg: RenderConfig) -> tuple[int, int, float, float, float, float]:
    """``(width, height, fx, fy, cx, cy)``; the principal point defaults to the image centre."""
    cx = (cfg.width - 1) / 2.0 if cfg.cx is None else float(cfg.cx)
    cy = (cfg.height - 1) / 2.0 if cfg.cy is None else float(cfg.cy)
    return cfg.width, cfg.height, float(cfg.fx), float(cfg.fy), cx, cy


def look_pose(center: np.ndarray, yaw: float, pitch: float = 0.0) -> np.ndarray:
    """(4, 4) float64 camera-to-world pose at ``center`` looking along ``yaw`` (radians from +x,
    counter-clockwise) and ``pitch`` (radians, positive looks up), with no roll."""
    cp, sp = math.cos(pitch), math.sin(pitch)
    forward = np.array([cp * math.cos(yaw), cp * math.sin(yaw), sp])
    right = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
    down = np.cross(forward, right)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2] = right, down, forward
    pose[:3, 3] = np.asarray(center, dtype=np.float64)
    return pose


def vantage_cameras(centers: np.ndarray, cfg: RenderConfig) -> list[Camera]:
    """``views_per_point`` cameras per centre, yaw steps of 360 / views_per_point degrees; view k
    of a centre is pitched by ``pitch_deg[k % len(pitch_deg)]``.

    centers: (K, 3) float64. Views are ordered centre by centre, yaw by yaw.
    """
    w, h, fx, fy, cx, cy = intrinsics(cfg)
    pitches = [math.radians(p) for p in (cfg.pitch_deg if isinstance(cfg.pitch_deg, list) else [cfg.pitch_deg])]
    if not pitches:
        pitches = [0.0]
    step = 2.0 * math.pi / cfg.views_per_point
    return [
        Camera(w, h, fx, fy, cx, cy, look_pose(c, k * step, pitches[k % len(pitches)]))
        for c in np.asarray(centers, dtype=np.float64)
        for k in range(cfg.views_per_point)
    ]


def pixel_directions(width: int, height: int, fx: float, fy: float, cx: float, cy: float) -> np.ndarray:
    """(H*W, 3) float64 camera-frame ray directions through pixel centres, z = 1, row-major."""
    u = (np.arange(width, dtype=np.float64) - cx) / fx
    v = (np.arange(height, dtype=np.float64) - cy) / fy
    d = np.zeros((height, width, 3))
    d[..., 0] = u[None, :]
    d[..., 1] = v[:, None]
    d[..., 2] = 1.0
    return d.reshape(-1, 3)


def rotate_directions(cam_dirs: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """(N, 3) float32 world directions of camera-frame directions (N, 3) under ``pose`` (4, 4).

    A float32 BLAS product: broadcasting with an inner dimension of 3 is ~10x slower. Keep BLAS
    single-threaded around it (threadpoolctl) when rendering from several threads.
    """
    d = np.ascontiguousarray(cam_dirs, dtype=np.float32)
    out = np.zeros_like(d)
    np.dot(d, pose[:3, :3].T.astype(np.float32), out=out)
    return out


def world_directions(camera: Camera, cam_dirs: np.ndarray) -> np.ndarray:
    """(N, 3) float32 world ray directions of camera-frame directions ``cam_dirs`` (N, 3)."""
    return rotate_directions(cam_dirs, camera.pose)

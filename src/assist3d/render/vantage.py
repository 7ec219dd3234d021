"""Vantage points: where the virtual scanner stands (paper: 'Realistic Point Cloud Construction').

The camera plane (mid-height of the room, or ``camera_height``) is gridded at ``vantage_cell``;
cells outside the room, closer than ``vantage_clearance`` to a wall, or closer than that to the
bounding box of an object that spans the camera height are dropped; ``vantage_points`` cells are
then picked by farthest point sampling from a seeded start cell.
"""

from __future__ import annotations

import logging

import fpsample
import numpy as np
import shapely

from ..config import RenderConfig
from ..core.contracts import Room, SceneMesh
from ..core.errors import RenderError

log = logging.getLogger(__name__)

__all__ = ["instance_boxes", "candidate_cells", "select_vantage_points", "camera_height"]

_MAX_CELLS = 2_000_000  # budget on the candidate grid (a 140 x 140 m room at 10 cm)


def camera_height(room: Room, cfg: RenderConfig) -> float:
    """Height of the camera plane, metres."""
    return float(cfg.camera_height) if cfg.camera_height is not None else room.height / 2.0


def instance_boxes(scene: SceneMesh) -> tuple[np.ndarray, np.ndarray]:
    """World axis-aligned boxes of every instance.

    Returns ``ids`` (M,) int32 (sorted instance ids >= 0) and ``boxes`` (M, 2, 3) float32
    (min corner, max corner).
    """
    inst = scene.face_instance
    keep = np.flatnonzero(inst >= 0)
    if len(keep) == 0:
        return np.zeros(0, np.int32), np.zeros((0, 2, 3), np.float32)
    order = keep[np.argsort(inst[keep], kind="stable")]
    tri = scene.vertices[scene.faces[order]]  # (n, 3, 3)
    fmin, fmax = tri.min(axis=1), tri.max(axis=1)
    ids_sorted = inst[order]
    starts = np.flatnonzero(np.r_[True, ids_sorted[1:] != ids_sorted[:-1]])
    boxes = np.stack([np.minimum.reduceat(fmin, starts), np.maximum.reduceat(fmax, starts)], axis=1)
    return ids_sorted[starts].astype(np.int32), boxes.astype(np.float32)


def candidate_cells(scene: SceneMesh, room: Room, cfg: RenderConfig, clearance: float) -> np.ndarray:
    """(n, 2) float64 centres of free grid cells on the camera plane for ``clearance`` metres."""
    poly = shapely.Polygon(room.polygon)
    if not poly.is_valid or poly.area <= 0:
        raise RenderError(f"room polygon is not a valid simple polygon: {room.polygon}")
    x0, y0, x1, y1 = poly.bounds
    cell = cfg.vantage_cell
    nx, ny = int(np.ceil((x1 - x0) / cell)), int(np.ceil((y1 - y0) / cell))
    if nx * ny > _MAX_CELLS:
        raise RenderError(f"vantage grid of {nx} x {ny} cells exceeds {_MAX_CELLS}; raise render.vantage_cell")
    gx = x0 + (np.arange(nx) + 0.5) * cell
    gy = y0 + (np.arange(ny) + 0.5) * cell
    xy = np.stack(np.meshgrid(gx, gy, indexing="xy"), axis=-1).reshape(-1, 2)
    inner = poly.buffer(-clearance, join_style="mitre") if clearance > 0 else poly
    if inner.is_empty:
        return np.zeros((0, 2))
    ok = shapely.contains_xy(inner, xy[:, 0], xy[:, 1])
    xy = xy[ok]
    z = camera_height(room, cfg)
    _, boxes = instance_boxes(scene)
    if len(boxes) and len(xy):
        spans = (boxes[:, 0, 2] - clearance <= z) & (boxes[:, 1, 2] + clearance >= z)
        for lo, hi in boxes[spans][:, :, :2].astype(np.float64):  # loop over objects, not points
            inside = np.all((xy > lo - clearance) & (xy < hi + clearance), axis=1)
            xy = xy[~inside]
    return xy


def select_vantage_points(scene: SceneMesh, room: Room, cfg: RenderConfig, *, rng: np.random.Generator) -> np.ndarray:
    """(K, 3) float64 camera centres, K = ``cfg.vantage_points`` unless fewer free cells exist.

    Deterministic for a given generator state. If no cell keeps the configured clearance it is
    halved (up to three times, then zero); a room with no free cell at all raises RenderError.
    """
    clearance = cfg.vantage_clearance
    for attempt in range(5):
        xy = candidate_cells(scene, room, cfg, clearance)
        if len(xy):
            break
        log.warning("vantage points: no free cell at clearance %.3f m; relaxing", clearance)
        clearance = clearance / 2.0 if attempt < 3 else 0.0
    else:
        raise RenderError("vantage points: no free cell on the camera plane (the room is full)")
    k = min(cfg.vantage_points, len(xy))
    if k < cfg.vantage_points:
        log.warning("vantage points: only %d free cells for %d requested", k, cfg.vantage_points)
    start = int(rng.integers(len(xy)))
    idx = fpsample.fps_sampling(np.ascontiguousarray(xy, dtype=np.float64), k, start_idx=start) if k > 1 else np.array([start])
    z = camera_height(room, cfg)
    return np.column_stack([xy[np.asarray(idx, dtype=np.int64)], np.full(k, z)])

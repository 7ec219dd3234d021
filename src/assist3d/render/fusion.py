"""Fusion of rendered RGB-D views into one voxel-downsampled, labelled point cloud.

Each view is ray-cast and immediately reduced to one point per 2 cm voxel (one pseudo-random
pixel per voxel) inside the worker thread that cast it, so at most a few full-resolution views
exist at any time; the union of the per-view picks is then reduced once more. Colour, normal and
labels come from the triangle each kept ray hit, so they are exact and cost nothing per raw ray.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from threadpoolctl import threadpool_limits

from ..config import RenderConfig
from ..core.contracts import Camera, SceneMesh
from .budget import cast_adaptive, face_planes, sky_box
from .camera import pixel_directions, rotate_directions
from .raycast import RayCaster, make_caster
from .sensor import apply_depth_sensor, sensor_enabled
from .voxel import VoxelGrid, pick_one_per_voxel, pick_one_per_voxel_scan

log = logging.getLogger(__name__)

__all__ = ["FusedHits", "ViewSink", "cast_and_fuse", "footprint_spacing", "scene_grid"]


class ViewSink(Protocol):
    """Extra per-view work riding on :func:`cast_and_fuse`'s ray casting (e.g. TSDF integration).

    ``view`` runs in the worker thread that cast view ``index``: t (H*W,) float32 depth (inf =
    miss), face (H*W,) int32 (-1 = miss), dirs (H*W, 3) float32 world ray directions (camera
    z = 1), after the depth-sensor options. ``add`` then receives its result in the calling
    thread, view by view in view order, whatever the thread count.
    """

    def view(self, index: int, camera: Camera, t: np.ndarray, face: np.ndarray, dirs: np.ndarray) -> Any: ...

    def add(self, index: int, part: Any) -> None: ...


@dataclass(frozen=True)
class FusedHits:
    """One kept ray hit per occupied voxel, sorted by voxel.

    coord (N, 3) float32 world hit points; face (N,) int32 hit triangles; view (N,) int32 index of
    the view that saw the point; pixel_counts (I,) int64 rendered pixels per instance id
    (index = id; background not counted); raw_hits total hits over all views.
    """

    coord: np.ndarray
    face: np.ndarray
    view: np.ndarray
    pixel_counts: np.ndarray
    raw_hits: int
    seconds_cast: float
    seconds_merge: float
    rays_cast: int = 0


def footprint_spacing(cfg: RenderConfig, sink: ViewSink | None = None) -> float | None:
    """The sampling distance (m) of ``render.rays = "footprint"``, or None where views are rendered whole:
    another ray mode, or depth-sensor options / a view sink (TSDF), which need every pixel."""
    if cfg.rays != "footprint" or sink is not None or sensor_enabled(cfg):
        return None
    return float(cfg.ray_spacing) * float(cfg.voxel_size)


def scene_grid(scene: SceneMesh, voxel_size: float) -> VoxelGrid:
    """The voxel grid around the scene's bounding box."""
    return VoxelGrid.around(scene.vertices.min(axis=0), scene.vertices.max(axis=0), voxel_size)


def _ordered_map(pool: ThreadPoolExecutor | None, fn: Callable[[int], Any], n: int, window: int) -> Iterator[Any]:
    """``fn(0), ..., fn(n - 1)`` in order, at most ``window`` of them pending at once (so results
    a slow consumer has not taken yet do not pile up); serial without a pool."""
    if pool is None:
        yield from (fn(i) for i in range(n))
        return
    pending: deque[Future] = deque()
    nxt = 0
    while nxt < n or pending:
        while nxt < n and len(pending) < window:
            pending.append(pool.submit(fn, nxt))
            nxt += 1
        yield pending.popleft().result()


def cast_and_fuse(scene: SceneMesh, caster: RayCaster, cameras: list[Camera], cfg: RenderConfig, *,
                  rng: np.random.Generator, sink: ViewSink | None = None) -> FusedHits:
    """Cast every camera's rays (``cfg.threads`` threads), de-duplicate per view, then merge.

    All cameras must share one intrinsics. Deterministic for a generator state, whatever the
    thread count. ``sink`` (optional) sees every view's depth as well (see :class:`ViewSink`).
    """
    if not cameras:
        return FusedHits(np.zeros((0, 3), np.float32), np.zeros(0, np.int32), np.zeros(0, np.int32),
                         np.zeros(0, np.int64), 0, 0.0, 0.0)
    c0 = cameras[0]
    cam_dirs = pixel_directions(c0.width, c0.height, c0.fx, c0.fy, c0.cx, c0.cy).astype(np.float32)
    grid = scene_grid(scene, cfg.voxel_size)
    n_ids = int(scene.face_instance.max(initial=-1)) + 2  # slot 0 = background, slot i + 1 = instance i
    # per triangle its count slot (background -> 0); one more slot at the end, which face -1 (a miss) indexes
    inst_of_face = np.append((scene.face_instance + 1).astype(np.int32), np.int32(n_ids))
    salts = rng.integers(1, 2**62, size=len(cameras) + 1)
    sensor_seeds = rng.integers(0, 2**63, size=len(cameras))
    realism = sensor_enabled(cfg)
    planes = sky = None
    if cfg.rays != "full":  # misses are cast again against a sky box (budget.py): flat tiles too
        planes = face_planes(scene, sky=True)
        sky = make_caster(cfg.backend, *sky_box(scene))
    spacing = footprint_spacing(cfg, sink)

    def one_view(i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, Any, int]:
        cam = cameras[i]
        dirs = rotate_directions(cam_dirs, cam.pose)
        center = cam.pose[:3, 3].astype(np.float32)
        if planes is not None:
            t, face, n_cast = cast_adaptive(caster, planes, cam, dirs, cfg.ray_tile, sky, spacing)
        else:
            origins = np.zeros_like(dirs)
            for j in range(3):
                origins[:, j] = center[j]
            t, face = caster.cast(origins, dirs)
            n_cast = len(t)
        if realism:
            t, face = apply_depth_sensor(scene, t, face, dirs, cam.width, cam.height, cfg,
                                         rng=np.random.default_rng(int(sensor_seeds[i])))
        extra = None if sink is None else sink.view(i, cam, t, face, dirs)
        pix = np.flatnonzero(face >= 0)
        counts = np.bincount(np.take(inst_of_face, face), minlength=n_ids + 1)[:n_ids]  # a miss (-1) -> slot n_ids
        tp = np.take(t, pix)
        # the hit points column by column ((N, 3) broadcasts are slow), keyed as they come (the same
        # float32 operations as grid.keys on the (N, 3) points); only the kept rows are gathered
        cols = []
        for j in range(3):
            col = np.take(dirs[:, j], pix)
            col *= tp
            col += center[j]
            cols.append(col)
        keys = grid.keys_of_columns(cols)
        keep = pick_one_per_voxel_scan(keys, int(salts[i]))
        pts = np.empty((len(keep), 3), np.float32)
        for j in range(3):
            np.take(cols[j], keep, out=pts[:, j])
        return np.take(keys, keep), pts, np.take(face, np.take(pix, keep)), counts, len(pix), extra, n_cast

    def run(pool: ThreadPoolExecutor | None) -> list[tuple]:
        out = []
        for i, part in enumerate(_ordered_map(pool, one_view, len(cameras), 2 * cfg.threads)):
            if sink is not None:
                sink.add(i, part[5])
            out.append(part[:5] + part[6:])
        return out

    t0 = time.perf_counter()
    with threadpool_limits(limits=1):
        if cfg.threads > 1 and len(cameras) > 1:
            with ThreadPoolExecutor(max_workers=cfg.threads, thread_name_prefix="raycast") as pool:
                parts = run(pool)
        else:
            parts = run(None)
    t1 = time.perf_counter()
    keys = np.concatenate([p[0] for p in parts])
    coord = np.concatenate([p[1] for p in parts])
    face = np.concatenate([p[2] for p in parts])
    view = np.repeat(np.arange(len(parts), dtype=np.int32), [len(p[0]) for p in parts])
    counts = np.sum([p[3] for p in parts], axis=0)
    raw = int(sum(p[4] for p in parts))
    rays_cast = int(sum(p[5] for p in parts))
    del parts
    keep = pick_one_per_voxel(keys, int(salts[-1]))
    out = FusedHits(coord[keep], face[keep], view[keep], counts[1:],
                    raw, t1 - t0, time.perf_counter() - t1, rays_cast)
    log.debug("fusion: %d raw hits -> %d per-view picks -> %d points", raw, len(keys), len(keep))
    return out

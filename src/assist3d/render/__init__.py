"""Realistic point-cloud construction (paper: 'Realistic Point Cloud Construction').

Facade: :func:`build_point_cloud` turns an assembled scene into a labelled point cloud by
picking vantage points, ray-casting RGB-D views and fusing them (or, for the ablation baseline,
by uniform surface sampling at matching density, or, ScanNet-like, by TSDF fusion of the same views
and marching cubes, see :mod:`.tsdf`). :func:`render_point_cloud` returns the same
cloud with the vantage points and per-instance visibility that :func:`verify_labels` checks.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from ..config import RenderConfig
from ..core.contracts import PointSample, Room, SceneMesh
from .camera import vantage_cameras
from .fusion import FusedHits, cast_and_fuse, footprint_spacing, scene_grid
from .meshsample import nearest_instance, sample_surface
from .raycast import BACKENDS, RayCaster, make_caster
from .rgbd import face_normals, oriented_normals, render_view, shade
from .sensor import view_gains
from .tsdf import TsdfIntegrator, require_marching_cubes, tsdf_cloud
from .vantage import select_vantage_points
from .verify import LabelCheck, verify_labels

log = logging.getLogger(__name__)

__all__ = ["RenderResult", "build_point_cloud", "render_point_cloud", "make_caster", "render_view",
           "select_vantage_points", "vantage_cameras", "verify_labels", "LabelCheck", "BACKENDS"]


@dataclass(frozen=True)
class RenderResult:
    """A labelled cloud plus what produced it.

    centers (K, 3) float64 vantage points; pixel_counts (I,) int64 rendered pixels per instance id;
    timings {"render": s, "fuse": s}; stats: views, raw hits, point source...
    """

    sample: PointSample
    centers: np.ndarray
    pixel_counts: np.ndarray
    timings: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)


def _segment_of_instance(scene: SceneMesh, instance: np.ndarray) -> np.ndarray:
    """(N,) int32 class index of each point's instance (-1 for -1)."""
    ids = scene.face_instance
    table = np.full(int(ids.max(initial=-1)) + 2, -1, np.int32)
    obj = ids >= 0
    table[ids[obj] + 1] = scene.face_segment[obj]
    return table[instance + 1]


def render_point_cloud(scene: SceneMesh, room: Room, cfg: RenderConfig, *, rng: np.random.Generator,
                       scene_id: str = "", caster: RayCaster | None = None) -> RenderResult:
    """Vantage points -> RGB-D views -> fused, labelled cloud (see module docs)."""
    rng_vantage, rng_fuse, rng_attr, rng_mesh = rng.spawn(4)
    t0 = time.perf_counter()
    centers = select_vantage_points(scene, room, cfg, rng=rng_vantage)
    cameras = vantage_cameras(centers, cfg)
    if caster is None:
        caster = make_caster(cfg.backend, scene.vertices, scene.faces)
    t_bvh = time.perf_counter() - t0
    integrator = marching_cubes = None
    if cfg.point_source == "tsdf":
        marching_cubes = require_marching_cubes()  # fail before the expensive part
        if cameras:
            integrator = TsdfIntegrator(scene, cameras[0], cfg, salt=int(rng_mesh.integers(1, 2**62)))
    hits: FusedHits = cast_and_fuse(scene, caster, cameras, cfg, rng=rng_fuse, sink=integrator)
    t1 = time.perf_counter()
    rendered_points = len(hits.coord)
    extra: dict = {}
    if cfg.point_source == "mesh":
        coord, face = sample_surface(scene, scene_grid(scene, cfg.voxel_size), rendered_points, rng=rng_mesh)
        normal = face_normals(scene, face)
        color = shade(scene.face_colors[face], np.ones(len(face), np.float32), False)
    else:
        coord, face, view = hits.coord, hits.face, hits.view
        if integrator is not None and marching_cubes is not None:
            cloud = tsdf_cloud(scene, integrator, cfg, marching_cubes, salt=int(rng_mesh.integers(1, 2**62)))
            coord, face, view, extra = cloud.coord, cloud.face, cloud.view, cloud.stats
        elif cfg.point_source == "tsdf":  # no cameras: nothing seen
            coord, face, view = coord[:0], face[:0], view[:0]
        centers_per_view = np.asarray([c.pose[:3, 3] for c in cameras], dtype=np.float32).reshape(-1, 3)
        normal, cos = oriented_normals(face_normals(scene, face), coord - centers_per_view[view])
        gains = view_gains(len(cameras), cfg, rng=rng_attr)
        color = shade(scene.face_colors[face], cos, cfg.shading, None if gains is None else gains[view])
    if cfg.labels == "nearest":
        instance = nearest_instance(scene, coord, radius=cfg.nearest_radius, spacing=cfg.voxel_size / 2,
                                    rng=rng_attr)
        segment = _segment_of_instance(scene, instance)
    else:
        instance = scene.face_instance[face]
        segment = scene.face_segment[face]
    sample = PointSample(scene_id, np.ascontiguousarray(coord, np.float32), np.ascontiguousarray(color, np.uint8),
                         np.ascontiguousarray(normal, np.float32), np.ascontiguousarray(instance, np.int32),
                         np.ascontiguousarray(segment, np.int32), np.ones(len(coord), bool))
    t2 = time.perf_counter()
    timings = {"render": round(t_bvh + hits.seconds_cast, 4), "fuse": round(hits.seconds_merge + (t2 - t1), 4)}
    stats = {"views": len(cameras), "vantage_points": len(centers), "rays": len(cameras) * cfg.width * cfg.height,
             "raw_hits": hits.raw_hits, "rendered_points": rendered_points, "points": len(sample),
             "point_source": cfg.point_source, "labels": cfg.labels, "backend": cfg.backend, **extra}
    if cfg.rays != "full":  # the full render's record stays as it was
        spacing = footprint_spacing(cfg, integrator)
        stats.update(ray_budget="adaptive" if spacing is None else "footprint", ray_tile=cfg.ray_tile,
                     rays_cast=hits.rays_cast)
        if spacing is not None:
            stats.update(ray_spacing=cfg.ray_spacing)
    log.debug("render %s: %s", scene_id, stats)
    return RenderResult(sample, centers, hits.pixel_counts, timings, stats)


def build_point_cloud(scene: SceneMesh, room: Room, cfg: RenderConfig, *,
                      rng: np.random.Generator) -> tuple[PointSample, dict]:
    """The labelled point cloud of ``scene`` and its timings ``{"render": s, "fuse": s}``."""
    res = render_point_cloud(scene, room, cfg, rng=rng)
    return res.sample, dict(res.timings)

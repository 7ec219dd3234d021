"""The non-learned reference: remove the room's planes (floor, walls, ceiling) found by RANSAC, then
take connected components of what is left (points closer than 6 cm are linked).

It is the baseline row of every table in experiments/fidelity-log.md, and ``assist3d segment --method
geometric``. It works on 2 cm voxel centres, so its cost and behaviour do not depend on the scan's
point density.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cluster import point_masks, radius_components
from .features import floor_height, voxelize
from .infer import Segmentation


@dataclass(frozen=True)
class GeometricConfig:
    voxel_size: float = 0.02
    plane_distance: float = 0.04  # inlier distance to a plane, metres
    min_plane_fraction: float = 0.03  # a structural plane holds at least this share of the voxels
    max_planes: int = 12
    ransac_iterations: int = 300
    link_radius: float = 0.06  # connected components
    min_voxels: int = 30
    seed: int = 0
    refine: int = 0  # least-squares refits of each RANSAC plane to its inliers (0 = the triplet's plane)


WALL_BEHIND = 0.15


def _fit_plane(p: np.ndarray) -> tuple[np.ndarray, float] | None:
    n = np.cross(p[1] - p[0], p[2] - p[0])
    norm = np.linalg.norm(n)
    if norm < 1e-9:
        return None
    n = n / norm
    return n, -float(n @ p[0])


def _refit_plane(p: np.ndarray, n_prev: np.ndarray) -> tuple[np.ndarray, float]:
    """The least-squares plane (PCA) of points ``p`` (K >= 3, 3), its normal on the side of ``n_prev``."""
    c = p.mean(0)
    n = np.linalg.eigh(np.cov((p - c).T))[1][:, 0]
    if n @ n_prev < 0:
        n = -n
    return n, -float(n @ c)


def _structural(n: np.ndarray, d: float, xyz: np.ndarray, inliers: np.ndarray, floor_z: float, top_z: float) -> bool:
    """Floor or ceiling (horizontal, at the bottom or top of the scan) or wall (vertical, nothing much behind it)."""
    if abs(n[2]) > 0.95:
        z = float(np.median(xyz[inliers, 2]))
        return z < floor_z + 0.2 or z > top_z - 0.3
    if abs(n[2]) < 0.1:
        side = xyz @ n + d
        # a wall has most of the scan on one side of it (what lies behind is seen through doors and
        # windows) and is tall
        z = xyz[inliers, 2]
        behind = min(float((side > 0.1).mean()), float((side < -0.1).mean()))
        return behind < WALL_BEHIND and float(np.percentile(z, 95) - np.percentile(z, 5)) > 1.0
    return False


def remove_planes(xyz: np.ndarray, cfg: GeometricConfig, rng: np.random.Generator) -> np.ndarray:
    """Boolean mask (V,) of the points on floor, wall and ceiling planes."""
    v = len(xyz)
    removed = np.zeros(v, bool)
    if v < 3:
        return removed
    floor_z, top_z = floor_height(xyz), float(np.percentile(xyz[:, 2], 99.5))
    remaining = np.arange(v)
    rejected = 0
    for _ in range(cfg.max_planes + 8):
        if len(remaining) < 3 or rejected >= 8:
            break
        pts = xyz[remaining]
        best, best_count = None, 0
        for _ in range(cfg.ransac_iterations):
            fit = _fit_plane(pts[rng.choice(len(pts), 3, replace=False)])
            if fit is None:
                continue
            n, d = fit
            count = int((np.abs(pts @ n + d) < cfg.plane_distance).sum())
            if count > best_count:
                best, best_count = fit, count
        if best is None or best_count < cfg.min_plane_fraction * v:
            break
        n, d = best
        inl = np.abs(pts @ n + d) < cfg.plane_distance
        for _ in range(cfg.refine):  # the plane of all its inliers, not of the three points that won
            n2, d2 = _refit_plane(pts[inl], n)
            inl2 = np.abs(pts @ n2 + d2) < cfg.plane_distance
            if inl2.sum() < max(3, cfg.min_plane_fraction * v):  # a refit that loses the plane keeps the last one
                break
            n, d, inl = n2, d2, inl2
        if _structural(n, d, xyz, remaining[inl], floor_z, top_z):
            removed[remaining[inl]] = True
        else:
            rejected += 1
        remaining = remaining[~inl]
    return removed


def structural_points(coord: np.ndarray, cfg: GeometricConfig = GeometricConfig()) -> np.ndarray:
    """(N,) bool: the points of ``coord`` (N, 3) on the room's structural planes (floor, walls,
    ceiling), as :func:`segment_geometric` removes them (RANSAC on 2 cm voxel centres)."""
    vox = voxelize(np.asarray(coord, np.float32), cfg.voxel_size)
    return remove_planes(vox.centres, cfg, np.random.default_rng(cfg.seed))[vox.inverse]


def segment_geometric(coord: np.ndarray, cfg: GeometricConfig = GeometricConfig(),
                      on_plane: np.ndarray | None = None) -> Segmentation:
    """Planes removed, connected components of the rest; score = larger components first (in (0, 1)).
    ``on_plane`` (N,) bool, from :func:`structural_points` with the same ``cfg``, saves finding the
    planes again."""
    vox = voxelize(np.asarray(coord, np.float32), cfg.voxel_size)
    if on_plane is None:
        on_plane = remove_planes(vox.centres, cfg, np.random.default_rng(cfg.seed))
    else:
        if np.shape(on_plane) != (len(vox.inverse),):
            raise ValueError(f"on_plane has shape {np.shape(on_plane)}, expected ({len(vox.inverse)},)")
        plane_points = np.asarray(on_plane, bool)
        on_plane = np.zeros(len(vox), bool)
        on_plane[vox.inverse] = plane_points  # every point of a 2 cm voxel shares its voxel's value
    rows = np.flatnonzero(~on_plane)
    labels = np.full(len(vox), -1, np.int64)
    comp = radius_components(vox.centres[rows], cfg.link_radius)
    sizes = np.bincount(comp) if len(comp) else np.zeros(0, np.int64)
    keep = np.flatnonzero(sizes >= cfg.min_voxels)
    score = sizes[keep] / (sizes[keep] + 200.0)
    order = np.argsort(-score, kind="stable")
    new_id = np.full(len(sizes), -1, np.int64)
    new_id[keep[order]] = np.arange(len(keep))
    if len(rows):
        labels[rows] = new_id[comp]
    scores = score[order].astype(np.float32)
    return Segmentation(masks=point_masks(labels, vox.inverse, len(scores)), scores=scores,
                        labels=labels[vox.inverse])

"""Surface sampling of a scene mesh: the mesh-sampled baseline and the nearest-object labels.

The baseline (``point_source="mesh"``, the paper's ablation) samples every surface uniformly by
area, with no occlusion, then keeps one point per voxel like the rendered cloud, and finally a
random subset of the size of the rendered cloud.
"""

from __future__ import annotations

import numpy as np

from ..core.contracts import SceneMesh
from ..core.errors import RenderError
from .voxel import VoxelGrid, pick_one_per_voxel

__all__ = ["face_areas", "sample_faces", "sample_surface", "nearest_instance"]

MAX_SAMPLES = 30_000_000  # budget on raw surface samples


def face_areas(scene: SceneMesh, faces: np.ndarray | None = None) -> np.ndarray:
    """(n,) float64 areas of ``faces`` (all faces if None)."""
    f = scene.faces if faces is None else scene.faces[faces]
    tri = scene.vertices[f].astype(np.float64)
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def sample_faces(scene: SceneMesh, faces: np.ndarray, count: int, *, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``count`` points uniformly by area on triangles ``faces`` (n,) int.

    Returns coord (count, 3) float32 and face (count,) int32 (indices into the scene's faces).
    """
    if count > MAX_SAMPLES:
        raise RenderError(f"surface sampling: {count} samples exceed the budget of {MAX_SAMPLES}")
    faces = np.asarray(faces, dtype=np.int64)
    area = face_areas(scene, faces)
    total = float(area.sum())
    if count == 0 or total <= 0:
        return np.zeros((0, 3), np.float32), np.zeros(0, np.int32)
    cum = np.cumsum(area)
    pick = np.minimum(np.searchsorted(cum, rng.random(count) * total, side="right"), len(faces) - 1)
    r1 = np.sqrt(rng.random(count))
    r2 = rng.random(count)
    tri = scene.vertices[scene.faces[faces[pick]]].astype(np.float64)
    pts = ((1 - r1)[:, None] * tri[:, 0] + (r1 * (1 - r2))[:, None] * tri[:, 1] + (r1 * r2)[:, None] * tri[:, 2])
    return pts.astype(np.float32), faces[pick].astype(np.int32)


def sample_surface(scene: SceneMesh, grid: VoxelGrid, target: int, *, rng: np.random.Generator,
                   oversample: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """Mesh-sampled baseline cloud: about ``oversample`` raw samples per voxel face of surface,
    one per voxel, then ``target`` of them at random (all if fewer).

    Returns coord (N, 3) float32 and face (N,) int32, sorted by voxel.
    """
    area = float(face_areas(scene).sum())
    raw = int(min(MAX_SAMPLES, np.ceil(oversample * area / grid.size ** 2)))
    coord, face = sample_faces(scene, np.arange(len(scene.faces)), raw, rng=rng)
    keep = pick_one_per_voxel(grid.keys(coord), int(rng.integers(1, 2**62)))
    if target < len(keep):
        keep = np.sort(rng.choice(keep, size=target, replace=False))
    return coord[keep], face[keep]


def nearest_instance(scene: SceneMesh, coord: np.ndarray, *, radius: float, spacing: float,
                     rng: np.random.Generator) -> np.ndarray:
    """The paper's label assignment: each point takes the instance of the nearest sample on any
    object's surface, or -1 when no object surface is within ``radius`` metres.

    Objects are sampled at about one point per ``spacing``^2 of area. Returns (N,) int32.
    """
    from scipy.spatial import cKDTree

    obj = np.flatnonzero(scene.face_instance >= 0)
    out = np.full(len(coord), -1, np.int32)
    if len(obj) == 0 or len(coord) == 0:
        return out
    count = int(np.ceil(float(face_areas(scene, obj).sum()) / spacing ** 2))
    count = max(count, 1)
    # every object face gets at least its first vertex, so thin or tiny objects are never missed
    pts, faces = sample_faces(scene, obj, count, rng=rng)
    corner = scene.vertices[scene.faces[obj, 0]]
    pts = np.concatenate([pts, corner])
    faces = np.concatenate([faces, obj.astype(np.int32)])
    tree = cKDTree(pts)
    dist, idx = tree.query(coord, k=1, distance_upper_bound=radius, workers=1)
    ok = np.isfinite(dist)
    out[ok] = scene.face_instance[faces[idx[ok]]]
    return out

"""Per-hit attributes (normals, shaded colour) and single RGB-D views."""

from __future__ import annotations

import numpy as np

from ..core.contracts import Camera, RGBDView, SceneMesh
from .camera import pixel_directions, world_directions
from .raycast import RayCaster

__all__ = ["face_normals", "oriented_normals", "shade", "render_view", "AMBIENT"]

AMBIENT = 0.35  # share of a face's colour kept when it is seen edge-on (Lambertian headlight)


def face_normals(scene: SceneMesh, faces: np.ndarray) -> np.ndarray:
    """(n, 3) float32 unit normals (by winding) of triangles ``faces`` (n,) int of ``scene``."""
    tri = scene.vertices[scene.faces[faces]]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return (n / np.maximum(length, np.float32(1e-20))).astype(np.float32)


def oriented_normals(normals: np.ndarray, rays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Flip unit normals (n, 3) to face against the rays (n, 3) that saw them.

    Returns (normals float32 (n, 3), |cos| float32 (n,) of the angle between ray and normal).
    """
    rn = rays / np.maximum(np.linalg.norm(rays, axis=1, keepdims=True), np.float32(1e-20))
    cos = np.einsum("ij,ij->i", normals, rn)
    flip = cos > 0
    out = np.where(flip[:, None], -normals, normals).astype(np.float32)
    return out, np.abs(cos).astype(np.float32)


def shade(colors: np.ndarray, abs_cos: np.ndarray, enabled: bool, gain: np.ndarray | None = None) -> np.ndarray:
    """(n, 3) uint8 colours lit by a headlight: ``c * (AMBIENT + (1 - AMBIENT) |cos|) * gain``."""
    f = np.ones(len(colors), np.float32)
    if enabled:
        f = np.float32(AMBIENT) + np.float32(1.0 - AMBIENT) * abs_cos
    if gain is not None:
        f = f * gain
    return np.clip(colors.astype(np.float32) * f[:, None] + np.float32(0.5), 0, 255).astype(np.uint8)


def render_view(scene: SceneMesh, caster: RayCaster, camera: Camera, *, shading: bool = True) -> RGBDView:
    """Ray-cast one RGB-D view: depth along the optical axis (0 = miss), shaded colour, instance
    id and hit triangle per pixel."""
    cam_dirs = pixel_directions(camera.width, camera.height, camera.fx, camera.fy, camera.cx, camera.cy)
    dirs = world_directions(camera, cam_dirs)
    origins = np.zeros_like(dirs)
    origins[:] = camera.pose[:3, 3].astype(np.float32)
    t, face = caster.cast(origins, dirs)
    hit = face >= 0
    h, w = camera.height, camera.width
    depth = np.where(hit, t, np.float32(0)).astype(np.float32)
    color = np.zeros((len(t), 3), np.uint8)
    instance = np.full(len(t), -1, np.int32)
    fh = face[hit]
    if len(fh):
        _, cos = oriented_normals(face_normals(scene, fh), dirs[hit])
        color[hit] = shade(scene.face_colors[fh], cos, shading)
        instance[hit] = scene.face_instance[fh]
    return RGBDView(camera, depth.reshape(h, w), color.reshape(h, w, 3), instance.reshape(h, w),
                    face.reshape(h, w))

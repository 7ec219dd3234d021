"""Simple shaded views of a scene for the VLM layout score.

Two sources: the assembled scene mesh (ray casting, :func:`render_views`) and a labelled point
cloud (z-buffered splats, :func:`render_point_views`), so any dataset folder can be scored, real
scans included. Cameras stand inside the room near its corners, high up, looking down at the
room's centre (the way people photograph rooms). Rays are cast with the renderer's ray caster
(:mod:`assist3d.render.raycast`); images are RGB PNG bytes from Pillow without metadata
(byte-stable), so a cached score stays a cache hit.
"""

from __future__ import annotations

import io
from typing import Callable

import numpy as np

from ...core.contracts import SceneMesh
from ...core.errors import RenderError
from ...render.camera import pixel_directions
from ...render.raycast import make_caster
from ...render.rgbd import face_normals

FOV_DEG = 75.0
BACKGROUND = np.array([235, 235, 235], dtype=np.float32)


def encode_png(image: np.ndarray) -> bytes:
    """PNG bytes of an (H, W, 3) uint8 RGB image (Pillow; no metadata, so the same image gives the
    same bytes)."""
    from PIL import Image

    if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
        raise ValueError(f"image: expected (H, W, 3) uint8, got {image.shape} {image.dtype}")
    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image), "RGB").save(buf, format="PNG", compress_level=6)
    return buf.getvalue()


def camera_positions(xy_min: np.ndarray, xy_max: np.ndarray, floor_z: float, height: float, n: int,
                     inside: Callable[[np.ndarray], np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) eye positions near the corners of the box (diagonal pairs first, then wall
    midpoints) and the (3,) point they look at.

    ``inside(xy (m, 2)) -> (m,) bool`` tells which spots are in the room; a spot outside (the
    notch of an L-shaped room) moves towards the centre until it is inside."""
    lo, hi = np.asarray(xy_min, np.float64), np.asarray(xy_max, np.float64)
    c = 0.5 * (lo + hi)
    spots = np.array([[lo[0], lo[1]], [hi[0], hi[1]], [hi[0], lo[1]], [lo[0], hi[1]],
                      [c[0], lo[1]], [c[0], hi[1]], [lo[0], c[1]], [hi[0], c[1]]])
    spots = spots[np.arange(n) % len(spots)]
    base = 0.12 + 0.1 * (np.arange(n) // len(spots))  # repeated spots move further in
    steps = np.array([0.0, 0.15, 0.3, 0.45, 0.6, 0.75])
    inset = np.minimum(base[:, None] + steps[None], 1.0)  # (n, k) candidates per eye, outermost first
    cand = spots[:, None] + (c - spots)[:, None] * inset[..., None]
    ok = np.ones(inset.shape, bool) if inside is None else inside(cand.reshape(-1, 2)).reshape(inset.shape)
    ok[:, -1] |= ~ok.any(1)  # nothing inside: the innermost candidate
    xy = cand[np.arange(n), ok.argmax(1)]
    eye_z = floor_z + min(0.85 * height, max(height - 0.25, 0.5 * height))
    eyes = np.column_stack([xy, np.full(n, eye_z)])
    target = np.array([c[0], c[1], floor_z + 0.2 * height])
    return eyes, target


def _camera_axes(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(3, 3) rows right, down, forward (OpenCV camera axes in world coordinates)."""
    f = target - eye
    f = f / np.linalg.norm(f)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r = r / max(np.linalg.norm(r), 1e-9)
    d = np.cross(f, r)
    return np.stack([r, d, f])


def _view_rays(eye: np.ndarray, target: np.ndarray, size: int) -> np.ndarray:
    """(size*size, 3) unit world ray directions of a square pinhole view, row-major from the top left."""
    focal = size / 2 / np.tan(np.radians(FOV_DEG) / 2)
    d = pixel_directions(size, size, focal, focal, (size - 1) / 2, (size - 1) / 2) @ _camera_axes(eye, target)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def render_views(scene_mesh: SceneMesh, n: int = 4, size: int = 512) -> list[bytes]:
    """``n`` PNG views (``size`` x ``size``) of the scene mesh, Lambert-shaded face colours."""
    if n < 1 or size < 8:
        raise ValueError(f"render_views: need n >= 1 and size >= 8, got n={n}, size={size}")
    v = scene_mesh.vertices.astype(np.float64)
    f = scene_mesh.faces
    if len(f) == 0:
        raise RenderError("render_views: the scene mesh has no faces")
    floor_faces = np.zeros(len(f), bool)
    if "floor" in scene_mesh.background_names:
        floor_faces = scene_mesh.face_part == -(scene_mesh.background_names.index("floor") + 1)
    pts = v[f[floor_faces].ravel()] if floor_faces.any() else v
    floor_z = float(pts[:, 2].min())
    height = float(v[:, 2].max()) - floor_z
    caster = make_caster("embree", v, f)

    def inside(xy: np.ndarray) -> np.ndarray:  # floor (or furniture) below the spot, from under the ceiling
        origins = np.column_stack([xy, np.full(len(xy), floor_z + 0.9 * max(height, 0.5))])
        return caster.cast(origins, np.tile([0.0, 0.0, -1.0], (len(xy), 1)))[1] >= 0

    eyes, target = camera_positions(pts[:, :2].min(0), pts[:, :2].max(0), floor_z, max(height, 2.0), n, inside)
    normals = face_normals(scene_mesh, np.arange(len(f))).astype(np.float64)
    colors = scene_mesh.face_colors.astype(np.float32)
    out = []
    for eye in eyes:
        dirs = _view_rays(eye, target, size)
        hit = caster.cast(np.broadcast_to(eye, dirs.shape), dirs)[1]
        img = np.broadcast_to(BACKGROUND, (len(dirs), 3)).copy()
        ok = hit >= 0
        shade = 0.35 + 0.65 * np.abs(np.einsum("ij,ij->i", normals[hit[ok]], dirs[ok]))
        img[ok] = colors[hit[ok]] * shade[:, None]
        out.append(encode_png(np.clip(img, 0, 255).astype(np.uint8).reshape(size, size, 3)))
    return out


def point_spacing(coord: np.ndarray, sample: int = 2000) -> float:
    """Median nearest-neighbour distance of a point cloud (coord (N, 3)), from a fixed subsample."""
    from scipy.spatial import cKDTree

    if len(coord) < 2:
        return 0.02
    pick = np.linspace(0, len(coord) - 1, min(sample, len(coord))).astype(np.int64)
    dist, _ = cKDTree(coord).query(coord[pick], k=2)
    return float(max(np.median(dist[:, 1]), 1e-3))


def render_point_views(coord: np.ndarray, color: np.ndarray, n: int = 4, size: int = 512) -> list[bytes]:
    """``n`` PNG views of a point cloud: coord (N, 3) float, color (N, 3) uint8.

    Each point is a square splat sized to cover the point spacing at its depth (3 or 5 px
    across at most), the nearest point wins every pixel, colours darken slightly with distance."""
    if coord.ndim != 2 or coord.shape[1] != 3 or color.shape != coord.shape:
        raise ValueError(f"render_point_views: expected coord and color of shape (N, 3), got {coord.shape}, "
                         f"{color.shape}")
    if len(coord) == 0:
        raise RenderError("render_point_views: no points")
    p = coord.astype(np.float64)
    lo, hi = np.percentile(p, 0.5, axis=0), np.percentile(p, 99.5, axis=0)
    cell = 0.25
    occupied = {tuple(k) for k in np.unique(np.floor(p[:, :2] / cell).astype(np.int64), axis=0)}

    def inside(xy: np.ndarray) -> np.ndarray:  # points in the spot's 0.25 m column
        keys = np.floor(xy / cell).astype(np.int64)
        return np.array([tuple(k) in occupied for k in keys], dtype=bool)

    eyes, target = camera_positions(lo[:2], hi[:2], float(lo[2]), max(float(hi[2] - lo[2]), 2.0), n, inside)
    focal = size / 2 / np.tan(np.radians(FOV_DEG) / 2)
    spacing = point_spacing(p)
    col = color.astype(np.float32)
    out = []
    for eye in eyes:
        cam = (p - eye) @ _camera_axes(eye, target).T
        front = cam[:, 2] > 0.05
        z = cam[front, 2]
        px = np.floor(cam[front, 0] / z * focal + size / 2).astype(np.int64)
        py = np.floor(cam[front, 1] / z * focal + size / 2).astype(np.int64)
        c = col[front] * np.clip(1.05 - 0.04 * z, 0.6, 1.0)[:, None]
        radius = np.clip(np.ceil(0.5 * spacing * focal / z - 0.5), 1, 2).astype(np.int64)
        pix_parts, idx_parts, z_parts = [], [], []
        for r in np.unique(radius):  # a few splat sizes, each vectorised over its points
            sel = np.nonzero(radius == r)[0]
            d = np.arange(-r, r + 1)
            dy, dx = (a.ravel() for a in np.meshgrid(d, d, indexing="ij"))
            sx = (px[sel, None] + dx[None]).ravel()
            sy = (py[sel, None] + dy[None]).ravel()
            inside = (sx >= 0) & (sx < size) & (sy >= 0) & (sy < size)
            pix_parts.append((sy * size + sx)[inside])
            idx_parts.append(np.repeat(sel, len(dx))[inside])
            z_parts.append(np.repeat(z[sel], len(dx))[inside])
        pix, idx, sz = np.concatenate(pix_parts), np.concatenate(idx_parts), np.concatenate(z_parts)
        order = np.lexsort((idx, sz, pix))
        first = np.unique(pix[order], return_index=True)[1]
        img = np.broadcast_to(BACKGROUND, (size * size, 3)).copy()
        img[pix[order][first]] = c[idx[order][first]]
        out.append(encode_png(np.clip(img, 0, 255).astype(np.uint8).reshape(size, size, 3)))
    return out

"""Small hand-built scenes (a room shell plus boxes or spheres) for tests and render benchmarks,
independent of the asset and layout stages."""

from __future__ import annotations

import numpy as np

from ..core.contracts import Room, SceneMesh

__all__ = ["shell_parts", "box_part", "sphere_part", "combine_parts"]

Part = tuple[np.ndarray, np.ndarray, tuple[int, int, int], int, int]  # vertices, faces, rgb, instance, segment


def shell_parts(room: Room) -> list[Part]:
    """Floor (and ceiling) triangulated from the polygon, one quad (two triangles) per wall.
    Background parts get instance and segment -1."""
    import mapbox_earcut

    poly = np.asarray(room.polygon, dtype=np.float64)
    rings = np.array([len(poly)], dtype=np.uint32)
    tri = np.asarray(mapbox_earcut.triangulate_float64(poly, rings), dtype=np.int32).reshape(-1, 3)
    floor_v = np.column_stack([poly, np.zeros(len(poly))])
    parts: list[Part] = [(floor_v, tri[:, ::-1].copy(), (150, 120, 90), -1, -1)]
    if room.ceiling:
        parts.append((floor_v + [0, 0, room.height], tri.copy(), (235, 235, 230), -1, -1))
    for k in range(len(poly)):
        a, b = poly[k], poly[(k + 1) % len(poly)]
        v = np.array([[a[0], a[1], 0], [b[0], b[1], 0], [b[0], b[1], room.height], [a[0], a[1], room.height]])
        parts.append((v, np.array([[0, 1, 2], [0, 2, 3]], np.int32), (200, 200, 195), -1, -1))
    return parts


def box_part(center: tuple[float, float, float], size: tuple[float, float, float], yaw: float,
             rgb: tuple[int, int, int], instance: int, segment: int) -> Part:
    """A box (12 outward-wound triangles) with its base centre at ``center``."""
    sx, sy, sz = (s / 2 for s in size)
    v = np.array([[x, y, z] for z in (0, 2 * sz) for y in (-sy, sy) for x in (-sx, sx)], dtype=np.float64)
    f = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
                  [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]], np.int32)
    c, s = np.cos(yaw), np.sin(yaw)
    v = v @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]]) + np.asarray(center)
    return v, f, rgb, instance, segment


def sphere_part(center: tuple[float, float, float], radius: float, subdivisions: int,
                rgb: tuple[int, int, int], instance: int, segment: int) -> Part:
    """An icosphere (20 * 4**subdivisions triangles) centred at ``center``."""
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(m.vertices) + np.asarray(center), np.asarray(m.faces, np.int32), rgb, instance, segment


def combine_parts(parts: list[Part]) -> SceneMesh:
    """One SceneMesh from parts; background parts are named ``bg_<k>`` in ``background_names``."""
    verts, faces, cols, inst, seg, part = [], [], [], [], [], []
    off = 0
    bg = 0
    names = []
    for v, f, rgb, i, s in parts:
        verts.append(np.asarray(v, np.float32))
        faces.append(np.asarray(f, np.int32) + off)
        off += len(v)
        n = len(f)
        cols.append(np.tile(np.asarray(rgb, np.uint8), (n, 1)))
        inst.append(np.full(n, i, np.int32))
        seg.append(np.full(n, s, np.int32))
        if i < 0:
            part.append(np.full(n, -(bg + 1), np.int32))
            names.append(f"bg_{bg}")
            bg += 1
        else:
            part.append(np.full(n, i, np.int32))
    return SceneMesh(np.concatenate(verts), np.concatenate(faces), np.concatenate(cols), np.concatenate(inst),
                     np.concatenate(seg), np.concatenate(part), tuple(names))

"""Room-shell meshes: the floor, one mesh per wall with its door and window openings cut out,
and (when ``room.ceiling``) the ceiling. Every surface faces into the room."""

from __future__ import annotations

import mapbox_earcut
import numpy as np

from ..core.contracts import MeshData, Room
from .geometry import room_polygon, wall_segments

FLOOR_COLOR = (156, 134, 110)
WALL_COLOR = (222, 218, 208)
CEILING_COLOR = (240, 240, 236)

__all__ = ["build_shell", "FLOOR_COLOR", "WALL_COLOR", "CEILING_COLOR"]


def _mesh(vertices: np.ndarray, faces: np.ndarray, color: tuple[int, int, int]) -> MeshData:
    faces = np.asarray(faces, dtype=np.int32).reshape(-1, 3)
    return MeshData(np.asarray(vertices, dtype=np.float32).reshape(-1, 3), faces,
                    np.tile(np.array(color, dtype=np.uint8), (len(faces), 1)))


def _cap(room: Room, z: float, up: bool, color: tuple[int, int, int]) -> MeshData:
    ring = np.asarray(room_polygon(room).exterior.coords)[:-1]  # counter-clockwise
    tri = mapbox_earcut.triangulate_float64(ring, np.array([len(ring)], dtype=np.uint32)).reshape(-1, 3)
    verts = np.column_stack([ring, np.full(len(ring), z)])
    # earcut's winding follows no promise: orient every triangle by its normal's z sign.
    a, b, c = verts[tri[:, 0]], verts[tri[:, 1]], verts[tri[:, 2]]
    nz = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    flip = (nz < 0) if up else (nz > 0)
    tri[flip] = tri[flip][:, [0, 2, 1]]
    return _mesh(verts, tri, color)


def _wall_rects(length: float, height: float, holes: list[tuple[float, float, float, float]]) -> list[tuple[float, ...]]:
    """Rectangles (s0, s1, z0, z1) covering [0, length] x [0, height] minus the holes."""
    cuts = {0.0, length}
    for s0, s1, _, _ in holes:
        cuts.update((min(max(s0, 0.0), length), min(max(s1, 0.0), length)))
    xs = sorted(cuts)
    rects = []
    for a, b in zip(xs[:-1], xs[1:]):
        if b - a < 1e-9:
            continue
        mid = (a + b) / 2
        blocked = sorted((max(z0, 0.0), min(z1, height)) for s0, s1, z0, z1 in holes if s0 <= mid <= s1 and z1 > z0)
        z = 0.0
        for z0, z1 in blocked:
            if z0 > z + 1e-9:
                rects.append((a, b, z, z0))
            z = max(z, z1)
        if z < height - 1e-9:
            rects.append((a, b, z, height))
    return rects


def build_shell(room: Room) -> list[tuple[str, MeshData]]:
    """Named background meshes of ``room``: ``floor``, ``wall_0`` ... ``wall_{n-1}`` (wall i is the
    polygon edge from vertex i to i+1) and ``ceiling`` if the room has one. World frame, metres."""
    parts: list[tuple[str, MeshData]] = [("floor", _cap(room, 0.0, True, FLOOR_COLOR))]
    walls = wall_segments(room)
    for i in range(len(walls.length)):
        holes = [(o.offset - o.width / 2, o.offset + o.width / 2, o.bottom, o.top)
                 for o in room.openings if o.wall == i]
        rects = _wall_rects(float(walls.length[i]), room.height, holes)
        u = np.append(walls.direction[i], 0.0)
        p0 = np.append(walls.start[i], 0.0)
        verts, faces = [], []
        for r, (s0, s1, z0, z1) in enumerate(rects):
            corners = [p0 + u * s + np.array([0, 0, z]) for s, z in ((s0, z0), (s1, z0), (s1, z1), (s0, z1))]
            verts.extend(corners)
            b = 4 * r
            # (s0,z0) -> (s1,z1) -> (s1,z0) winds with the normal pointing into the room.
            faces.extend([(b, b + 2, b + 1), (b, b + 3, b + 2)])
        if faces:
            mesh = _mesh(np.array(verts), np.array(faces), WALL_COLOR)
            parts.append((f"wall_{i}", _orient_inward(mesh, walls.normal[i])))
        else:
            empty = MeshData(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int32), np.zeros((0, 3), np.uint8))
            parts.append((f"wall_{i}", empty))
    if room.ceiling:
        parts.append(("ceiling", _cap(room, room.height, False, CEILING_COLOR)))
    return parts


def _orient_inward(mesh: MeshData, normal: np.ndarray) -> MeshData:
    v = mesh.vertices.astype(np.float64)
    f = mesh.faces.copy()
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    flip = n[:, :2] @ normal < 0
    f[flip] = f[flip][:, [0, 2, 1]]
    return MeshData(mesh.vertices.copy(), f, mesh.face_colors.copy())

"""Room-shell meshes: the floor, one mesh per wall with its door and window openings cut out,
and (when ``room.ceiling``) the ceiling. Every surface faces into the room."""

from __future__ import annotations

import mapbox_earcut
import numpy as np
from trimesh import creation

from ..core.contracts import MeshData, Room
from ..core.geometry import room_polygon, wall_segments

FLOOR_COLOR = (156, 134, 110)
WALL_COLOR = (222, 218, 208)
CEILING_COLOR = (240, 240, 236)

__all__ = ["build_shell", "opening_meshes", "FLOOR_COLOR", "WALL_COLOR", "CEILING_COLOR"]

# filled openings (``room.fill_openings``): frames sit in the hole, behind the wall plane, so that
# nothing but an open door leaf (inside the clearance zone placement keeps free) enters the room
FRAME = 0.05  # m, width of a door or window frame member
DOOR_FRAME_DEPTH = 0.10  # m behind the wall plane
LEAF_THICKNESS = 0.04  # m
LEAF_RECESS = 0.01  # m, a closed leaf's room-side face behind the wall plane
WINDOW_DEPTH = (0.02, 0.10)  # m behind the wall plane: frame members between these depths
SILL_DEPTH = 0.12  # m, the bottom member reaches this deep (the sill)
MULLION_MIN_WIDTH = 0.9  # m, wider windows get a central mullion
FRAME_COLORS = ((236, 236, 230), (205, 195, 175), (120, 86, 60))
LEAF_COLORS = ((236, 236, 230), (172, 122, 80), (120, 86, 60), (150, 150, 152))
HANDLE_COLOR = (170, 170, 175)


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


def _box(origin: np.ndarray, ex: np.ndarray, ey: np.ndarray, ez: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (8, 3) and outward-facing triangles (12, 3) of the box origin + [0,1] ex + [0,1] ey
    + [0,1] ez (edge vectors, any orientation: trimesh flips the triangles of a mirrored frame)."""
    t = np.eye(4)
    t[:3, :3] = np.column_stack([ex, ey, ez])
    t[:3, 3] = origin + (ex + ey + ez) / 2
    box = creation.box(extents=(1.0, 1.0, 1.0), transform=t)
    return np.asarray(box.vertices), np.asarray(box.faces)


def _boxes_mesh(boxes: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, tuple[int, int, int]]]) -> MeshData:
    verts, faces, colors = [], [], []
    for b, (origin, ex, ey, ez, color) in enumerate(boxes):
        v, f = _box(origin, ex, ey, ez)
        verts.append(v)
        faces.append(f + 8 * b)
        colors.append(np.tile(np.array(color, np.uint8), (len(f), 1)))
    return MeshData(np.concatenate(verts).astype(np.float32), np.concatenate(faces).astype(np.int32),
                    np.concatenate(colors))


def opening_meshes(room: Room) -> list[tuple[int, str, MeshData]]:
    """(instance id, class, mesh) of every filled opening of ``room`` (``Opening.instance`` set), in
    the world frame: a door is its frame (two jambs and a head, ``DOOR_FRAME_DEPTH`` deep behind the
    wall plane), its leaf (closed just behind the wall plane or turned ``leaf_deg`` into the room
    about its hinge) and a handle; a window is its frame (sides, head, a deeper bottom member as the
    sill) and, when wider than ``MULLION_MIN_WIDTH``, a central mullion. No glass: depth sensors see
    through it. Colours come from small palettes, picked by instance id."""
    walls = wall_segments(room)
    out = []
    for o in room.openings:
        if o.instance is None or not 0 <= o.wall < len(walls.length):
            continue
        u = np.append(walls.direction[o.wall], 0.0)
        n = np.append(walls.normal[o.wall], 0.0)
        z = np.array([0.0, 0.0, 1.0])
        p0 = np.append(walls.start[o.wall], 0.0)

        def at(s: float, d: float, h: float) -> np.ndarray:
            return p0 + u * s + n * d + z * h

        a, b = o.offset - o.width / 2, o.offset + o.width / 2
        frame = FRAME_COLORS[o.instance % len(FRAME_COLORS)]
        if o.kind == "door":
            dd = DOOR_FRAME_DEPTH
            boxes = [(at(a, -dd, 0.0), u * FRAME, n * dd, z * o.top, frame),
                     (at(b - FRAME, -dd, 0.0), u * FRAME, n * dd, z * o.top, frame),
                     (at(a + FRAME, -dd, o.top - FRAME), u * (b - a - 2 * FRAME), n * dd, z * FRAME, frame)]
            sign = 1.0 if o.hinge == 0 else -1.0
            t = np.deg2rad(o.leaf_deg)
            e = np.cos(t) * sign * u + np.sin(t) * n  # along the leaf, from the hinge
            m = -np.cos(t) * n + np.sin(t) * sign * u  # across the leaf, away from the room
            gap = 0.003
            length = b - a - 2 * FRAME - 2 * gap
            hinge = at(a + FRAME + gap if o.hinge == 0 else b - FRAME - gap, -LEAF_RECESS, 0.01)
            tall = o.top - FRAME - 0.01 - gap
            boxes.append((hinge, e * length, m * LEAF_THICKNESS, z * tall, LEAF_COLORS[o.instance % len(LEAF_COLORS)]))
            grip = hinge + e * (length - 0.16) + z * (min(1.0, 0.5 * tall) - 0.015)
            boxes.append((grip, e * 0.12, -m * 0.04, z * 0.03, HANDLE_COLOR))  # on the room side of the leaf
        else:
            d0, d1 = WINDOW_DEPTH
            depth = n * (d1 - d0)
            boxes = [(at(a, -d1, o.bottom), u * FRAME, depth, z * (o.top - o.bottom), frame),
                     (at(b - FRAME, -d1, o.bottom), u * FRAME, depth, z * (o.top - o.bottom), frame),
                     (at(a + FRAME, -d1, o.top - FRAME), u * (b - a - 2 * FRAME), depth, z * FRAME, frame),
                     (at(a + FRAME, -SILL_DEPTH, o.bottom), u * (b - a - 2 * FRAME), n * SILL_DEPTH, z * FRAME, frame)]
            if o.width > MULLION_MIN_WIDTH:
                boxes.append((at(o.offset - FRAME / 2, -d1, o.bottom + FRAME), u * FRAME, depth,
                              z * (o.top - o.bottom - 2 * FRAME), frame))
        out.append((int(o.instance), o.kind, _boxes_mesh(boxes)))
    return out


"""Planar and box geometry used by placement, assembly and checks.

Conventions (see :mod:`assist3d.core.contracts`): metres, z up, an asset's canonical frame has its base
at z = 0, its footprint centred at the origin, width along x, depth along y and its front facing
-y. A pose here is ``(x, y, yaw, z)``: a rotation by ``yaw`` about z followed by a translation;
:func:`pose_matrix` turns it into the 4x4 row-major matrix stored in ``PlacedInstance.pose``.

Everything is vectorised: functions take numpy arrays and broadcast.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from .contracts import PlacedInstance, Room
from .errors import PlacementError

__all__ = [
    "pose_matrix", "pose_xyz_yaw", "transform_points", "rotated_half_extents", "rect_corners",
    "obb_overlap", "box_gap", "rects_in_polygon", "WallSegments", "wall_segments", "room_polygon",
    "world_bounds", "footprint_polygon", "InstanceBoxes",
]


def pose_matrix(x: float, y: float, yaw: float, z: float = 0.0) -> np.ndarray:
    """(4, 4) float64 pose: rotate by ``yaw`` (radians, about +z), then translate to (x, y, z)."""
    c, s = float(np.cos(yaw)), float(np.sin(yaw))
    # Snap tiny values so that 90-degree turns are exact in the JSON.
    c = 0.0 if abs(c) < 1e-12 else c
    s = 0.0 if abs(s) < 1e-12 else s
    return np.array([[c, -s, 0.0, float(x)], [s, c, 0.0, float(y)], [0.0, 0.0, 1.0, float(z)],
                     [0.0, 0.0, 0.0, 1.0]], dtype=np.float64)


def pose_xyz_yaw(pose: np.ndarray) -> tuple[float, float, float, float]:
    """(x, y, z, yaw) of a pose that rotates about z only."""
    return float(pose[0, 3]), float(pose[1, 3]), float(pose[2, 3]), float(np.arctan2(pose[1, 0], pose[0, 0]))


def transform_points(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply a (4, 4) pose to (n, 3) points; returns (n, 3) in the points' float dtype."""
    p = np.asarray(points)
    out = p @ pose[:3, :3].T.astype(p.dtype) + pose[:3, 3].astype(p.dtype)
    return out


def rotated_half_extents(width: np.ndarray | float, depth: np.ndarray | float,
                         yaw: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Half extents (x, y) of the axis-aligned box around a ``width`` x ``depth`` rectangle turned by ``yaw``."""
    c, s = np.abs(np.cos(yaw)), np.abs(np.sin(yaw))
    w, d = np.asarray(width, float) / 2.0, np.asarray(depth, float) / 2.0
    return c * w + s * d, s * w + c * d


def rect_corners(x: np.ndarray, y: np.ndarray, yaw: np.ndarray, width: np.ndarray | float,
                 depth: np.ndarray | float) -> np.ndarray:
    """(n, 4, 2) corners (counter-clockwise) of oriented rectangles centred at (x, y)."""
    x, y, yaw = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float), np.asarray(yaw, float))
    w = np.broadcast_to(np.asarray(width, float), x.shape) / 2.0
    d = np.broadcast_to(np.asarray(depth, float), x.shape) / 2.0
    lx = np.stack([-w, w, w, -w], -1)
    ly = np.stack([-d, -d, d, d], -1)
    c, s = np.cos(yaw)[..., None], np.sin(yaw)[..., None]
    return np.stack([x[..., None] + c * lx - s * ly, y[..., None] + s * lx + c * ly], -1)


def obb_overlap(ax: np.ndarray, ay: np.ndarray, ayaw: np.ndarray, ahw: np.ndarray, ahd: np.ndarray,
                bx: np.ndarray, by: np.ndarray, byaw: np.ndarray, bhw: np.ndarray, bhd: np.ndarray,
                margin: float = 0.0) -> np.ndarray:
    """Whether oriented rectangles A and B overlap (separating-axis test), broadcast over inputs.

    ``*hw``/``*hd`` are half width (local x) and half depth (local y). Rectangles closer than
    ``margin`` count as overlapping; touching rectangles (gap 0, margin 0) do not.
    """
    return _obb_overlap_cs(bx - ax, by - ay, np.cos(ayaw), np.sin(ayaw), ahw, ahd, np.cos(byaw), np.sin(byaw),
                           bhw, bhd, margin)


def _obb_overlap_cs(dx, dy, ca, sa, ahw, ahd, cb, sb, bhw, bhd, margin: float) -> np.ndarray:
    """:func:`obb_overlap` from the centre offsets and the cosines and sines of the yaws (callers
    that test many pairs of few rectangles take those once per rectangle)."""
    axes = ((ca, sa), (-sa, ca), (cb, sb), (-sb, cb))
    sep = np.zeros(np.broadcast(dx, dy, ahw, bhw).shape, dtype=bool)
    for ux, uy in axes:
        ra = ahw * np.abs(ca * ux + sa * uy) + ahd * np.abs(-sa * ux + ca * uy)
        rb = bhw * np.abs(cb * ux + sb * uy) + bhd * np.abs(-sb * ux + cb * uy)
        sep |= np.abs(dx * ux + dy * uy) >= ra + rb + margin - 1e-9
    return ~sep


def box_gap(ax: np.ndarray, ay: np.ndarray, ahx: np.ndarray, ahy: np.ndarray,
            bx: np.ndarray, by: np.ndarray, bhx: np.ndarray, bhy: np.ndarray) -> np.ndarray:
    """Distance between the axis-aligned boxes (half extents ``h*``) around two footprints; 0 if they touch."""
    gx = np.maximum(np.abs(bx - ax) - ahx - bhx, 0.0)
    gy = np.maximum(np.abs(by - ay) - ahy - bhy, 0.0)
    return np.hypot(gx, gy)


def room_polygon(room: Room) -> shapely.Polygon:
    """The room's floor polygon as a valid, counter-clockwise shapely polygon."""
    poly = shapely.Polygon(room.polygon) if len(room.polygon) >= 3 else shapely.Polygon()
    if not poly.is_valid or poly.area <= 0:
        raise PlacementError(f"room polygon {room.polygon} is not a simple polygon with positive area; "
                             f"give at least three vertices, counter-clockwise, without self-crossings")
    return shapely.orient_polygons(poly)


def points_in_ring(x: np.ndarray, y: np.ndarray, ring: np.ndarray) -> np.ndarray:
    """(n,) bool: points strictly inside the closed ring (v, 2) by the crossing-number rule
    (points exactly on the boundary may go either way)."""
    x1, y1 = ring[:, 0], ring[:, 1]
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    inside = np.zeros(len(x), dtype=bool)
    for a, b, c, d in zip(x1, y1, x2, y2):
        if b == d:
            continue
        cross = (y > min(b, d)) == (y <= max(b, d))
        xint = a + (y - b) * (c - a) / (d - b)
        inside ^= cross & (x < xint)
    return inside


def _is_convex_ccw(verts: np.ndarray) -> bool:
    """Whether a counter-clockwise ring (v, 2) is convex."""
    e = np.roll(verts, -1, axis=0) - verts
    cross = e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1)
    return bool((cross >= -1e-12).all())


def rects_in_polygon(corners: np.ndarray, poly: shapely.Polygon, shrink: float = 1e-4) -> np.ndarray:
    """(n,) bool: each rectangle (corners (n, 4, 2)) lies inside ``poly``.

    All corners (pulled ``shrink`` towards the centre, so rectangles flush with an edge pass) must
    be inside and no polygon vertex may lie strictly inside the rectangle: exact for the
    rectilinear and convex polygons rooms and support surfaces are made of.
    """
    n = len(corners)
    if n == 0:
        return np.zeros(0, dtype=bool)
    verts = np.asarray(poly.exterior.coords)[:-1]
    if not poly.interiors and _is_convex_ccw(verts):
        # Convex: every corner on the inner side of every edge (flush corners allowed).
        e = np.roll(verts, -1, axis=0) - verts
        rel = corners.reshape(-1, 1, 2) - verts[None]
        cross = e[None, :, 0] * rel[..., 1] - e[None, :, 1] * rel[..., 0]
        elen = np.linalg.norm(e, axis=1)
        return (cross >= -1e-7 * elen[None]).all(1).reshape(n, 4).all(1)
    centre = corners.mean(1, keepdims=True)
    vec = corners - centre
    norm = np.maximum(np.linalg.norm(vec, axis=-1, keepdims=True), 1e-12)
    pulled = corners - vec / norm * shrink
    inside = points_in_ring(pulled[..., 0].ravel(), pulled[..., 1].ravel(), verts).reshape(n, 4).all(1)
    for hole in poly.interiors:
        inside &= ~points_in_ring(pulled[..., 0].ravel(), pulled[..., 1].ravel(),
                                  np.asarray(hole.coords)[:-1]).reshape(n, 4).any(1)
    # A vertex strictly inside the rectangle: test in the rectangle's own frame.
    e0 = corners[:, 1] - corners[:, 0]
    e1 = corners[:, 3] - corners[:, 0]
    l0 = np.linalg.norm(e0, axis=-1)
    l1 = np.linalg.norm(e1, axis=-1)
    u0 = e0 / np.maximum(l0, 1e-12)[:, None]
    u1 = e1 / np.maximum(l1, 1e-12)[:, None]
    rel = verts[None, :, :] - corners[:, None, 0, :]
    p0 = (rel * u0[:, None, :]).sum(-1)
    p1 = (rel * u1[:, None, :]).sum(-1)
    tol = 1e-6
    vin = ((p0 > tol) & (p0 < l0[:, None] - tol) & (p1 > tol) & (p1 < l1[:, None] - tol)).any(1)
    return inside & ~vin


@dataclass(frozen=True)
class WallSegments:
    """The room's walls: wall i runs from ``start[i]`` to ``end[i]`` (polygon edge i).

    start, end, direction, normal: (W, 2) float64 (``normal`` points into the room); length (W,);
    ``yaw`` (W,): the yaw that puts an object's back (+y) against the wall, front into the room.
    """

    start: np.ndarray
    end: np.ndarray
    direction: np.ndarray
    normal: np.ndarray
    length: np.ndarray
    yaw: np.ndarray


def wall_segments(room: Room) -> WallSegments:
    """Wall segments of ``room`` with inward normals (the polygon is counter-clockwise)."""
    pts = np.asarray(room.polygon, dtype=np.float64)
    area2 = float(np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1]))
    start = pts
    end = np.roll(pts, -1, axis=0)
    vec = end - start
    length = np.linalg.norm(vec, axis=1)
    direction = vec / np.maximum(length, 1e-12)[:, None]
    sign = 1.0 if area2 > 0 else -1.0  # clockwise input: inward normal is on the right
    normal = sign * np.stack([-direction[:, 1], direction[:, 0]], 1)
    yaw = np.arctan2(normal[:, 0], -normal[:, 1])
    return WallSegments(start, end, direction, normal, length, yaw)


def world_bounds(size: tuple[float, float, float] | np.ndarray, pose: np.ndarray) -> np.ndarray:
    """(2, 3) float64 min/max corner of an asset's size box (canonical frame) under ``pose``."""
    w, d, h = (float(v) for v in size)
    corners = np.array([[sx * w / 2, sy * d / 2, sz * h] for sx in (-1, 1) for sy in (-1, 1) for sz in (0, 1)])
    pts = corners @ pose[:3, :3].T + pose[:3, 3]
    return np.stack([pts.min(0), pts.max(0)])


def footprint_polygon(size: tuple[float, float, float], pose: np.ndarray) -> shapely.Polygon:
    """The oriented footprint rectangle of an asset's size box under ``pose``."""
    x, y, _, yaw = pose_xyz_yaw(pose)
    return shapely.Polygon(rect_corners(np.array([x]), np.array([y]), np.array([yaw]), size[0], size[1])[0])


class InstanceBoxes:
    """Oriented 3-D boxes of placed instances as parallel arrays (an append-only broad phase).

    x, y, yaw, hw (half width), hd (half depth), z0, z1 (bottom, top), hx, hy (axis-aligned
    half extents), ids: all (n,) arrays.
    """

    FIELDS = ("x", "y", "yaw", "hw", "hd", "z0", "z1", "hx", "hy", "ids")

    def __init__(self) -> None:
        self._base = np.zeros((0, len(self.FIELDS)))  # boxes given at once (from_arrays)
        self._rows: list[tuple[float, ...]] = []  # boxes added one by one
        self._arrays: dict[str, np.ndarray] | None = None

    @classmethod
    def from_instances(cls, instances: tuple[PlacedInstance, ...] | list[PlacedInstance],
                       sizes: dict[str, tuple[float, float, float]]) -> "InstanceBoxes":
        if not instances:
            return cls()
        poses = np.stack([inst.pose for inst in instances])
        size = np.array([sizes[inst.asset] for inst in instances], dtype=np.float64).reshape(-1, 3)
        yaw = np.arctan2(poses[:, 1, 0], poses[:, 0, 0])
        hx, hy = rotated_half_extents(size[:, 0], size[:, 1], yaw)
        z = poses[:, 2, 3]
        cols = {"x": poses[:, 0, 3], "y": poses[:, 1, 3], "yaw": yaw, "hw": size[:, 0] / 2, "hd": size[:, 1] / 2,
                "z0": z, "z1": z + size[:, 2], "hx": hx, "hy": hy,
                "ids": np.array([inst.id for inst in instances], dtype=np.float64)}
        return cls.from_arrays(cols)

    @classmethod
    def from_arrays(cls, columns: dict[str, np.ndarray]) -> "InstanceBoxes":
        boxes = cls()
        boxes._base = np.stack([np.asarray(columns[k], dtype=np.float64) for k in cls.FIELDS], 1)
        return boxes

    def add(self, ident: int, x: float, y: float, yaw: float, z: float, size: tuple[float, float, float]) -> None:
        w, d, h = (float(v) for v in size)
        hx, hy = rotated_half_extents(w, d, yaw)
        self._rows.append((x, y, yaw, w / 2, d / 2, z, z + h, float(hx), float(hy), float(ident)))
        self._arrays = None

    def add_pose(self, ident: int, size: tuple[float, float, float], pose: np.ndarray) -> None:
        x, y, z, yaw = pose_xyz_yaw(pose)
        self.add(ident, x, y, yaw, z, size)

    def pop(self) -> None:
        """Remove the box added last with :meth:`add`."""
        self._rows.pop()
        self._arrays = None

    def __len__(self) -> int:
        return len(self._base) + len(self._rows)

    @property
    def a(self) -> dict[str, np.ndarray]:
        """The columns as (n,) float64 arrays (cached until the next change)."""
        if self._arrays is None:
            data = np.array(self._rows, dtype=np.float64).reshape(-1, len(self.FIELDS))
            if len(self._base):
                data = np.concatenate([self._base, data])
            self._arrays = {k: data[:, i] for i, k in enumerate(self.FIELDS)}
        return self._arrays

    def select(self, mask: np.ndarray) -> dict[str, np.ndarray]:
        return {k: v[mask] for k, v in self.a.items()}


def footprints_overlap(cx: np.ndarray, cy: np.ndarray, cyaw: np.ndarray, chw: float | np.ndarray,
                       chd: float | np.ndarray, boxes: dict[str, np.ndarray], margin: float) -> np.ndarray:
    """(n, m) bool: candidate footprints (n,) overlap (or come closer than ``margin`` to) the
    footprints of ``boxes`` (columns of :class:`InstanceBoxes`): an axis-aligned broad phase,
    then the exact separating-axis test on the surviving pairs."""
    n, m = len(cx), len(boxes["x"])
    out = np.zeros((n, m), dtype=bool)
    if n == 0 or m == 0:
        return out
    chw = np.broadcast_to(np.asarray(chw, float), (n,))
    chd = np.broadcast_to(np.asarray(chd, float), (n,))
    hx, hy = rotated_half_extents(chw * 2, chd * 2, cyaw)
    near = ((np.abs(boxes["x"][None] - cx[:, None]) < hx[:, None] + boxes["hx"][None] + margin)
            & (np.abs(boxes["y"][None] - cy[:, None]) < hy[:, None] + boxes["hy"][None] + margin))
    rows, cols = np.nonzero(near)
    if len(rows):
        ca, sa = np.cos(cyaw), np.sin(cyaw)  # per rectangle, not per pair (the same values)
        cb, sb = np.cos(boxes["yaw"]), np.sin(boxes["yaw"])
        out[rows, cols] = _obb_overlap_cs(boxes["x"][cols] - cx[rows], boxes["y"][cols] - cy[rows], ca[rows],
                                          sa[rows], chw[rows], chd[rows], cb[cols], sb[cols], boxes["hw"][cols],
                                          boxes["hd"][cols], margin)
    return out


def z_overlap(z0: np.ndarray, z1: np.ndarray, boxes: dict[str, np.ndarray]) -> np.ndarray:
    """(n, m) bool: height intervals [z0, z1] (n,) overlap those of ``boxes`` by more than 1 mm, or
    by more than half the thinner of the two when that is under 2 mm.

    The 1 mm tolerance lets a box rest on another; without the second rule a 1 mm banknote and a
    loaf on the same table (height overlap: the banknote's 1 mm) would not count as colliding.
    """
    overlap = np.minimum(z1[:, None], boxes["z1"][None]) - np.maximum(z0[:, None], boxes["z0"][None])
    thinner = np.minimum((z1 - z0)[:, None], (boxes["z1"] - boxes["z0"])[None])
    return overlap > np.minimum(1e-3, 0.5 * np.maximum(thinner, 1e-5))


def boxes_collide(cx: np.ndarray, cy: np.ndarray, cyaw: np.ndarray, chw: float | np.ndarray, chd: float | np.ndarray,
                  cz0: np.ndarray, cz1: np.ndarray, boxes: dict[str, np.ndarray], margin: float) -> np.ndarray:
    """(n,) bool: candidate boxes (n,) hit any of ``boxes`` (columns of :class:`InstanceBoxes`).

    Two boxes collide when their z ranges overlap by more than 1 mm and their footprints overlap
    or come closer than ``margin``.
    """
    n = len(cx)
    if n == 0 or len(boxes["x"]) == 0:
        return np.zeros(n, dtype=bool)
    zz = z_overlap(cz0, cz1, boxes)  # cheap: only the boxes some candidate meets in height need footprints
    cols = np.flatnonzero(zz.any(0))
    if len(cols) == 0:
        return np.zeros(n, dtype=bool)
    if len(cols) < len(boxes["x"]):
        boxes = {k: v[cols] for k, v in boxes.items()}
        zz = zz[:, cols]
    return (footprints_overlap(cx, cy, cyaw, chw, chd, boxes, margin) & zz).any(1)


def along_walls(walls, width: float, depth: float, step: float, gap: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres and yaws (x, y, yaw: (n,) float64) of a ``width`` x ``depth`` footprint with its back
    ``gap`` from each wall segment long enough for it, every ``step`` along the wall plus one flush
    with the wall's far end. ``walls`` is :func:`wall_segments`' result."""
    xs, ys, yaws = [], [], []
    for i in range(len(walls.length)):
        length = float(walls.length[i])
        if length < width:
            continue
        s = np.unique(np.append(np.arange(width / 2, length - width / 2 + 1e-6, step), length - width / 2))
        xs.append(walls.start[i, 0] + walls.direction[i, 0] * s + walls.normal[i, 0] * (depth / 2 + gap))
        ys.append(walls.start[i, 1] + walls.direction[i, 1] * s + walls.normal[i, 1] * (depth / 2 + gap))
        yaws.append(np.full_like(s, walls.yaw[i]))
    if not xs:
        e = np.zeros(0)
        return e, e, e
    return np.concatenate(xs), np.concatenate(ys), np.concatenate(yaws)

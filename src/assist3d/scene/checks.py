"""Physical checks of a layout on the actual meshes (boxes serve only as a broad phase).

``check_layout`` reports, one line per problem:

* **interpenetration**: for each pair of instances whose mesh bounds overlap by more than
  ``tol`` in x, y and z, points of one mesh (its vertices plus seeded surface samples, those
  inside the other's bounds) are tested against the other mesh. A point is *inside* when rays
  cast along the six axis directions cross the other mesh an odd number of times (crossings
  less than 1 mm apart counted once: catalog meshes often hold faces twice) in at least five of
  them (a vote that tolerates one hole of a non-watertight catalog mesh yet does not mistake
  the open cavity of a shelf, the space under a table or the inside of a single-sided rim for
  material), and
  it counts only if its depth (distance to the nearest crossing along 14 directions) exceeds
  ``tol``;
* **support**: an on-top object must touch its parent within ``tol``: rays cast straight down
  from ``tol`` above its lowest points must meet the parent's mesh within ``tol`` of the base for
  at least one of them (otherwise it floats; an object sunk into its support is reported by
  the interpenetration test);
* **floor**: a floor object's lowest point must be within ``tol`` of z = 0;
* **room**: every vertex must lie inside the room polygon grown by ``tol`` and between the floor
  and the ceiling height (``tol`` slack);
* **wall**: a wall object must touch the wall its back faces within ``tol``, must not pass
  through it, and must not cover a door or window of that wall;
* **siblings**: two objects on the same support whose height ranges overlap must not share more
  than 1 cm^2 of footprint (their boxes). The mesh test above cannot see a 1 mm banknote inside
  a loaf (no point of either is 1 cm deep in the other); this one can.
"""

from __future__ import annotations

import logging

import numpy as np
import shapely

from ..assets.catalog import Catalog
from ..core.contracts import MeshData, PlacedInstance, SceneLayout
from ..core.geometry import footprint_polygon, pose_xyz_yaw, room_polygon, wall_segments
from ..placement.surface import distinct_counts
from .assemble import instance_meshes

log = logging.getLogger(__name__)

__all__ = ["check_layout"]

SAMPLES = 800  # surface samples per mesh for the interpenetration test (plus its vertices)
MAX_POINTS = 6000
MIN_VOTES = 5  # of the six axis rays that must see the point inside
MAX_TESTED = 1500  # points of one mesh tested inside another, at most
AXES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64)
DIAGONALS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64) / np.sqrt(3)


class _Mesh:
    """A world-space mesh with lazily built trimesh objects (ray intersector, samples)."""

    def __init__(self, inst: PlacedInstance, mesh: MeshData):
        self.inst = inst
        self.v = mesh.vertices.astype(np.float64)
        self.f = mesh.faces
        self.lo = self.v.min(0) if len(self.v) else np.zeros(3)
        self.hi = self.v.max(0) if len(self.v) else np.zeros(3)
        self._tm = None
        self._points: np.ndarray | None = None

    @property
    def tm(self):
        if self._tm is None:
            import trimesh

            self._tm = trimesh.Trimesh(self.v, self.f, process=False)
        return self._tm

    def points(self) -> np.ndarray:
        """(n, 3) vertices plus seeded area-weighted surface samples."""
        if self._points is None:
            rng = np.random.default_rng(self.inst.id)
            tri = self.v[self.f]
            area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1) / 2
            pts = [self.v]
            if area.sum() > 0:
                pick = rng.choice(len(tri), SAMPLES, p=area / area.sum())
                u, w = rng.random((2, SAMPLES))
                flip = u + w > 1
                u[flip], w[flip] = 1 - u[flip], 1 - w[flip]
                t = tri[pick]
                pts.append(t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + w[:, None] * (t[:, 2] - t[:, 0]))
            p = np.concatenate(pts)
            if len(p) > MAX_POINTS:
                p = p[rng.choice(len(p), MAX_POINTS, replace=False)]
            self._points = p
        return self._points


def _crossings(tm, origins: np.ndarray, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(count (n,), nearest (n,)): how often rays from ``origins`` along ``direction`` cross ``tm``
    and the distance to the first crossing (inf if none)."""
    n = len(origins)
    dirs = np.tile(direction, (n, 1))
    locs, idx, _ = tm.ray.intersects_location(origins, dirs, multiple_hits=True)
    nearest = np.full(n, np.inf)
    dist = np.linalg.norm(locs - origins[idx], axis=1) if len(idx) else np.zeros(0)
    if len(idx):
        np.minimum.at(nearest, idx, dist)
    return distinct_counts(np.asarray(idx, dtype=np.int64), dist, n), nearest


def _inside_depth(points: np.ndarray, other: _Mesh, tol: float, seed: int) -> float:
    """An estimate of how deep ``points`` reach into ``other``'s material (0 if none is inside):
    the largest, over points voted inside, of the distance to the nearest crossing along 14 rays
    (6 axes, 8 diagonals), an upper bound of the distance to the surface that is tight for the
    axis-aligned and 45-degree faces furniture is made of."""
    sel = points[((points > other.lo + tol) & (points < other.hi - tol)).all(1)]
    if len(sel) == 0:
        return 0.0
    if len(sel) > MAX_TESTED:
        sel = sel[np.random.default_rng(seed).choice(len(sel), MAX_TESTED, replace=False)]
    votes = np.zeros(len(sel), dtype=np.int64)
    depth = np.full(len(sel), np.inf)
    for axis in AXES:
        count, nearest = _crossings(other.tm, sel, axis)
        votes += count % 2
        depth = np.minimum(depth, nearest)
    keep = (votes >= MIN_VOTES) & (depth > tol)
    if not keep.any():
        return 0.0
    sel, depth = sel[keep], depth[keep]
    for diag in DIAGONALS:
        locs, idx, _ = other.tm.ray.intersects_location(sel, np.tile(diag, (len(sel), 1)), multiple_hits=False)
        if len(idx):
            np.minimum.at(depth, idx, np.linalg.norm(locs - sel[idx], axis=1))
    depth = depth[np.isfinite(depth)]
    return float(depth.max()) if len(depth) else 0.0


def _check_pairs(meshes: list[_Mesh], tol: float) -> list[str]:
    if len(meshes) < 2:
        return []
    lo = np.stack([m.lo for m in meshes])
    hi = np.stack([m.hi for m in meshes])
    overlap = (np.minimum(hi[:, None], hi[None]) - np.maximum(lo[:, None], lo[None]) > tol).all(-1)
    ii, jj = np.nonzero(np.triu(overlap, 1))
    out = []
    for i, j in zip(ii, jj):
        a, b = meshes[i], meshes[j]
        depth = max(_inside_depth(a.points(), b, tol, int(a.inst.id)), _inside_depth(b.points(), a, tol, int(b.inst.id)))
        if depth > tol:
            rel = " (resting on it)" if b.inst.parent == a.inst.id or a.inst.parent == b.inst.id else ""
            out.append(f"instances {a.inst.id} ({a.inst.class_name}) and {b.inst.id} ({b.inst.class_name}){rel} "
                       f"interpenetrate by {depth * 100:.1f} cm")
    return out


def _check_support(m: _Mesh, parent: _Mesh, tol: float) -> str | None:
    zmin = m.lo[2]
    bottom = m.v[m.v[:, 2] <= zmin + 0.005]
    if len(bottom) > 400:
        bottom = bottom[np.random.default_rng(m.inst.id).choice(len(bottom), 400, replace=False)]
    origins = bottom.copy()
    origins[:, 2] = zmin + tol
    dirs = np.tile(np.array([0.0, 0.0, -1.0]), (len(origins), 1))
    locs, idx, _ = parent.tm.ray.intersects_location(origins, dirs, multiple_hits=False)
    name = f"instance {m.inst.id} ({m.inst.class_name}) on {parent.inst.id} ({parent.inst.class_name})"
    if len(locs) == 0:
        return f"{name}: floats (nothing of its support below it)"
    gap = zmin - locs[:, 2]  # >= -tol: the surface met below the ray origin
    if gap.min() > tol:
        return f"{name}: floats {gap.min() * 100:.1f} cm above its support"
    return None


def _check_wall(m: _Mesh, layout: SceneLayout, tol: float) -> str | None:
    walls = wall_segments(layout.room)
    _, _, _, yaw = pose_xyz_yaw(m.inst.pose)
    back = np.array([-np.sin(yaw), np.cos(yaw)])
    name = f"wall instance {m.inst.id} ({m.inst.class_name})"
    facing = np.flatnonzero(walls.normal @ back < -0.999)
    best: tuple[float, int] | None = None
    for i in facing:
        dist = (m.v[:, :2] - walls.start[i]) @ walls.normal[i]
        along = (m.v[:, :2] - walls.start[i]) @ walls.direction[i]
        if along.min() < -tol or along.max() > walls.length[i] + tol:
            continue
        if best is None or abs(dist.min()) < abs(best[0]):
            best = (float(dist.min()), int(i))
    if best is None:
        return f"{name}: no wall behind it"
    gap, i = best
    if gap > tol:
        return f"{name}: {gap * 100:.1f} cm off wall {i}"
    if gap < -tol:
        return f"{name}: {-gap * 100:.1f} cm through wall {i}"
    along = (m.v[:, :2] - walls.start[i]) @ walls.direction[i]
    for o in layout.room.openings:
        if o.wall != i:
            continue
        ds = min(along.max(), o.offset + o.width / 2) - max(along.min(), o.offset - o.width / 2)
        dz = min(m.hi[2], o.top) - max(m.lo[2], o.bottom)
        if ds > tol and dz > tol:
            return f"{name}: covers a {o.kind} of wall {i}"
    return None


def check_layout(layout: SceneLayout, catalog: Catalog, *, tol: float = 0.01) -> list[str]:
    """Problems of ``layout`` found on the meshes (see the module docstring). Empty = good."""
    meshes = [_Mesh(inst, mesh) for inst, (_, mesh) in zip(layout.instances, instance_meshes(layout, catalog))]
    by_id = {m.inst.id: m for m in meshes}
    problems: list[str] = []
    poly = room_polygon(layout.room).buffer(tol, join_style="mitre")
    for m in meshes:
        name = f"instance {m.inst.id} ({m.inst.class_name})"
        if len(m.v) == 0:
            continue
        outside = ~shapely.contains_xy(poly, m.v[:, 0], m.v[:, 1])
        if outside.any() or m.lo[2] < -tol or m.hi[2] > layout.room.height + tol:
            problems.append(f"{name}: outside the room")
        if m.inst.group == "floor" and m.inst.parent is None and abs(m.lo[2]) > tol:
            problems.append(f"{name}: base {m.lo[2] * 100:.1f} cm from the floor")
        elif m.inst.group == "wall":
            p = _check_wall(m, layout, tol)
            if p:
                problems.append(p)
        if m.inst.parent is not None:
            parent = by_id.get(m.inst.parent)
            if parent is None:
                problems.append(f"{name}: parent {m.inst.parent} is not in the layout")
            else:
                p = _check_support(m, parent, tol)
                if p:
                    problems.append(p)
    problems.extend(_check_pairs(meshes, tol))
    problems.extend(check_siblings(layout, catalog))
    return problems


def check_siblings(layout: SceneLayout, catalog: Catalog, *, min_area: float = 1e-4) -> list[str]:
    """Pairs of on-top objects of one support whose heights overlap and whose footprint boxes
    share more than ``min_area`` m^2 (see the module docstring)."""
    by_parent: dict[int, list] = {}
    for inst in layout.instances:
        if inst.parent is None:
            continue
        size = catalog.get(inst.asset).size
        z = pose_xyz_yaw(inst.pose)[2]
        by_parent.setdefault(inst.parent, []).append((inst, z, z + float(size[2]), footprint_polygon(size, inst.pose)))
    problems = []
    for items in by_parent.values():
        for a in range(len(items)):
            for b in range(a + 1, len(items)):
                ia, za0, za1, pa = items[a]
                ib, zb0, zb1, pb = items[b]
                area = pa.intersection(pb).area
                if min(za1, zb1) - max(za0, zb0) > 1e-6 and area > min_area:
                    problems.append(f"instances {ia.id} ({ia.class_name}) and {ib.id} ({ib.class_name}) overlap on "
                                    f"their support ({area * 1e4:.0f} cm^2 of footprint)")
    return problems

"""On-top objects: candidates on a grid inside the support's surfaces.

Each ``SupportSurface`` of the support's asset (height, polygon in the asset frame, optional free
``clearance`` above) is carried into the world by the support's pose. Candidates lie on the 2 cm
grid of the surface's height map (:mod:`.surface`, thinned to a few hundred per yaw) at
``rotations`` yaws aligned with the support plus ``rotations`` yaws turned by a seeded random
offset per object. A candidate's footprint must lie
inside the polygon, its height must fit under the surface's clearance and the ceiling, and its
3-D box must not collide with the other objects on the support nor with anything else placed
(wall objects overhead, neighbours), and the support's mesh must really carry it there
(:mod:`.surface`: the mesh top under the footprint is at the surface height and nothing of the
mesh is in the way above). The base sits exactly at the surface height.
"""

from __future__ import annotations

import numpy as np
import shapely

from ..config import LayoutConfig
from ..core.contracts import MeshData, PlacedInstance, Room, SupportSurface
from ..core.geometry import InstanceBoxes, boxes_collide, pose_xyz_yaw, world_bounds
from .common import Item, MovingBoxesMixin, RelationState, order_candidates, target_box
from .scoring import Candidates
from .search import Choice
from .surface import MeshTriangles, surface_map

EPS = 1e-6


def _clean_polygon(points: tuple[tuple[float, float], ...]) -> shapely.Polygon:
    """A valid polygon from a record's outline (a self-crossing outline keeps its largest piece)."""
    poly = shapely.Polygon(points)
    if not poly.is_valid:
        fixed = poly.buffer(0)
        parts = list(getattr(fixed, "geoms", [fixed]))
        poly = max(parts, key=lambda g: g.area) if parts else shapely.Polygon()
    return shapely.orient_polygons(poly) if poly.area > 0 else poly


class OnTopProblem(MovingBoxesMixin):
    """One on-top group as a :class:`~assist3d.placement.search.SearchProblem`."""

    def __init__(self, room: Room, items: list[Item], support: PlacedInstance,
                 surfaces: tuple[SupportSurface, ...], placed: tuple[PlacedInstance, ...],
                 sizes: dict[str, tuple[float, float, float]], cfg: LayoutConfig, rng: np.random.Generator,
                 max_branch: int, support_mesh: MeshData, map_key: tuple):
        self.room, self.items, self.cfg, self.rng = room, items, cfg, rng
        self.n = len(items)
        self.max_branch = max_branch
        self.support = support
        self.sx, self.sy, self.sz, self.syaw = pose_xyz_yaw(support.pose)
        self.surfaces = [s for s in surfaces if len(s.polygon) >= 3]
        self.polys = [_clean_polygon(s.polygon) for s in self.surfaces]
        keep = [i for i, p in enumerate(self.polys) if p.area > 0]
        self.surfaces = [self.surfaces[i] for i in keep]
        self.polys = [self.polys[i] for i in keep]
        sb = world_bounds(sizes[support.asset], support.pose)
        others = InstanceBoxes.from_instances([p for p in placed if p.id != support.id], sizes)
        if len(others):
            a = others.a
            near = ((a["x"] - a["hx"] < sb[1, 0] + 0.1) & (a["x"] + a["hx"] > sb[0, 0] - 0.1)
                    & (a["y"] - a["hy"] < sb[1, 1] + 0.1) & (a["y"] + a["hy"] > sb[0, 1] - 0.1))
            others = InstanceBoxes.from_arrays(others.select(near))
        self.others = others
        self.moving = InstanceBoxes()
        self.cross = {support.id: target_box(support, sizes[support.asset])}
        self.rel = RelationState(items, self.cross)
        step = 2 * np.pi / max(cfg.rotations, 1)
        self.yaw_offset = rng.uniform(0.0, step, size=self.n)
        self.cap = cfg.max_on_top_per_support
        self.avoidable_after = np.zeros(self.n + 1, dtype=np.int64)  # avoidable items in k..n-1
        tri = MeshTriangles(support_mesh)
        self.maps = [surface_map(map_key + (i,), support_mesh, surf, poly, tri)
                     for i, (surf, poly) in enumerate(zip(self.surfaces, self.polys))]
        self._forced: list[str | None] = [None] * self.n
        self._cache: dict[int, Candidates] = {}
        for k in range(self.n - 1, -1, -1):
            self._forced[k] = self._unavoidable(k)
            self.avoidable_after[k] = self.avoidable_after[k + 1] + (self._forced[k] is None)

    def _raw(self, k: int) -> Candidates:
        """Candidates of item ``k`` that lie inside a surface and fit under its clearance."""
        w, d, h = (float(v) for v in self.items[k].record.size)
        parts: list[Candidates] = []
        rot = max(self.cfg.rotations, 1)
        steps = np.arange(rot) * (2 * np.pi / rot)
        yaws = np.concatenate([steps, self.yaw_offset[k] + steps])  # aligned with the support, and turned
        c, s = np.cos(self.syaw), np.sin(self.syaw)
        for surf, smap in zip(self.surfaces, self.maps):
            if surf.clearance is not None and h > surf.clearance - 0.005:
                continue
            z = self.sz + surf.height
            if z + h > self.room.height - 0.02:
                continue
            lx, ly, lyaw = smap.centres(w, d, h, yaws)
            if len(lx) == 0:
                continue
            wx = self.sx + c * lx - s * ly
            wy = self.sy + s * lx + c * ly
            parts.append(Candidates(wx, wy, np.mod(lyaw + self.syaw, 2 * np.pi), np.full_like(wx, z), (w, d, h)))
        return Candidates.concat(parts, (w, d, h))

    def _collide(self, k: int, cands: Candidates, include_moving: bool, include_others: bool = True) -> np.ndarray:
        w, d, h = (float(v) for v in self.items[k].record.size)
        hit = np.zeros(len(cands), dtype=bool)
        for boxes in ([self.others] if include_others else []) + ([self.moving] if include_moving else []):
            if len(boxes) and len(cands):
                hit |= boxes_collide(cands.x, cands.y, cands.yaw, w / 2, d / 2, cands.z, cands.z + h, boxes.a,
                                     min(self.cfg.clearance, 0.01))
        return hit

    def _unavoidable(self, k: int) -> str | None:
        item = self.items[k]
        if item.forced_reason:
            return item.forced_reason
        if not self.surfaces:
            return f"support {self.support.asset} has no support surface"
        w, d, h = item.record.size
        c = self._raw(k)
        if len(c) == 0:
            return f"its {w:.2f} x {d:.2f} x {h:.2f} m box fits on no surface of the support ({self.support.asset})"
        free = c.take(np.flatnonzero(~self._collide(k, c, include_moving=False)))
        if len(free) == 0:
            return "every position on the support is blocked by other objects"
        self._cache[k] = free
        return None

    def unavoidable(self, k: int) -> str | None:
        return self._forced[k]

    def candidates(self, k: int) -> tuple[list[Choice], str]:
        if len(self.moving) >= self.cap:
            return [], f"the support already holds {self.cap} objects (max_on_top_per_support)"
        w, d, _ = self.items[k].record.size
        c = self._cache[k]
        ok = ~self._collide(k, c, include_moving=True, include_others=False)
        if not ok.any():
            return [], "no free position left on the support"
        c = c.take(np.flatnonzero(ok))
        c, score, why = self.rel.satisfying(k, c, "position on the support")
        if why:
            return [], why
        return order_candidates(c, score, score, self.rng, self.max_branch, max(0.5 * max(w, d), 0.05)), ""

    def min_future_skips(self, k: int, placed: int) -> int:
        return max(0, int(self.avoidable_after[k]) - max(self.cap - placed, 0))


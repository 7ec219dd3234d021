"""Wall objects: candidates every ``wall_step`` along each wall, back flush with it, at heights.

A candidate is (wall, position along it, base height). Its box (width x depth x height, back on
the wall, front into the room) must lie inside the room in plan view, must not cover a door or
window opening (or hang in a door's clearance zone below the door's top), and must not collide in
3-D with floor objects (it may hang above a low one) or with other wall objects. Heights come
from a ``height`` relation (value = (lo, hi) metres of the base), else from the asset's
``elevation`` (+- 0.3 m), else from a default band of 0.9-1.6 m; the top always stays
``TOP_MARGIN`` below the ceiling.
"""

from __future__ import annotations

import numpy as np

from ..config import LayoutConfig
from ..core.contracts import PlacedInstance, Room
from ..core.geometry import (InstanceBoxes, along_walls, footprints_overlap, rect_corners, rects_in_polygon, room_polygon,
                        wall_segments, z_overlap)
from .common import PRIOR_WEIGHT, Item, MovingBoxesMixin, RelationState, order_candidates, target_box
from .scoring import Candidates
from .search import Choice

TOP_MARGIN = 0.05  # free space kept between a wall object's top and the ceiling, m
DEFAULT_BAND = (0.9, 1.6)  # base height band of wall objects without a height relation, m
HEIGHT_STEP = 0.1  # spacing of candidate base heights, m
WALL_GAP = 0.001  # gap between a wall object's back and the wall, m
EPS = 1e-6


class WallProblem(MovingBoxesMixin):
    """The wall group as a :class:`~assist3d.placement.search.SearchProblem`."""

    def __init__(self, room: Room, items: list[Item], placed: tuple[PlacedInstance, ...],
                 sizes: dict[str, tuple[float, float, float]], cfg: LayoutConfig, rng: np.random.Generator,
                 max_branch: int):
        self.room, self.items, self.cfg, self.rng = room, items, cfg, rng
        self.n = len(items)
        self.max_branch = max_branch
        self.poly = room_polygon(room)
        self.walls = wall_segments(room)
        self.fixed = InstanceBoxes()  # openings, door zones, floor objects: never move
        wl = self.walls
        for op in room.openings:
            if not 0 <= op.wall < len(wl.length):
                continue
            u, nrm, yaw = wl.direction[op.wall], wl.normal[op.wall], float(wl.yaw[op.wall])
            depth = 0.05
            c = wl.start[op.wall] + u * op.offset + nrm * depth / 2
            self.fixed.add(-1, float(c[0]), float(c[1]), yaw, op.bottom, (op.width, depth, op.top - op.bottom))
            if op.kind == "door" and cfg.door_clearance > 0:
                c = wl.start[op.wall] + u * op.offset + nrm * cfg.door_clearance / 2
                self.fixed.add(-1, float(c[0]), float(c[1]), yaw, 0.0, (op.width + 0.1, cfg.door_clearance, op.top))
        for inst in placed:
            self.fixed.add_pose(inst.id, sizes[inst.asset], inst.pose)
        self.moving = InstanceBoxes()
        self.cross = {inst.id: target_box(inst, sizes[inst.asset]) for inst in placed}
        self.rel = RelationState(items, self.cross)
        self._levels = [self._height_levels(k) for k in range(self.n)]
        self._cache: dict[int, tuple[Candidates, np.ndarray]] = {}

    def _height_levels(self, k: int) -> tuple[np.ndarray, float]:
        """Candidate base heights of item ``k`` and the preferred one."""
        item = self.items[k]
        h = float(item.record.size[2])
        zmax = self.room.height - h - TOP_MARGIN
        rel = next((r for r in item.relations if r.kind == "height"), None)
        if rel is not None and rel.hard:
            lo, hi = rel.value
        elif item.record.elevation > 0:
            lo, hi = item.record.elevation - 0.3, item.record.elevation + 0.3
        else:
            lo, hi = DEFAULT_BAND
        if rel is not None and not rel.hard:
            lo, hi = min(lo, rel.value[0]), max(hi, rel.value[1])
        lo = max(lo, 0.0)
        hi = min(hi, zmax)
        if hi < lo - EPS:
            if zmax < 0 or (rel is not None and rel.hard):
                return np.zeros(0), 0.0
            lo = hi = zmax  # a tall item: as high as the room allows
        levels = np.unique(np.append(np.arange(lo, hi + EPS, HEIGHT_STEP), hi))
        pref = item.record.elevation if item.record.elevation > 0 else (lo + hi) / 2
        if rel is not None:
            pref = (rel.value[0] + rel.value[1]) / 2
        return levels, float(pref)

    def _positions(self, k: int) -> Candidates:
        """Item ``k``'s positions along all walls (z = 0) whose footprint stays inside the room."""
        w, d, h = (float(v) for v in self.items[k].record.size)
        x, y, yaw = along_walls(self.walls, w, d, self.cfg.wall_step, WALL_GAP)
        if len(x) == 0:
            e = np.zeros(0)
            return Candidates(e, e, e, e, (w, d, h))
        inside = rects_in_polygon(rect_corners(x, y, yaw, w, d), self.poly)
        return Candidates(x[inside], y[inside], yaw[inside], np.zeros(int(inside.sum())), (w, d, h))

    def _hits(self, k: int, pos: Candidates, levels: np.ndarray, boxes: InstanceBoxes) -> np.ndarray:
        """(positions, levels) bool: the box at each position and base height hits ``boxes``.

        Footprint overlaps (positions x boxes) and height overlaps (levels x boxes) are computed
        separately and combined with one matrix product.
        """
        w, d, h = (float(v) for v in self.items[k].record.size)
        if len(boxes) == 0 or len(pos) == 0:
            return np.zeros((len(pos), len(levels)), dtype=bool)
        a = boxes.a
        xy = footprints_overlap(pos.x, pos.y, pos.yaw, w / 2, d / 2, a, self.cfg.clearance)
        zz = z_overlap(levels, levels + h, a)
        return (xy.astype(np.float32) @ zz.T.astype(np.float32)) > 0

    def _static(self, k: int) -> tuple[Candidates, np.ndarray]:
        """Item ``k``'s positions and the (positions, levels) mask of those free of openings,
        door zones and floor objects (cached)."""
        hit = self._cache.get(k)
        if hit is None:
            pos = self._positions(k)
            levels = self._levels[k][0]
            hit = (pos, ~self._hits(k, pos, levels, self.fixed))
            self._cache[k] = hit
        return hit

    def _expand(self, k: int, pos: Candidates, mask: np.ndarray) -> Candidates:
        levels = self._levels[k][0]
        pi, li = np.nonzero(mask)
        return Candidates(pos.x[pi], pos.y[pi], pos.yaw[pi], levels[li], pos.size)

    def unavoidable(self, k: int) -> str | None:
        item = self.items[k]
        if item.forced_reason:
            return item.forced_reason
        w, d, h = item.record.size
        if len(self._levels[k][0]) == 0:
            return f"no base height fits its {h:.2f} m height under the {self.room.height:.2f} m ceiling"
        pos, free = self._static(k)
        if len(pos) == 0:
            return f"its {w:.2f} m width fits on no wall"
        if not free.any():
            return "every wall position is blocked by openings or floor objects"
        return None

    def candidates(self, k: int) -> tuple[list[Choice], str]:
        w, d, h = self.items[k].record.size
        pos, free = self._static(k)
        ok = free & ~self._hits(k, pos, self._levels[k][0], self.moving)
        if not ok.any():
            return [], f"no free wall position for its {w:.2f} m x {h:.2f} m front"
        c = self._expand(k, pos, ok)
        c, score, why = self.rel.satisfying(k, c, "wall position")
        if why:
            return [], why
        pref = self._levels[k][1]
        prior = 1.0 - np.clip(np.abs(c.z - pref) / 1.0, 0, 1)
        rank = score + PRIOR_WEIGHT * prior
        return order_candidates(c, rank, score, self.rng, self.max_branch, max(0.5 * float(w), 0.3)), ""

    def min_future_skips(self, k: int, placed: int) -> int:
        return 0


"""Floor objects: candidates on a grid over the room, validated with an occupancy raster.

The room is rasterised on a fine grid (a third of ``cell_size``, at most 5 cm; every wall
coordinate of the polygon is a cell border, so axis-aligned walls fall exactly on borders). A fine cell is *blocked*
when it is not entirely inside the room polygon, lies in a door's clearance zone, or is touched
by a placed object's footprint grown by ``clearance``. A candidate (centre on the ``cell_size``
grid, or snapped with its back against a wall, times ``rotations`` yaws) is valid when no cell
its footprint touches is blocked: one summed-area table per search node answers that for all
candidates at once. The test is conservative (an object may stay up to one fine cell further
from its neighbours than needed, and non-axis-aligned footprints are tested by their bounding
box), so a valid candidate never overlaps anything. The front of every candidate must keep
``front_clearance`` to the walls.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from scipy import ndimage

from ..config import LayoutConfig
from ..core.contracts import Room
from ..core.geometry import along_walls, room_polygon, rotated_half_extents, wall_segments
from .common import PRIOR_WEIGHT, Item, RelationState, order_candidates
from .scoring import Candidates, TargetBox
from .search import Choice

EPS = 1e-6
SNAP_GAP = 0.002  # gap between a wall-snapped object's back and the wall, m


def _sums(sat: np.ndarray, i0: np.ndarray, i1: np.ndarray, j0: np.ndarray, j1: np.ndarray) -> np.ndarray:
    """(rows, cols) sums of the summed-area table over the rectangles [j0, j1) x [i0, i1) formed
    by every row range (j) with every column range (i); out-of-grid indices are clipped."""
    nyp, nxp = sat.shape
    i0, i1 = np.maximum(i0, 0), np.minimum(i1, nxp - 1)
    hi, lo = sat[np.minimum(j1, nyp - 1)], sat[np.maximum(j0, 0)]  # rows first, then columns: two 1-d gathers
    return hi[:, i1] - lo[:, i1] - hi[:, i0] + lo[:, i0]


def _rect_sums(sat: np.ndarray, i0: np.ndarray, i1: np.ndarray, j0: np.ndarray, j1: np.ndarray) -> np.ndarray:
    """(n,) sums of the summed-area table over rectangles [j0, j1) x [i0, i1) (indices clipped)."""
    nyp, nxp = sat.shape
    i0, i1 = np.maximum(i0, 0), np.minimum(i1, nxp - 1)
    j0, j1 = np.maximum(j0, 0), np.minimum(j1, nyp - 1)
    return sat[j1, i1] - sat[j0, i1] - sat[j1, i0] + sat[j0, i0]


def _breaks(lo: float, hi: float, coords: np.ndarray, fine: float) -> np.ndarray:
    """Cell borders from ``lo`` to ``hi``: every wall coordinate is a border, the spans between
    them are split evenly into cells no wider than ``fine``."""
    knots = np.unique(np.concatenate([[lo, hi], coords]))
    out = [knots[:1]]
    for a, b in zip(knots[:-1], knots[1:]):
        m = max(1, math.ceil((b - a) / fine - 1e-9))
        out.append(np.linspace(a, b, m + 1)[1:])
    return np.concatenate(out)


class FloorGrid:
    """A fine raster of the room: ``outside`` and ``static`` (outside or door zone) masks.

    Cell borders ``xb`` (nx + 1,) and ``yb`` (ny + 1,) include every vertex coordinate of the
    room polygon, so axis-aligned walls lie exactly on cell borders.
    """

    def __init__(self, room: Room, cell_size: float, door_clearance: float):
        self.poly = room_polygon(room)
        minx, miny, maxx, maxy = self.poly.bounds
        fine = float(np.clip(cell_size / 3.0, 0.02, 0.05))
        pts = np.asarray(room.polygon, dtype=np.float64)
        self.xb = _breaks(minx, maxx, pts[:, 0], fine)
        self.yb = _breaks(miny, maxy, pts[:, 1], fine)
        self.nx, self.ny = len(self.xb) - 1, len(self.yb) - 1
        gx0, gy0 = np.meshgrid(self.xb[:-1], self.yb[:-1])
        gx1, gy1 = np.meshgrid(self.xb[1:], self.yb[1:])
        inside = np.ones(gx0.shape, dtype=bool)
        for cx, cy in ((gx0, gy0), (gx1, gy0), (gx1, gy1), (gx0, gy1)):
            inside &= shapely.intersects_xy(self.poly, cx, cy)
        self.outside = ~inside
        self.static = self.outside.copy()
        walls = wall_segments(room)
        for op in room.openings:
            if op.kind != "door" or door_clearance <= 0 or not 0 <= op.wall < len(walls.length):
                continue
            u, nrm = walls.direction[op.wall], walls.normal[op.wall]
            centre = walls.start[op.wall] + u * op.offset + nrm * (door_clearance / 2)
            yaw = float(walls.yaw[op.wall])
            ex, ey = rotated_half_extents(op.width + 0.1, door_clearance, yaw)
            self.fill(self.static, centre[0], centre[1], float(ex), float(ey), True)
        # Distance of every cell centre to the nearest wall (for edge/middle scores and priors).
        mx = (gx0 + gx1) / 2
        my = (gy0 + gy1) / 2
        dist = np.zeros(mx.shape)  # only the cells inside are asked for (the others read 0)
        dist[inside] = shapely.distance(self.poly.exterior, shapely.points(mx[inside], my[inside]))
        self.wall_dist = dist
        self.outside_sat = self.sat(self.outside)

    def ranges(self, cx: np.ndarray, cy: np.ndarray, ex: np.ndarray, ey: np.ndarray):
        """Index ranges [i0, i1) x [j0, j1) of the cells touched by axis-aligned rectangles
        (i0 = -1 or i1 = n + 1 when a rectangle leaves the grid)."""
        i0 = np.searchsorted(self.xb, cx - ex + EPS, "right") - 1
        i1 = np.searchsorted(self.xb, cx + ex - EPS, "left")
        j0 = np.searchsorted(self.yb, cy - ey + EPS, "right") - 1
        j1 = np.searchsorted(self.yb, cy + ey - EPS, "left")
        return i0, i1, j0, j1

    def fill(self, grid: np.ndarray, cx: float, cy: float, ex: float, ey: float, value) -> tuple[int, int, int, int]:
        i0, i1, j0, j1 = (int(v) for v in self.ranges(np.float64(cx), np.float64(cy), np.float64(ex), np.float64(ey)))
        i0, j0 = max(i0, 0), max(j0, 0)
        i1, j1 = min(max(i1, i0), self.nx), min(max(j1, j0), self.ny)
        if grid.dtype == bool:
            grid[j0:j1, i0:i1] = value
        else:
            grid[j0:j1, i0:i1] += value
        return i0, i1, j0, j1

    @staticmethod
    def sat(mask: np.ndarray) -> np.ndarray:
        s = np.zeros((mask.shape[0] + 1, mask.shape[1] + 1), dtype=np.int32)
        np.cumsum(np.cumsum(mask, 0, dtype=np.int32), 1, out=s[1:, 1:])
        return s

    def free(self, sat: np.ndarray, cx: np.ndarray, cy: np.ndarray, ex: np.ndarray, ey: np.ndarray) -> np.ndarray:
        """(n,) bool: rectangles lie on the grid and touch no blocked cell of ``sat``'s mask."""
        i0, i1, j0, j1 = self.ranges(cx, cy, ex, ey)
        ok = (i0 >= 0) & (j0 >= 0) & (i1 <= self.nx) & (j1 <= self.ny)
        return ok & (_rect_sums(sat, i0, i1, j0, j1) == 0)

    def dist_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        i = np.minimum(np.maximum(np.searchsorted(self.xb, x, "right") - 1, 0), self.nx - 1)
        j = np.minimum(np.maximum(np.searchsorted(self.yb, y, "right") - 1, 0), self.ny - 1)
        return self.wall_dist[j, i]


class FloorProblem:
    """The floor group as a :class:`~assist3d.placement.search.SearchProblem`."""

    def __init__(self, room: Room, items: list[Item], cfg: LayoutConfig, rng: np.random.Generator,
                 max_branch: int):
        self.room, self.items, self.cfg, self.rng = room, items, cfg, rng
        self.n = len(items)
        self.max_branch = max_branch
        self.grid = FloorGrid(room, cfg.cell_size, cfg.door_clearance)
        self.occ = np.zeros((self.grid.ny, self.grid.nx), dtype=np.int16)
        self.filled: dict[int, tuple[int, int, int, int]] = {}
        self.rel = RelationState(items, {})
        self.walls = wall_segments(room)
        minx, miny, maxx, maxy = self.grid.poly.bounds
        cs = cfg.cell_size
        gx = np.arange(minx + cs / 2, maxx, cs)
        gy = np.arange(miny + cs / 2, maxy, cs)
        self.gx, self.gy = gx, gy
        self.yaws = np.arange(cfg.rotations) * (2 * np.pi / cfg.rotations)
        self.static_sat = self.grid.sat(self.grid.static)
        self._cache: dict[int | tuple, tuple[Candidates, tuple[np.ndarray, ...]]] = {}  # by item, by size
        self._sat: np.ndarray | None = None
        self.hmax = float(max(np.diff(self.grid.xb).max(), np.diff(self.grid.yb).max()))
        self._static_radius = self._free_radius(self.grid.static)

    # ------------------------------------------------------------ candidates

    def _cell_index(self, v: np.ndarray, borders: np.ndarray) -> np.ndarray:
        return np.minimum(np.maximum(np.searchsorted(borders, v, "right") - 1, 0), len(borders) - 2)

    def _grid_part(self, w: float, d: float, h: float, yaw: float) -> tuple[Candidates, tuple[np.ndarray, ...]]:
        """Grid candidates at one yaw valid in the empty room, with their footprints' cell ranges.

        Cell ranges are separable (x ranges depend on the column only, y ranges on the row), so
        they are computed per grid column and row and combined by broadcasting.
        """
        g = self.grid
        gx, gy = self.gx, self.gy
        ex, ey = (float(v) for v in rotated_half_extents(w, d, yaw))
        i0 = np.searchsorted(g.xb, gx - ex + EPS, "right") - 1
        i1 = np.searchsorted(g.xb, gx + ex - EPS, "left")
        j0 = np.searchsorted(g.yb, gy - ey + EPS, "right") - 1
        j1 = np.searchsorted(g.yb, gy + ey - EPS, "left")
        valid = (((i0 >= 0) & (i1 <= g.nx))[None, :] & ((j0 >= 0) & (j1 <= g.ny))[:, None])
        valid &= _sums(self.static_sat, i0, i1, j0, j1) == 0
        fc = self.cfg.front_clearance
        fx, fy = float(np.sin(yaw)), -float(np.cos(yaw))
        if fc > 0:
            zex, zey = (float(v) for v in rotated_half_extents(w, fc, yaw))
            zx, zy = gx + fx * (d / 2 + fc / 2), gy + fy * (d / 2 + fc / 2)
            a0 = np.searchsorted(g.xb, zx - zex + EPS, "right") - 1
            a1 = np.searchsorted(g.xb, zx + zex - EPS, "left")
            b0 = np.searchsorted(g.yb, zy - zey + EPS, "right") - 1
            b1 = np.searchsorted(g.yb, zy + zey - EPS, "left")
            valid &= (((a0 >= 0) & (a1 <= g.nx))[None, :] & ((b0 >= 0) & (b1 <= g.ny))[:, None])
            valid &= _sums(g.outside_sat, a0, a1, b0, b1) == 0
        jj, ii = np.nonzero(valid)
        x, y = gx[ii], gy[jj]
        bi = self._cell_index(gx - fx * d / 2, g.xb)[ii]
        bj = self._cell_index(gy - fy * d / 2, g.yb)[jj]
        ci = self._cell_index(gx, g.xb)[ii]
        cj = self._cell_index(gy, g.yb)[jj]
        c = Candidates(x, y, np.full_like(x, yaw), np.zeros_like(x), (w, d, h), g.wall_dist[bj, bi],
                       g.wall_dist[cj, ci] - max(ex, ey))
        return c, (i0[ii], i1[ii], j0[jj], j1[jj])

    def _snapped_part(self, w: float, d: float, h: float) -> tuple[Candidates, tuple[np.ndarray, ...]]:
        """Candidates with the back against a wall (2 mm gap), valid in the empty room."""
        g = self.grid
        x, y, yaw = along_walls(self.walls, w, d, self.cfg.cell_size, SNAP_GAP)
        if len(x) == 0:
            e = np.zeros(0)
            return Candidates(e, e, e, e, (w, d, h), e, e), (e.astype(int),) * 4
        ex, ey = rotated_half_extents(w, d, yaw)
        i0, i1, j0, j1 = g.ranges(x, y, ex, ey)
        ok = (i0 >= 0) & (j0 >= 0) & (i1 <= g.nx) & (j1 <= g.ny) & (_rect_sums(self.static_sat, i0, i1, j0, j1) == 0)
        fc = self.cfg.front_clearance
        if fc > 0:
            fx, fy = np.sin(yaw), -np.cos(yaw)
            zex, zey = rotated_half_extents(w, fc, yaw)
            ok &= g.free(g.outside_sat, x + fx * (d / 2 + fc / 2), y + fy * (d / 2 + fc / 2), zex, zey)
        k = np.flatnonzero(ok)
        c = Candidates(x[k], y[k], yaw[k], np.zeros(len(k)), (w, d, h), np.full(len(k), SNAP_GAP),
                       g.dist_at(x[k], y[k]) - np.maximum(ex[k], ey[k]))
        return c, (i0[k], i1[k], j0[k], j1[k])

    def _static(self, k: int) -> tuple[Candidates, tuple[np.ndarray, ...]]:
        """Item ``k``'s candidates that are valid in the empty room (inside, off door zones,
        front clear of walls) and the cell ranges of their footprints; cached per item."""
        hit = self._cache.get(k)
        if hit is not None:
            return hit
        w, d, h = (float(v) for v in self.items[k].record.size)
        edge = self._hard_edge(k)
        hit = self._cache.get((w, d, h, edge))  # items of one size (the same asset) share them
        if hit is None:
            parts = [] if edge else [self._grid_part(w, d, h, float(yaw)) for yaw in self.yaws]
            parts.append(self._snapped_part(w, d, h))
            c = Candidates.concat([p[0] for p in parts], (w, d, h))
            ranges = tuple(np.concatenate([p[1][i] for p in parts]) for i in range(4))
            hit = self._cache[(w, d, h, edge)] = (c, ranges)
        self._cache[k] = hit
        return hit

    def _hard_edge(self, k: int) -> bool:
        return any(r.kind == "edge" and r.hard for r in self.items[k].relations)

    def _has_global(self, k: int) -> bool:
        return any(r.kind in ("edge", "middle") for r in self.items[k].relations)

    def _free_radius(self, blocked: np.ndarray) -> float:
        """An upper bound of the radius of the largest free disc in the room (plus a cell)."""
        if blocked.all():
            return 0.0
        return float(ndimage.distance_transform_edt(~blocked, sampling=self.hmax).max()) + self.hmax

    def unavoidable(self, k: int) -> str | None:
        item = self.items[k]
        if item.forced_reason:
            return item.forced_reason
        w, d, h = item.record.size
        if h > self.room.height:
            return f"taller ({h:.2f} m) than the room ({self.room.height:.2f} m)"
        # Cheap and exact enough: a footprint whose inscribed disc is wider than any free disc
        # of the empty room fits nowhere (the full test runs lazily in ``candidates``).
        if min(w, d) / 2 > self._static_radius or (self._hard_edge(k) and len(self._static(k)[0]) == 0):
            where = "against a wall " if self._hard_edge(k) else ""
            return f"footprint {w:.2f} x {d:.2f} m fits nowhere {where}in the empty room"
        return None

    def candidates(self, k: int) -> tuple[list[Choice], str]:
        w, d, _ = self.items[k].record.size
        c, (i0, i1, j0, j1) = self._static(k)
        if len(c) == 0:
            return [], f"footprint {w:.2f} x {d:.2f} m fits nowhere in the empty room"
        if self._sat is None:
            self._sat = self.grid.sat(self.occ > 0)  # one table per search state, shared by all items
        ok = self._sat[j1, i1] - self._sat[j0, i1] - self._sat[j1, i0] + self._sat[j0, i0] == 0
        if not ok.any():
            return [], f"no free floor position for its {w:.2f} x {d:.2f} m footprint"
        c = c.take(np.flatnonzero(ok))
        c, score, why = self.rel.satisfying(k, c, "floor position")
        if why:
            return [], why
        prior = np.zeros(len(c)) if self._has_global(k) else 1.0 - np.clip(c.back_gap / 1.0, 0, 1)  # type: ignore[operator]
        rank = score + PRIOR_WEIGHT * prior
        spread = max(0.5 * max(w, d), 2 * self.cfg.cell_size)
        return order_candidates(c, rank, score, self.rng, self.max_branch, spread), ""

    def min_future_skips(self, k: int, placed: int) -> int:
        return 0

    # ------------------------------------------------------------ state

    def push(self, k: int, choice: Choice) -> None:
        w, d, _ = self.items[k].record.size
        ex, ey = rotated_half_extents(w, d, choice.yaw)
        cl = self.cfg.clearance
        self.filled[k] = self.grid.fill(self.occ, choice.x, choice.y, float(ex) + cl, float(ey) + cl, 1)
        self._sat = None
        self.rel.place(k, choice)

    def pop(self, k: int) -> None:
        i0, i1, j0, j1 = self.filled.pop(k)
        self.occ[j0:j1, i0:i1] -= 1
        self._sat = None
        self.rel.remove(k)

    def box(self, k: int) -> TargetBox | None:
        return self.rel.boxes.get(k)

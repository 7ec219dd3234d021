"""An offline physical-plausibility score (0-100) of a scene layout.

The paper scores layout reasonability by asking GPT-4o to rate rendered views. Offline, we score
what makes a layout implausible physically, from the layout and the assets' boxes and support
surfaces:

========================  ======  ===========================================================
component                 weight  an instance passes when ...
========================  ======  ===========================================================
collision_free            0.30    its box overlaps no other box (except its support/children)
                                  by more than 5 % of the smaller box's volume
supported                 0.25    floor objects stand on the floor (a floor-only asset stacked
                                  on another object fails), on-top objects on one of their
                                  support's surfaces (within 2 cm, centre inside the surface),
                                  wall objects hang on a wall
inside                    0.15    its footprint lies in the room (1 cm tolerance) and its top
                                  below the ceiling
on_wall                   0.10    (wall objects) its back is flush with a wall segment
not_facing_wall           0.10    (floor objects) its front is not within 0.3 m of a wall
reachable                 0.10    scene-level: the share of free floor (for a 0.2 m-radius
                                  agent) reachable from the doors
========================  ======  ===========================================================

score = 100 * sum(weight * pass rate). Each component is reported too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from shapely import STRtree
from shapely.geometry import LineString, Point, Polygon, box as sbox
from shapely.affinity import affine_transform

from ...assets.catalog import Catalog
from ...core.contracts import AssetRecord, SceneLayout
from ...core.errors import AssetError

WEIGHTS = {
    "collision_free": 0.30,
    "supported": 0.25,
    "inside": 0.15,
    "on_wall": 0.10,
    "not_facing_wall": 0.10,
    "reachable": 0.10,
}
TOL = 0.02
OVERLAP_FRACTION = 0.05
FACING_DIST = 0.3
AGENT_RADIUS = 0.2
GRID = 0.05


@dataclass(frozen=True)
class PlausibilityReport:
    score: float
    components: dict
    problems: tuple[str, ...]

    def to_json(self) -> dict:
        return {"score": round(self.score, 3), "components": {k: round(v, 4) for k, v in self.components.items()},
                "problems": list(self.problems)}


def _footprint(rec: AssetRecord, pose: np.ndarray) -> Polygon:
    w, d, _ = rec.size
    poly = sbox(-w / 2, -d / 2, w / 2, d / 2)
    return affine_transform(poly, [pose[0, 0], pose[0, 1], pose[1, 0], pose[1, 1], pose[0, 3], pose[1, 3]])


def _world_polygon(points, pose: np.ndarray) -> Polygon:
    poly = Polygon(points)
    return affine_transform(poly, [pose[0, 0], pose[0, 1], pose[1, 0], pose[1, 1], pose[0, 3], pose[1, 3]])


def score_layout(layout: SceneLayout, catalog: Catalog) -> PlausibilityReport:
    """Score one layout; assets are looked up in ``catalog`` (an unknown asset is an error)."""
    room = Polygon(layout.room.polygon)
    walls = [LineString([layout.room.polygon[i], layout.room.polygon[(i + 1) % len(layout.room.polygon)]])
             for i in range(len(layout.room.polygon))]
    insts = list(layout.instances)
    recs: list[AssetRecord] = []
    for inst in insts:
        try:
            recs.append(catalog.get(inst.asset))
        except AssetError:
            raise AssetError(f"layout references asset {inst.asset!r}, which is not in catalog {catalog.root}; "
                             f"pass the catalog the dataset was generated from (--assets)") from None
    problems: list[str] = []
    n = len(insts)
    if n == 0:
        return PlausibilityReport(0.0, {k: 0.0 for k in WEIGHTS}, ("no instances",))
    feet = [_footprint(r, i.pose) for r, i in zip(recs, insts)]
    z0 = np.array([i.pose[2, 3] for i in insts])
    z1 = z0 + np.array([r.size[2] for r in recs])
    vol = np.array([f.area for f in feet]) * (z1 - z0)
    related = {(i.id, i.parent) for i in insts if i.parent is not None}
    related |= {(b, a) for a, b in related}
    ids = [i.id for i in insts]
    by_id = {i.id: k for k, i in enumerate(insts)}

    # collisions (broad phase on footprints)
    tree = STRtree(feet)
    colliding = np.zeros(n, bool)
    for a, b in zip(*tree.query(feet, predicate="intersects")):
        if a >= b or (ids[a], ids[b]) in related:
            continue
        dz = min(z1[a], z1[b]) - max(z0[a], z0[b])
        if dz <= 0:
            continue
        v = feet[a].intersection(feet[b]).area * dz
        if v > OVERLAP_FRACTION * max(min(vol[a], vol[b]), 1e-9):
            colliding[a] = colliding[b] = True
            problems.append(f"instances {ids[a]} and {ids[b]} interpenetrate ({v * 1e3:.1f} litres)")

    # support, inside, wall, facing
    supported = np.zeros(n, bool)
    inside = np.zeros(n, bool)
    wall_items, on_wall = [], []
    floor_items, not_facing = [], []
    room_in = room.buffer(0.01)
    for k, (inst, rec, foot) in enumerate(zip(insts, recs, feet)):
        inside[k] = room_in.contains(foot) and z1[k] <= layout.room.height + 0.01
        if not inside[k]:
            problems.append(f"instance {inst.id} ({inst.class_name}) is outside the room")
        if inst.group == "wall":
            back = LineString([(-rec.size[0] / 2, rec.size[1] / 2), (rec.size[0] / 2, rec.size[1] / 2)])
            back = affine_transform(back, [inst.pose[0, 0], inst.pose[0, 1], inst.pose[1, 0], inst.pose[1, 1],
                                           inst.pose[0, 3], inst.pose[1, 3]])
            ok = any(max(w.distance(Point(c)) for c in back.coords) < TOL for w in walls)
            wall_items.append(k)
            on_wall.append(ok)
            supported[k] = ok or abs(z0[k]) < TOL
            if not ok:
                problems.append(f"wall instance {inst.id} ({inst.class_name}) is not on a wall")
            continue
        if inst.group == "floor" and inst.parent is not None and "obj" not in rec.groups:
            # furniture stands on the floor: a floor-only asset resting on another object (a
            # RandomRooms-style pile) is not supported, whatever it rests on
            supported[k] = False
            problems.append(f"instance {inst.id} ({inst.class_name}) is a floor object stacked on instance "
                            f"{inst.parent}")
            continue
        if inst.parent is not None and inst.parent in by_id:
            p = insts[by_id[inst.parent]]
            prec = recs[by_id[inst.parent]]
            c = Point(inst.pose[0, 3], inst.pose[1, 3])
            supported[k] = any(abs(p.pose[2, 3] + s.height - z0[k]) < TOL and _world_polygon(s.polygon, p.pose).buffer(TOL).contains(c)
                               for s in prec.supports)
        else:
            supported[k] = abs(z0[k]) < TOL
        if not supported[k]:
            problems.append(f"instance {inst.id} ({inst.class_name}) is floating or sunk (base z = {z0[k]:.3f} m)")
        if inst.group == "floor" and inst.parent is None:
            floor_items.append(k)
            fwd = -inst.pose[:2, 1]
            nrm = np.linalg.norm(fwd)
            fwd = fwd / nrm if nrm > 0 else np.array([0.0, -1.0])
            front_c = np.array([inst.pose[0, 3], inst.pose[1, 3]]) + fwd * rec.size[1] / 2
            probe = LineString([front_c + fwd * 0.005, front_c + fwd * FACING_DIST])
            facing = any(probe.intersects(w) for w in walls)
            not_facing.append(not facing)

    reach = _reachability(layout, [feet[k] for k in range(n) if insts[k].group == "floor" and insts[k].parent is None
                                   and z0[k] < 1.0])
    comps = {
        "collision_free": float(1.0 - colliding.mean()),
        "supported": float(supported.mean()),
        "inside": float(inside.mean()),
        "on_wall": float(np.mean(on_wall)) if wall_items else 1.0,
        "not_facing_wall": float(np.mean(not_facing)) if floor_items else 1.0,
        "reachable": reach,
    }
    score = 100.0 * sum(WEIGHTS[k] * v for k, v in comps.items())
    return PlausibilityReport(float(score), comps, tuple(problems))


def _reachability(layout: SceneLayout, floor_feet: list[Polygon]) -> float:
    """Share of free floor (for a disc agent) connected to a door (or to the largest free region)."""
    poly = np.asarray(layout.room.polygon, np.float64)
    lo = poly.min(0)
    hi = poly.max(0)
    shape = np.ceil((hi - lo) / GRID).astype(int) + 1
    xs = lo[0] + (np.arange(shape[0]) + 0.5) * GRID
    ys = lo[1] + (np.arange(shape[1]) + 0.5) * GRID
    from matplotlib.path import Path as MplPath

    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    pts = np.stack([gx.ravel(), gy.ravel()], 1)
    room_mask = MplPath(poly).contains_points(pts).reshape(shape)
    occ = np.zeros(shape, bool)
    for f in floor_feet:
        if f.is_empty:
            continue
        fx = np.asarray(f.exterior.coords)
        sel = (pts[:, 0] >= fx[:, 0].min()) & (pts[:, 0] <= fx[:, 0].max()) & \
              (pts[:, 1] >= fx[:, 1].min()) & (pts[:, 1] <= fx[:, 1].max())
        if sel.any():
            inside = MplPath(fx).contains_points(pts[sel])
            flat = occ.ravel()
            idx = np.flatnonzero(sel)[inside]
            flat[idx] = True
    r = int(np.ceil(AGENT_RADIUS / GRID))
    yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
    disc = (xx ** 2 + yy ** 2) <= r * r
    blocked = ndimage.binary_dilation(occ | ~room_mask, structure=disc)
    free = room_mask & ~blocked
    total = int(free.sum())
    if total == 0:
        return 0.0
    labels, nlab = ndimage.label(free)
    starts: set[int] = set()
    for o in layout.room.openings:
        if o.kind != "door":
            continue
        a = poly[o.wall]
        b = poly[(o.wall + 1) % len(poly)]
        t = (b - a) / max(np.linalg.norm(b - a), 1e-9)
        inward = np.array([-t[1], t[0]])  # CCW polygon: interior on the left
        c = a + t * o.offset + inward * (AGENT_RADIUS + 2 * GRID)
        ij = np.floor((c - lo) / GRID).astype(int)
        if 0 <= ij[0] < shape[0] and 0 <= ij[1] < shape[1]:
            win = labels[max(ij[0] - 3, 0):ij[0] + 4, max(ij[1] - 3, 0):ij[1] + 4]
            starts |= set(int(v) for v in np.unique(win) if v > 0)
    if not starts:
        sizes = np.bincount(labels.ravel())[1:]
        return float(sizes.max() / total)
    reach = np.isin(labels, list(starts)).sum()
    return float(reach / total)

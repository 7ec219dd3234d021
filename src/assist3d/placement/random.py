"""The RandomRooms-style baseline: random positions and yaws, no relations, objects dropped in place.

Objects go largest footprint first. Each gets a uniformly random yaw and a uniformly random
position whose footprint lies inside the room (up to ``TRIES`` draws, then it is dropped), and
falls straight down: onto the floor, or onto the highest box its footprint overlaps (stacking
where it lands, that box's instance becoming its parent). There is no collision reasoning
beyond that, as in the baseline the paper compares with.
"""

from __future__ import annotations

import numpy as np

from ..core.contracts import AssetRecord, DroppedObject, PlacedInstance, Room
from ..core.geometry import InstanceBoxes, obb_overlap, pose_matrix, rect_corners, rects_in_polygon, room_polygon

TRIES = 64


def drop_randomly(room: Room, objects: tuple[AssetRecord, ...], placed: tuple[PlacedInstance, ...],
                  sizes: dict[str, tuple[float, float, float]], group: str, rng: np.random.Generator,
                  next_id: int) -> tuple[list[PlacedInstance], list[DroppedObject]]:
    """Place ``objects`` at random (see the module docstring); returns (placed, dropped)."""
    poly = room_polygon(room)
    minx, miny, maxx, maxy = poly.bounds
    boxes = InstanceBoxes.from_instances(placed, sizes)
    order = sorted(range(len(objects)), key=lambda i: (-objects[i].size[0] * objects[i].size[1], i))
    out: list[PlacedInstance] = []
    dropped: list[DroppedObject] = []
    for i in order:
        rec = objects[i]
        w, d, h = (float(v) for v in rec.size)
        yaw = float(rng.uniform(0.0, 2 * np.pi))
        xs = rng.uniform(minx, maxx, TRIES)
        ys = rng.uniform(miny, maxy, TRIES)
        inside = rects_in_polygon(rect_corners(xs, ys, np.full(TRIES, yaw), w, d), poly)
        if not inside.any():
            dropped.append(DroppedObject(rec.id, group, f"no random position in {TRIES} draws keeps its "
                                                        f"{w:.2f} x {d:.2f} m footprint inside the room"))
            continue
        j = int(np.flatnonzero(inside)[0])
        x, y = float(xs[j]), float(ys[j])
        z, parent = 0.0, None
        if len(boxes):
            a = boxes.a
            under = obb_overlap(x, y, yaw, w / 2, d / 2, a["x"], a["y"], a["yaw"], a["hw"], a["hd"])
            if under.any():
                top = int(np.argmax(np.where(under, a["z1"], -np.inf)))
                z = float(a["z1"][top])
                parent = int(a["ids"][top])
        if z + h > room.height:
            dropped.append(DroppedObject(rec.id, group, f"landed on a pile {z:.2f} m high and would pierce the "
                                                        f"{room.height:.2f} m ceiling"))
            continue
        ident = next_id + len(out)
        out.append(PlacedInstance(ident, rec.id, rec.class_name, group, pose_matrix(x, y, yaw, z), parent))
        boxes.add(ident, x, y, yaw, z, rec.size)
    return out, dropped

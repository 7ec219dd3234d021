"""Vantage points: inside the room, clear of walls and tall objects, spread out, seeded."""

from __future__ import annotations

import numpy as np
import shapely

from assist3d.config import RenderConfig
from assist3d.core.contracts import Room
from assist3d.render.shapes import box_part, combine_parts, shell_parts
from assist3d.render.vantage import candidate_cells, instance_boxes, select_vantage_points

L_ROOM = Room(((0.0, 0.0), (6.0, 0.0), (6.0, 2.5), (2.5, 2.5), (2.5, 5.0), (0.0, 5.0)), 2.8, ceiling=False)


def l_scene():
    parts = shell_parts(L_ROOM)
    parts.append(box_part((4.5, 1.2, 0.0), (1.2, 1.0, 2.0), 0.0, (1, 2, 3), 1, 0))  # tall: blocks the camera plane
    parts.append(box_part((1.2, 3.8, 0.0), (1.0, 1.0, 0.4), 0.0, (1, 2, 3), 2, 0))  # low: does not
    return combine_parts(parts)


def test_vantage_points_are_free_spread_and_deterministic():
    scene = l_scene()
    cfg = RenderConfig(vantage_points=5, vantage_clearance=0.3)
    pts = select_vantage_points(scene, L_ROOM, cfg, rng=np.random.default_rng(0))
    assert pts.shape == (5, 3)
    assert np.allclose(pts[:, 2], 1.4)  # mid-height plane
    poly = shapely.Polygon(L_ROOM.polygon)
    for x, y, _ in pts:
        p = shapely.Point(x, y)
        assert poly.contains(p) and poly.exterior.distance(p) >= 0.3 - 1e-9
        assert not (4.5 - 0.6 - 0.3 < x < 4.5 + 0.6 + 0.3 and 1.2 - 0.5 - 0.3 < y < 1.2 + 0.5 + 0.3)
    again = select_vantage_points(scene, L_ROOM, cfg, rng=np.random.default_rng(0))
    assert np.array_equal(pts, again)
    # farthest point sampling spreads them: no two closer than 1 m in this 23 m^2 room
    d = np.linalg.norm(pts[:, None, :2] - pts[None, :, :2], axis=-1) + np.eye(5) * 99
    assert d.min() > 1.0


def test_low_objects_do_not_block_and_camera_height_is_configurable():
    scene = l_scene()
    cfg = RenderConfig(vantage_clearance=0.3)
    cells = candidate_cells(scene, L_ROOM, cfg, 0.3)
    on_low = (np.abs(cells[:, 0] - 1.2) < 0.4) & (np.abs(cells[:, 1] - 3.8) < 0.4)
    assert on_low.any()  # the 0.4 m box lies below the camera plane
    high = RenderConfig(camera_height=0.2, vantage_clearance=0.3)
    cells_low = candidate_cells(scene, L_ROOM, high, 0.3)
    assert not ((np.abs(cells_low[:, 0] - 1.2) < 0.4) & (np.abs(cells_low[:, 1] - 3.8) < 0.4)).any()


def test_crowded_room_relaxes_clearance_instead_of_failing():
    room = Room(((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)), 2.5, ceiling=False)
    scene = combine_parts(shell_parts(room) + [box_part((0.5, 0.5, 0.0), (0.3, 0.3, 2.0), 0.0, (1, 1, 1), 1, 0)])
    pts = select_vantage_points(scene, room, RenderConfig(vantage_clearance=0.4), rng=np.random.default_rng(1))
    assert 1 <= len(pts) <= 5


def test_instance_boxes():
    ids, boxes = instance_boxes(l_scene())
    assert ids.tolist() == [1, 2]
    np.testing.assert_allclose(boxes[0], [[3.9, 0.7, 0.0], [5.1, 1.7, 2.0]], atol=1e-5)

"""Plausibility score on layouts where a real bug could hide: L-shaped rooms, objects yawed by 90
degrees, shelves with several support surfaces, and RandomRooms-style piles."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from assist3d.assets.catalog import Catalog
from assist3d.core.contracts import AssetRecord, MeshData, Opening, PlacedInstance, Room, SceneLayout, SupportSurface
from assist3d.bench.metrics.plausibility import score_layout


def _mesh(size) -> MeshData:
    m = trimesh.creation.box(size)
    m.apply_translation((0, 0, size[2] / 2))
    return MeshData(m.vertices.astype(np.float32), m.faces.astype(np.int32), np.full((len(m.faces), 3), 180, np.uint8))


def _rect(w, d):
    return ((-w, -d), (w, -d), (w, d), (-w, d))


@pytest.fixture
def catalog(tmp_path):
    cat = Catalog.open_or_create(tmp_path / "lib")

    def add(aid, size, groups, supports=()):
        cat.add(AssetRecord(id=aid, source="test", name=aid, class_name=aid, groups=groups, size=size,
                            supports=supports), _mesh(size))

    add("cabinet", (0.8, 0.5, 1.0), ("floor",), (SupportSurface(1.0, _rect(0.38, 0.23)),))
    add("bench", (4.5, 0.5, 0.45), ("floor",))
    add("picture", (0.8, 0.04, 0.6), ("wall",))
    add("cup", (0.1, 0.1, 0.12), ("obj",))
    add("lamp", (0.2, 0.2, 0.4), ("floor", "obj"))
    # a bookshelf with three shelves (and its top) as support surfaces
    add("bookshelf", (0.9, 0.35, 1.6), ("floor",),
        tuple(SupportSurface(h, _rect(0.42, 0.15), clearance=0.35) for h in (0.4, 0.8, 1.2)) +
        (SupportSurface(1.6, _rect(0.43, 0.16)),))
    cat.save()
    return cat


def _pose(x, y, z=0.0, yaw=0.0):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0, x], [s, c, 0, y], [0, 0, 1, z], [0, 0, 0, 1]], dtype=np.float64)


BOX_ROOM = Room(((0, 0), (5, 0), (5, 4), (0, 4)), 2.8, (Opening("door", 0, 2.5, 0.9, 0.0, 2.0),))
# L-shaped: a 6 x 5 rectangle without its north-east 3 x 2.5 quadrant (counter-clockwise)
L_ROOM = Room(((0, 0), (6, 0), (6, 2.5), (3, 2.5), (3, 5), (0, 5)), 2.8, (Opening("door", 0, 1.0, 0.9, 0.0, 2.0),))


def _score(room, *insts, catalog):
    return score_layout(SceneLayout(room, tuple(insts), (), seed=0, seconds=0.0), catalog)


def test_l_shaped_room_inner_corner(catalog):
    good = (
        # against the inner wall x = 3 (north wing), back to +x: yaw -90 deg turns +y (back) to +x
        PlacedInstance(1, "cabinet", "cabinet", "floor", _pose(2.75, 3.5, yaw=-math.pi / 2)),
        # picture on the inner wall y = 2.5 of the east wing, back to +y
        PlacedInstance(2, "picture", "picture", "wall", _pose(4.5, 2.48, 1.4)),
    )
    rep = _score(L_ROOM, *good, catalog=catalog)
    assert rep.problems == () and rep.score == pytest.approx(100.0)
    # the same cabinet in the missing quadrant: inside the bounding box, outside the room
    notch = PlacedInstance(3, "cabinet", "cabinet", "floor", _pose(4.5, 3.8))
    rep = _score(L_ROOM, *good, notch, catalog=catalog)
    assert rep.components["inside"] == pytest.approx(2 / 3)
    assert any("instance 3" in p and "outside" in p for p in rep.problems)
    # a picture on the line y = 2.5 but west of the inner corner hangs mid-room, on no wall
    ghost = PlacedInstance(4, "picture", "picture", "wall", _pose(1.5, 2.48, 1.4))
    rep = _score(L_ROOM, *good, ghost, catalog=catalog)
    assert rep.components["on_wall"] == pytest.approx(0.5)


def test_objects_yawed_by_90_degrees(catalog):
    # a 4.5 m bench fits the 5 m side but not the 4 m side: only the rotated footprint is outside
    along_x = PlacedInstance(1, "bench", "bench", "floor", _pose(2.5, 1.0))
    along_y = PlacedInstance(1, "bench", "bench", "floor", _pose(2.5, 2.0, yaw=math.pi / 2))
    assert _score(BOX_ROOM, along_x, catalog=catalog).components["inside"] == 1.0
    assert _score(BOX_ROOM, along_y, catalog=catalog).components["inside"] == 0.0
    # a picture turned to hang on the west wall (back towards -x) is on the wall; unturned it is not
    west = PlacedInstance(1, "picture", "picture", "wall", _pose(0.02, 2.0, 1.4, yaw=math.pi / 2))
    unturned = PlacedInstance(1, "picture", "picture", "wall", _pose(0.02, 2.0, 1.4))
    assert _score(BOX_ROOM, west, catalog=catalog).components["on_wall"] == 1.0
    assert _score(BOX_ROOM, unturned, catalog=catalog).components["on_wall"] == 0.0
    # a cabinet backed onto the west wall faces the room; turned the other way it faces the wall
    backed = PlacedInstance(1, "cabinet", "cabinet", "floor", _pose(0.26, 2.0, yaw=math.pi / 2))
    facing = PlacedInstance(1, "cabinet", "cabinet", "floor", _pose(0.26, 2.0, yaw=-math.pi / 2))
    assert _score(BOX_ROOM, backed, catalog=catalog).components["not_facing_wall"] == 1.0
    assert _score(BOX_ROOM, facing, catalog=catalog).components["not_facing_wall"] == 0.0


def test_on_top_objects_on_a_shelf_with_several_surfaces(catalog):
    shelf = PlacedInstance(1, "bookshelf", "bookshelf", "floor", _pose(2.5, 3.82, yaw=0.0))
    on = [PlacedInstance(10 + k, "cup", "cup", "obj", _pose(2.3 + 0.2 * k, 3.85, h), parent=1)
          for k, h in enumerate((0.4, 0.8, 1.2, 1.6))]
    rep = _score(BOX_ROOM, shelf, *on, catalog=catalog)
    # every surface holds its cup; cups inside the shelf's box do not count as interpenetrating
    assert rep.problems == () and rep.components["supported"] == 1.0 and rep.components["collision_free"] == 1.0
    between = PlacedInstance(20, "cup", "cup", "obj", _pose(2.5, 3.85, 1.0), parent=1)   # between two shelves
    beside = PlacedInstance(21, "cup", "cup", "obj", _pose(3.2, 3.85, 0.8), parent=1)    # at shelf height, off it
    rep = _score(BOX_ROOM, shelf, *on, between, beside, catalog=catalog)
    assert rep.components["supported"] == pytest.approx(5 / 7)
    assert sum("floating" in p for p in rep.problems) == 2
    # a yawed shelf: its surfaces turn with it
    turned = PlacedInstance(1, "bookshelf", "bookshelf", "floor", _pose(0.18, 2.0, yaw=math.pi / 2))
    cup = PlacedInstance(10, "cup", "cup", "obj", _pose(0.15, 2.3, 0.8), parent=1)
    assert _score(BOX_ROOM, turned, cup, catalog=catalog).components["supported"] == 1.0


def test_randomrooms_style_pile_scores_low(catalog):
    # RandomRooms-style: furniture dropped onto furniture (the generator records what each object
    # landed on as its parent), random yaws, one object facing a wall
    insts = (
        PlacedInstance(1, "cabinet", "cabinet", "floor", _pose(1.5, 1.5, yaw=0.3)),
        PlacedInstance(2, "cabinet", "cabinet", "floor", _pose(1.6, 1.5, 1.0, yaw=2.0), parent=1),
        PlacedInstance(3, "cabinet", "cabinet", "floor", _pose(3.5, 2.5, yaw=1.0)),
        PlacedInstance(4, "bench", "bench", "floor", _pose(3.0, 2.5, 1.0, yaw=0.5), parent=3),
        PlacedInstance(5, "cabinet", "cabinet", "floor", _pose(4.6, 1.0, yaw=math.pi / 2)),
        PlacedInstance(6, "lamp", "lamp", "floor", _pose(1.6, 1.5, 2.0), parent=2),
    )
    rep = _score(BOX_ROOM, *insts, catalog=catalog)
    stacked = [p for p in rep.problems if "stacked" in p]
    # the cabinet and the bench on furniture fail; the lamp (an asset that may go on top) does not
    assert len(stacked) == 2 and "instance 2 " in stacked[0] and "instance 4 " in stacked[1]
    assert rep.components["supported"] == pytest.approx(4 / 6)
    assert rep.components["not_facing_wall"] == pytest.approx(2 / 3)
    # the same objects standing side by side along the north wall, fronts to the room
    tidy = tuple(PlacedInstance(k, "cabinet", "cabinet", "floor", _pose(0.6 + 0.9 * k, 3.74)) for k in range(5))
    tidy_rep = _score(BOX_ROOM, *tidy, catalog=catalog)
    assert tidy_rep.score == pytest.approx(100.0)
    assert rep.score < tidy_rep.score - 10

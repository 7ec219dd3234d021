"""Wall and on-top placement: flush with walls, off openings, above targets, resting on supports,
inside support polygons, under shelf clearance, capped per support."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.config import LayoutConfig
from assist3d.core.contracts import PlacedInstance, Relation
from assist3d.core.geometry import pose_matrix, wall_segments, world_bounds
from assist3d.placement import place_group
from assist3d.planning.relations import PlanRequest

from test_placement_kit import (DOOR, WINDOW, box_asset, footprint, front_dir, make_catalog, plan, rect_room,
                                      shelf_asset, table_asset)


@pytest.fixture
def catalog(tmp_path):
    assets = [box_asset(f"pic{i}", w, 0.04, h, groups=("wall",), cls="picture")
              for i, (w, h) in enumerate([(0.8, 0.6), (0.5, 0.5), (1.2, 0.4), (0.4, 0.9), (0.6, 0.6)])]
    assets += [box_asset("cab", 1.0, 0.4, 0.7, groups=("wall",), cls="cabinet", elevation=1.4),
               box_asset("sofa", 2.0, 0.9, 0.8, cls="sofa"),
               box_asset("tall", 0.6, 0.05, 2.55, groups=("wall",), cls="mirror"),
               table_asset("table"), shelf_asset("shelf")]
    assets += [box_asset(f"cup{i}", 0.1 + 0.02 * i, 0.1, 0.12, groups=("obj",), cls="cup") for i in range(8)]
    assets += [box_asset("vase", 0.15, 0.15, 0.5, groups=("obj",), cls="vase"),
               box_asset("tray", 2.0, 0.3, 0.05, groups=("obj",), cls="tray")]
    return make_catalog(tmp_path, assets)


def _wall_check(inst, catalog, room):
    walls = wall_segments(room)
    w, d, h = catalog.get(inst.asset).size
    back = inst.pose[:2, 3] - front_dir(inst) * d / 2
    dist = np.array([(back - walls.start[i]) @ walls.normal[i] for i in range(len(walls.length))])
    i = int(np.argmin(np.abs(dist)))
    assert abs(dist[i]) < 0.005 and front_dir(inst) @ walls.normal[i] > 0.999, "not flush with a wall"
    s = (inst.pose[:2, 3] - walls.start[i]) @ walls.direction[i]
    z = inst.pose[2, 3]
    assert s - w / 2 >= -1e-6 and s + w / 2 <= walls.length[i] + 1e-6
    assert z >= 0 and z + h <= room.height
    for o in room.openings:
        if o.wall == i:
            ds = min(s + w / 2, o.offset + o.width / 2) - max(s - w / 2, o.offset - o.width / 2)
            dz = min(z + h, o.top) - max(z, o.bottom)
            assert ds <= 1e-6 or dz <= 1e-6, "covers an opening"
    return i, s, z


def test_wall_objects_flush_off_openings_and_above_floor_objects(catalog):
    room = rect_room(4.0, 3.0, openings=(DOOR, WINDOW))
    sofa = PlacedInstance(1, "sofa", "sofa", "floor", pose_matrix(2.0, 2.545, np.pi, 0.0))
    ids = ["pic0", "pic1", "pic2", "pic3", "pic4", "cab"] * 2
    req = PlanRequest("wall", tuple(catalog.get(i) for i in ids), room, (sofa,))
    rel = {0: [Relation("above", 1, hard=True), Relation("height", None, (1.0, 1.6), hard=True)]}
    res = place_group(req, plan(req, rel), catalog, cfg=LayoutConfig(), rng=np.random.default_rng(0), next_id=2)
    assert len(res.instances) >= 10
    sofa_box = world_bounds(catalog.get("sofa").size, sofa.pose)
    boxes = []
    for inst in res.instances:
        _wall_check(inst, catalog, room)
        b = world_bounds(catalog.get(inst.asset).size, inst.pose)
        over = np.minimum(b[1], sofa_box[1]) - np.maximum(b[0], sofa_box[0])
        assert (over <= 1e-6).any(), "wall object intersects the sofa"
        boxes.append(b)
    for a in range(len(boxes)):
        for c in range(a + 1, len(boxes)):
            over = np.minimum(boxes[a][1], boxes[c][1]) - np.maximum(boxes[a][0], boxes[c][0])
            assert (over <= 1e-6).any(), "wall objects collide"
    first = res.instances[0]
    assert first.asset == "pic0"
    assert 1.0 <= first.pose[0, 3] <= 3.0 and 1.0 - 1e-9 <= first.pose[2, 3] <= 1.6 + 1e-9  # over the sofa
    assert first.relations[0] == Relation("above", 1, (), True)


def test_wall_object_taller_than_the_room_is_dropped(catalog):
    room = rect_room(4.0, 3.0, height=2.4)
    req = PlanRequest("wall", (catalog.get("tall"), catalog.get("pic1")), room)
    res = place_group(req, plan(req), catalog, cfg=LayoutConfig(), rng=np.random.default_rng(0), next_id=1)
    assert [i.asset for i in res.instances] == ["pic1"]
    assert "ceiling" in res.dropped[0].reason


def _support(catalog, asset, x=2.0, y=1.5, yaw=0.3):
    return PlacedInstance(5, asset, catalog.get(asset).class_name, "floor", pose_matrix(x, y, yaw, 0.0))


def test_on_top_objects_rest_on_the_table_inside_its_top(catalog):
    room = rect_room(4.0, 3.0)
    table = _support(catalog, "table")
    ids = [f"cup{i}" for i in range(8)]
    req = PlanRequest("on:5", tuple(catalog.get(i) for i in ids), room, (table,), table)
    cfg = LayoutConfig()
    res = place_group(req, plan(req, {0: [Relation("on", 5)]}), catalog, cfg=cfg, rng=np.random.default_rng(2),
                      next_id=6)
    assert len(res.instances) == cfg.max_on_top_per_support
    assert all("max_on_top_per_support" in d.reason for d in res.dropped)
    top = footprint(table, catalog.get("table").size)
    feet = []
    for inst in res.instances:
        assert inst.parent == 5 and inst.group == "obj"
        assert abs(inst.pose[2, 3] - 0.75) < 1e-9, "not resting on the table top"
        f = footprint(inst, catalog.get(inst.asset).size)
        assert top.buffer(1e-6).contains(f)
        feet.append(f)
    for a in range(len(feet)):
        for b in range(a + 1, len(feet)):
            assert feet[a].intersection(feet[b]).area < 1e-9


def test_shelf_clearance_is_respected(catalog):
    room = rect_room(4.0, 3.0)
    shelf = _support(catalog, "shelf", yaw=0.0)
    ids = ["vase", "cup0", "cup1", "tray"]
    req = PlanRequest("on:5", tuple(catalog.get(i) for i in ids), room, (shelf,), shelf)
    res = place_group(req, plan(req), catalog, cfg=LayoutConfig(), rng=np.random.default_rng(0), next_id=6)
    by_asset = {i.asset: i for i in res.instances}
    assert "vase" in by_asset and abs(by_asset["vase"].pose[2, 3] - 0.42) < 1e-9, "0.5 m vase fits only the upper board"
    for inst in res.instances:
        z = inst.pose[2, 3]
        assert min(abs(z - 0.02), abs(z - 0.42)) < 1e-9
        clearance = 0.36 if abs(z - 0.02) < 1e-9 else 0.76
        assert catalog.get(inst.asset).size[2] <= clearance
    (d,) = res.dropped
    assert d.asset == "tray" and "fits on no surface" in d.reason


def test_on_top_of_a_support_without_surfaces_drops_everything(catalog):
    room = rect_room(4.0, 3.0)
    sofa = _support(catalog, "sofa")
    req = PlanRequest("on:5", (catalog.get("cup0"),), room, (sofa,), sofa)
    res = place_group(req, plan(req), catalog, cfg=LayoutConfig(), rng=np.random.default_rng(0), next_id=6)
    assert res.instances == () and "no support surface" in res.dropped[0].reason


def test_surface_inside_a_closed_model_or_overhung_carries_nothing(tmp_path):
    from dataclasses import replace

    from assist3d.core.contracts import MeshData, SupportSurface

    from test_placement_kit import box_mesh, merge

    # A closed 1 x 1 x 1 m block whose record claims a surface at 0.5 m (inside the material),
    # with every face duplicated back to back as catalog meshes often are; and a table whose
    # record claims a surface 3 cm above its real top.
    block, block_mesh = box_asset("block", 1.0, 1.0, 1.0)
    inner = box_mesh((-0.45, -0.45, 0.5), (0.45, 0.45, 0.5))  # a flat face inside the block at 0.5 m
    m = merge(block_mesh, MeshData(inner.vertices, inner.faces[2:4], inner.face_colors[2:4]))
    doubled = MeshData(m.vertices, np.concatenate([m.faces, m.faces[:, ::-1]]).astype(np.int32),
                       np.concatenate([m.face_colors, m.face_colors]))
    square = ((-0.4, -0.4), (0.4, -0.4), (0.4, 0.4), (-0.4, 0.4))
    block = replace(block, supports=(SupportSurface(0.5, square),))
    table, table_mesh = table_asset("table")
    high = replace(table, id="hightable", supports=(SupportSurface(0.78, table.supports[0].polygon),))
    cat = make_catalog(tmp_path, [(block, doubled), (high, table_mesh), (table, table_mesh),
                                  box_asset("cup", 0.1, 0.1, 0.1, groups=("obj",), cls="cup")])
    room = rect_room(4.0, 3.0)
    for asset, expect in (("block", 0), ("hightable", 0), ("table", 3)):
        sup = PlacedInstance(5, asset, "x", "floor", pose_matrix(2.0, 1.5, 0.0, 0.0))
        req = PlanRequest("on:5", (cat.get("cup"),) * 3, room, (sup,), sup)
        res = place_group(req, plan(req), cat, cfg=LayoutConfig(), rng=np.random.default_rng(0), next_id=6)
        assert len(res.instances) == expect, asset

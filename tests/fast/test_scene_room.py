"""Room shells: sizes, winding, L-shapes and openings."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.config import RoomConfig
from assist3d.core.errors import ConfigError
from assist3d.scene.room import opening_segment, polygon_area, room_walls, sample_room, wall_lengths


def _rooms(cfg: RoomConfig, n: int = 200):
    return [sample_room(cfg, np.random.default_rng(s)) for s in range(n)]


def test_area_height_aspect_and_winding_in_range():
    cfg = RoomConfig()
    for room in _rooms(cfg):
        area = polygon_area(room.polygon)
        assert area > 0, "polygon must be counter-clockwise"
        assert cfg.area_min - 1e-3 <= area <= cfg.area_max + 1e-3
        assert cfg.height_min <= room.height <= cfg.height_max
        p = np.asarray(room.polygon)
        ext = p.max(0) - p.min(0)
        assert ext.max() / ext.min() <= cfg.aspect_max + 1e-6
        assert np.allclose(p.min(0), 0.0)
        assert room.ceiling is cfg.ceiling


def test_l_shapes_have_six_axis_aligned_vertices():
    rooms = _rooms(RoomConfig(l_shape_prob=1.0), 50)
    for room in rooms:
        assert len(room.polygon) == 6
        w = room_walls(room)
        d = w[:, 1] - w[:, 0]
        assert np.all(np.isclose(d[:, 0], 0) | np.isclose(d[:, 1], 0)), "walls are axis-aligned"
        # exactly one reflex corner: five left turns and one right turn
        e = np.roll(d, -1, axis=0)
        cross = d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0]
        assert (cross > 0).sum() == 5 and (cross < 0).sum() == 1
    assert all(len(r.polygon) == 4 for r in _rooms(RoomConfig(l_shape_prob=0.0), 20))


def test_openings_on_walls_sized_and_non_overlapping():
    cfg = RoomConfig(doors=(1, 2), windows=(2, 4))
    n_doors = 0
    for room in _rooms(cfg):
        lengths = wall_lengths(room)
        by_wall: dict[int, list[tuple[float, float]]] = {}
        for o in room.openings:
            assert 0 <= o.wall < len(room.polygon)
            assert o.width / 2 <= o.offset <= lengths[o.wall] - o.width / 2
            assert o.top <= room.height
            if o.kind == "door":
                n_doors += 1
                assert o.bottom == 0 and 0.8 <= o.width <= 1.0 and 2.0 <= o.top <= 2.1
            else:
                assert 0.8 <= o.bottom <= 1.0 and o.top < room.height and o.top > o.bottom
            by_wall.setdefault(o.wall, []).append((o.offset - o.width / 2, o.offset + o.width / 2))
            seg = opening_segment(room, o)
            assert np.isclose(np.linalg.norm(seg[1] - seg[0]), o.width)
        for spans in by_wall.values():
            spans.sort()
            for (a0, a1), (b0, b1) in zip(spans, spans[1:]):
                assert a1 <= b0, "openings on one wall overlap"
        assert sum(o.kind == "door" for o in room.openings) >= 1
    assert n_doors >= 200


def test_deterministic_and_bad_config():
    a = sample_room(RoomConfig(), np.random.default_rng(7))
    b = sample_room(RoomConfig(), np.random.default_rng(7))
    assert a.to_json() == b.to_json()
    with pytest.raises(ConfigError, match="area_min"):
        sample_room(RoomConfig(area_min=50, area_max=20), np.random.default_rng(0))
    with pytest.raises(ConfigError, match="height_min"):
        sample_room(RoomConfig(height_min=3.2, height_max=2.5), np.random.default_rng(0))


def _filled(seed: int, clearance: float = 0.8):
    from assist3d.scene.room import fill_openings

    room = sample_room(RoomConfig(doors=(2, 2), windows=(2, 3)), np.random.default_rng(seed))
    return room, fill_openings(room, 100, clearance, np.random.default_rng(seed))


def _local(room, opening, pts):
    """(along the wall from its start, depth into the room) of points ``pts`` (n, 3)."""
    w = room_walls(room)[opening.wall]
    u = (w[1] - w[0]) / np.linalg.norm(w[1] - w[0])
    n = np.array([-u[1], u[0]])  # counter-clockwise polygon: the room is on the left
    return (pts[:, :2] - w[0]) @ u, (pts[:, :2] - w[0]) @ n


def test_filled_openings_sit_in_their_holes_and_open_doors_stay_in_the_clearance_zone():
    from assist3d.core.contracts import Opening
    from assist3d.scene.shell import opening_meshes

    leaves = []
    for seed in range(40):
        room, filled = _filled(seed)
        assert [o.instance for o in filled.openings] == list(range(100, 100 + len(room.openings)))
        for plain, o in zip(room.openings, filled.openings):
            assert (o.kind, o.wall, o.offset, o.width, o.bottom, o.top) == (
                plain.kind, plain.wall, plain.offset, plain.width, plain.bottom, plain.top)
            assert Opening.from_json(o.to_json()) == o
        meshes = {i: (k, m) for i, k, m in opening_meshes(filled)}
        assert sorted(meshes) == [o.instance for o in filled.openings]
        for o in filled.openings:
            kind, mesh = meshes[o.instance]
            assert kind == o.kind and len(mesh.faces) >= 48
            v = mesh.vertices.astype(np.float64)
            tri = v[mesh.faces]  # every box closed and facing out: each one's signed volume is positive
            signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6
            assert (signed.reshape(-1, 12).sum(1) > 1e-9).all()
            along, depth = _local(filled, o, v)
            z = mesh.vertices[:, 2]
            assert along.min() >= o.offset - o.width / 2 - 1e-4 and along.max() <= o.offset + o.width / 2 + 1e-4
            assert z.min() >= o.bottom - 1e-4 and z.max() <= o.top + 1e-4
            if o.kind == "window" or o.leaf_deg == 0:
                # behind the wall plane but for a closed door's handle (3 cm into the clearance zone)
                assert depth.max() <= (0.031 if o.kind == "door" else 1e-6)
            else:
                leaves.append(o.leaf_deg)
                assert depth.max() <= 0.8 - 0.05 + 1e-4  # the far edge stays inside the clearance zone
    assert len(leaves) > 10 and min(leaves) >= 15.0  # some doors are ajar, and then by at least 15 degrees
    # a clearance zone too shallow for 15 degrees keeps every door closed
    for seed in range(10):
        _, filled = _filled(seed, clearance=0.2)
        assert all(o.leaf_deg == 0 for o in filled.openings)


def test_plain_openings_serialise_as_before():
    from assist3d.core.contracts import Opening

    o = Opening("door", 1, 2.0, 0.9, 0.0, 2.05)
    assert set(o.to_json()) == {"kind", "wall", "offset", "width", "bottom", "top"}
    assert Opening.from_json(o.to_json()) == o

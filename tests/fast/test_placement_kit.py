"""Builders shared by the placement, assembly and check tests: box/table/shelf assets, rooms, plans.

(Named test_* so it lives beside the tests that import it; it also checks its own builders.)
"""

from __future__ import annotations

import numpy as np
import shapely

from assist3d.assets.catalog import Catalog
from assist3d.core.contracts import AssetRecord, MeshData, Opening, PlacedInstance, Relation, Room, SupportSurface
from assist3d.core.geometry import rect_corners
from assist3d.planning.relations import GroupPlan, PlannedObject, PlanRequest


def box_mesh(lo: tuple[float, float, float], hi: tuple[float, float, float], color=(200, 60, 60)) -> MeshData:
    """A closed, outward-facing axis-aligned box from ``lo`` to ``hi``."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], dtype=np.float32)
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]], dtype=np.int32)
    return MeshData(v, f, np.tile(np.array(color, np.uint8), (12, 1)))


def merge(*meshes: MeshData) -> MeshData:
    off = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
    return MeshData(np.concatenate([m.vertices for m in meshes]),
                    np.concatenate([m.faces + o for m, o in zip(meshes, off)]).astype(np.int32),
                    np.concatenate([m.face_colors for m in meshes]))


def box_asset(ident: str, w: float, d: float, h: float, groups=("floor",), cls: str = "box",
              elevation: float = 0.0) -> tuple[AssetRecord, MeshData]:
    rec = AssetRecord(ident, "test", ident, cls, tuple(groups), (w, d, h), elevation=elevation)
    return rec, box_mesh((-w / 2, -d / 2, 0.0), (w / 2, d / 2, h))


def table_asset(ident: str, w: float = 1.2, d: float = 0.8, h: float = 0.75, top: float = 0.04) -> tuple[AssetRecord, MeshData]:
    """A table: a top slab and four legs; its support surface is the top."""
    parts = [box_mesh((-w / 2, -d / 2, h - top), (w / 2, d / 2, h), (150, 100, 60))]
    for sx in (-1, 1):
        for sy in (-1, 1):
            cx, cy = sx * (w / 2 - 0.05), sy * (d / 2 - 0.05)
            parts.append(box_mesh((cx - 0.03, cy - 0.03, 0.0), (cx + 0.03, cy + 0.03, h - top), (120, 80, 50)))
    poly = ((-w / 2, -d / 2), (w / 2, -d / 2), (w / 2, d / 2), (-w / 2, d / 2))
    rec = AssetRecord(ident, "test", ident, "table", ("floor",), (w, d, h), (SupportSurface(h, poly),))
    return rec, merge(*parts)


def shelf_asset(ident: str, w: float = 0.8, d: float = 0.35, h: float = 1.2) -> tuple[AssetRecord, MeshData]:
    """Open shelf: boards at 0, 0.4 and 1.18 m (2 cm thick), sides; surfaces on the two lower boards
    with 0.36 m and 0.76 m of clearance."""
    t = 0.02
    parts = [box_mesh((-w / 2, -d / 2, z), (w / 2, d / 2, z + t), (90, 90, 140)) for z in (0.0, 0.4, h - t)]
    parts += [box_mesh((sx * w / 2 - (t if sx > 0 else 0), -d / 2, 0.0), (sx * w / 2 + (0 if sx > 0 else t), d / 2, h))
              for sx in (-1, 1)]
    inner = ((-w / 2 + t, -d / 2), (w / 2 - t, -d / 2), (w / 2 - t, d / 2), (-w / 2 + t, d / 2))
    surfaces = (SupportSurface(t, inner, 0.4 - t - t), SupportSurface(0.4 + t, inner, h - t - 0.4 - t))
    return AssetRecord(ident, "test", ident, "shelf", ("floor",), (w, d, h), surfaces), merge(*parts)


def make_catalog(tmp_path, assets) -> Catalog:
    cat = Catalog.open_or_create(tmp_path / "catalog")
    for rec, mesh in assets:
        cat.add(rec, mesh)
    cat.save()
    return Catalog.open(tmp_path / "catalog")


def rect_room(wx: float = 5.0, wy: float = 4.0, height: float = 2.6, openings=()) -> Room:
    return Room(((0.0, 0.0), (wx, 0.0), (wx, wy), (0.0, wy)), height, tuple(openings), False)


def l_room() -> Room:
    return Room(((0.0, 0.0), (6.0, 0.0), (6.0, 3.0), (3.0, 3.0), (3.0, 5.0), (0.0, 5.0)), 2.7, (), False)


def plan(request: PlanRequest, relations: dict[int, list[Relation]] | None = None, order=None) -> GroupPlan:
    order = list(range(len(request.objects))) if order is None else order
    relations = relations or {}
    return GroupPlan(request.group, tuple(PlannedObject(i, tuple(relations.get(pos, ()))) for pos, i in enumerate(order)),
                     "test")


def footprint(inst: PlacedInstance, size) -> shapely.Polygon:
    yaw = float(np.arctan2(inst.pose[1, 0], inst.pose[0, 0]))
    return shapely.Polygon(rect_corners(np.array([inst.pose[0, 3]]), np.array([inst.pose[1, 3]]), np.array([yaw]),
                                        size[0], size[1])[0])


def front_dir(inst: PlacedInstance) -> np.ndarray:
    """World direction of the instance's front (canonical -y)."""
    return -inst.pose[:2, 1]


DOOR = Opening("door", 0, 2.5, 0.9, 0.0, 2.05)
WINDOW = Opening("window", 1, 2.0, 1.2, 0.9, 2.0)


def test_kit_box_mesh_is_closed_and_outward():
    import trimesh

    m = box_mesh((0, 0, 0), (1, 2, 3))
    tm = trimesh.Trimesh(m.vertices, m.faces, process=False)
    assert tm.is_watertight and tm.volume > 0 and abs(tm.volume - 6.0) < 1e-5

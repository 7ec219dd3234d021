"""Scene assembly, GLB export and the mesh-based layout checks."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.config import LayoutConfig
from assist3d.core.contracts import PlacedInstance, SceneLayout
from assist3d.core.geometry import pose_matrix
from assist3d.export.glb import export_glb
from assist3d.scene.assemble import assemble_scene
from assist3d.scene.checks import check_layout
from assist3d.placement import place_group
from assist3d.planning.relations import PlanRequest
from assist3d.scene.shell import build_shell

from test_placement_kit import DOOR, WINDOW, box_asset, make_catalog, plan, rect_room, shelf_asset, table_asset


@pytest.fixture
def catalog(tmp_path):
    assets = [box_asset("crate", 0.6, 0.5, 0.4, cls="crate"), box_asset("cup", 0.1, 0.1, 0.12, groups=("obj",), cls="cup"),
              box_asset("pic", 0.8, 0.04, 0.6, groups=("wall",), cls="picture"), table_asset("table"),
              shelf_asset("shelf")]
    return make_catalog(tmp_path, assets)


def _inst(ident, asset, cls, group, x, y, yaw=0.0, z=0.0, parent=None):
    return PlacedInstance(ident, asset, cls, group, pose_matrix(x, y, yaw, z), parent)


def _layout(*instances, room=None):
    return SceneLayout(room or rect_room(4.0, 3.0, openings=(DOOR, WINDOW)), tuple(instances), (), 0, 0.0)


def _good(catalog):
    return _layout(_inst(1, "table", "table", "floor", 2.0, 1.5, 0.4),
                   _inst(2, "crate", "crate", "floor", 0.5, 0.5),
                   _inst(3, "cup", "cup", "obj", 2.0, 1.5, 1.0, 0.75, parent=1),
                   _inst(4, "pic", "picture", "wall", 2.0, 2.979, 0.0, 1.2),
                   _inst(5, "shelf", "shelf", "floor", 3.5, 2.8, np.pi),
                   _inst(6, "cup", "cup", "obj", 3.5, 2.8, 0.0, 0.42, parent=5))


def test_shell_has_openings_cut_and_faces_inward():
    room = rect_room(4.0, 3.0, openings=(DOOR, WINDOW))
    parts = dict(build_shell(room))
    assert list(parts)[:5] == ["floor", "wall_0", "wall_1", "wall_2", "wall_3"] and "ceiling" not in parts
    area = lambda m: float(np.linalg.norm(np.cross(*(m.vertices[m.faces[:, k]] - m.vertices[m.faces[:, 0]]
                                                     for k in (1, 2))), axis=1).sum() / 2)
    assert abs(area(parts["floor"]) - 12.0) < 1e-4
    assert abs(area(parts["wall_0"]) - (4.0 * 2.6 - 0.9 * 2.05)) < 1e-4
    assert abs(area(parts["wall_1"]) - (3.0 * 2.6 - 1.2 * 1.1)) < 1e-4
    v, f = parts["wall_0"].vertices, parts["wall_0"].faces
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    assert (n[:, 1] > 0).all()  # wall 0 is y = 0: its inside is +y
    assert (np.cross(*(parts["floor"].vertices[parts["floor"].faces[:, k]] - parts["floor"].vertices[parts["floor"].faces[:, 0]]
                       for k in (1, 2)))[:, 2] > 0).all()


def test_assemble_labels_every_face(catalog):
    layout = _good(catalog)
    classes = ("crate", "cup", "picture", "table")
    mesh = assemble_scene(layout, catalog, classes)
    for inst in layout.instances:
        nf = len(catalog.load_mesh(inst.asset).faces)
        assert (mesh.face_instance == inst.id).sum() == nf
        seg = classes.index(inst.class_name) if inst.class_name in classes else -1
        assert (mesh.face_segment[mesh.face_instance == inst.id] == seg).all()
    bg = mesh.face_instance == -1
    assert (mesh.face_segment[bg] == -1).all() and (mesh.face_part[bg] < 0).all()
    assert mesh.background_names[0] == "floor" and mesh.background_names[-1] == "wall_3"
    # instance vertices are in the world frame of the poses
    cup = mesh.faces[mesh.face_instance == 3].ravel()
    assert abs(mesh.vertices[cup, 2].min() - 0.75) < 1e-5


def test_export_glb_round_trips_node_names(catalog, tmp_path):
    import trimesh

    layout = _good(catalog)
    path = tmp_path / "scene.glb"
    export_glb(layout, catalog, path)
    scene = trimesh.load(path, force="scene")
    names = set(scene.graph.nodes_geometry)
    assert {f"instance_{i.id}" for i in layout.instances} <= names
    assert {"background_floor", "background_wall_0", "background_wall_3"} <= names
    geom = scene.graph[f"instance_3"][1]
    transform = scene.graph[f"instance_3"][0]
    verts = trimesh.transform_points(scene.geometry[geom].vertices, transform)
    assert abs(verts[:, 2].min() - 0.75) < 1e-5 and abs(verts[:, 0].mean() - 2.0) < 0.06
    table = scene.geometry[scene.graph["instance_1"][1]]
    colors = table.visual.vertex_colors
    assert {tuple(c[:3]) for c in colors} == {(150, 100, 60), (120, 80, 50)}
    per_face = colors[table.faces][:, :, :3]
    assert (per_face == per_face[:, :1]).all(), "a face's corners must share its colour"
    assert len(table.vertices) < 3 * len(table.faces), "vertices of same-coloured faces stay shared"


def test_check_layout_passes_a_good_layout(catalog):
    assert check_layout(_good(catalog), catalog) == []


def test_check_layout_flags_interpenetration(catalog):
    lay = _layout(_inst(1, "crate", "crate", "floor", 1.0, 1.0), _inst(2, "crate", "crate", "floor", 1.3, 1.1, 0.2))
    problems = check_layout(lay, catalog)
    assert len(problems) == 1 and "interpenetrate" in problems[0]
    # touching is fine
    lay = _layout(_inst(1, "crate", "crate", "floor", 1.0, 1.0), _inst(2, "crate", "crate", "floor", 1.6, 1.0))
    assert check_layout(lay, catalog) == []


def test_check_layout_flags_floating_sunk_outside_and_off_wall(catalog):
    lay = _layout(_inst(1, "table", "table", "floor", 2.0, 1.5),
                  _inst(2, "cup", "cup", "obj", 2.0, 1.5, 0.0, 0.80, parent=1),   # floats 5 cm
                  _inst(3, "cup", "cup", "obj", 2.3, 1.5, 0.0, 0.70, parent=1),   # sunk 5 cm into the top
                  _inst(4, "crate", "crate", "floor", 3.9, 0.5),                  # through the wall
                  _inst(5, "crate", "crate", "floor", 0.6, 2.0, 0.0, 0.05),       # hovering over the floor
                  _inst(6, "pic", "picture", "wall", 2.0, 2.92, 0.0, 1.2))        # 6 cm off the wall
    text = "\n".join(check_layout(lay, catalog))
    assert "instance 2 (cup) on 1 (table): floats" in text
    assert "instances 1 (table) and 3 (cup) (resting on it) interpenetrate" in text
    assert "instance 4 (crate): outside the room" in text
    assert "instance 5 (crate): base 5.0 cm from the floor" in text
    assert "wall instance 6 (picture): 6.0 cm off wall 2" in text


def test_placed_layout_passes_the_checks(catalog):
    room = rect_room(3.0, 2.5)
    cfg = LayoutConfig()
    rng = np.random.default_rng(0)
    req = PlanRequest("floor", (catalog.get("table"), catalog.get("shelf"), catalog.get("crate")), room)
    floor = place_group(req, plan(req), catalog, cfg=cfg, rng=rng, next_id=1).instances
    instances = list(floor)
    for sup in floor[:2]:
        req = PlanRequest(f"on:{sup.id}", (catalog.get("cup"),) * 4, room, tuple(instances), sup)
        instances += place_group(req, plan(req), catalog, cfg=cfg, rng=rng, next_id=len(instances) + 1).instances
    assert len(instances) >= 9
    assert check_layout(_layout(*instances, room=room), catalog) == []

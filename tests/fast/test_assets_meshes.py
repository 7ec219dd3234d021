"""Mesh-folder importer, normalisation, support extraction and the ``assets`` commands."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
import trimesh

from assist3d.assets.catalog import Catalog
from assist3d.assets.meshes import import_meshes
from assist3d.assets.normalize import (axes_rotation, extract_supports, face_colors_of, normalize_loaded,
                                       to_canonical, validate_mesh)
from assist3d.core.contracts import MeshData


def _mesh(tm: trimesh.Trimesh) -> MeshData:
    return MeshData(vertices=np.asarray(tm.vertices, dtype=np.float32), faces=np.asarray(tm.faces, dtype=np.int32),
                    face_colors=np.full((len(tm.faces), 3), 128, dtype=np.uint8))


def _box(extents, center) -> trimesh.Trimesh:
    b = trimesh.creation.box(extents)
    b.apply_translation(center)
    return b


# ------------------------------------------------------------------------------------ normalize


def test_axes_rotation_is_proper_and_maps_axes():
    r = axes_rotation("+y", "+z")
    assert np.isclose(np.linalg.det(r), 1.0)
    assert np.allclose(r @ [0, 1, 0], [0, 0, 1]) and np.allclose(r @ [0, 0, 1], [0, -1, 0])
    assert np.allclose(axes_rotation("+z", "-y"), np.eye(3))
    with pytest.raises(ValueError):
        axes_rotation("+y", "-y")
    with pytest.raises(ValueError):
        axes_rotation("up", "+z")


def test_to_canonical_size_and_placement():
    v = np.array([[1, 2, 3], [3, 6, 4], [2, 2, 5]], dtype=float)
    out = to_canonical(v, size=(1.0, 2.0, 4.0))
    assert np.allclose(out.max(0) - out.min(0), (1, 2, 4))
    assert np.isclose(out[:, 2].min(), 0) and np.allclose((out.max(0) + out.min(0))[:2], 0)
    uni = to_canonical(v, scale=0.5)
    assert np.allclose(uni.max(0) - uni.min(0), (1.0, 2.0, 1.0))


def test_validate_mesh_reasons():
    tri = np.array([[0, 1, 2]])
    assert "no vertices" in validate_mesh(np.zeros((0, 3)), tri)
    assert "no triangles" in validate_mesh(np.eye(3), np.zeros((0, 3), dtype=int))
    assert "out of range" in validate_mesh(np.eye(3), np.array([[0, 1, 5]]))
    assert "NaN" in validate_mesh(np.array([[0, 0, np.nan], [1, 0, 0], [0, 1, 1]]), tri)
    assert "degenerate" in validate_mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]]), tri)
    assert validate_mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 1]]), tri) is None


def test_face_colours_from_vertex_colours_and_grey_fallback():
    b = trimesh.creation.box((1, 1, 1))
    b.visual.vertex_colors = np.tile([10, 200, 30, 255], (len(b.vertices), 1))
    assert np.all(face_colors_of(b) == (10, 200, 30))
    plain = trimesh.Trimesh(vertices=b.vertices, faces=b.faces, process=False)
    assert face_colors_of(plain).shape == (12, 3)


def test_supports_of_a_table_and_a_shelf():
    table = trimesh.util.concatenate([_box((1.2, 0.8, 0.04), (0, 0, 0.73))] + [
        _box((0.05, 0.05, 0.71), (x, y, 0.355)) for x in (-0.55, 0.55) for y in (-0.35, 0.35)])
    sup = extract_supports(_mesh(table))
    assert len(sup) == 1
    s = sup[0]
    from shapely.geometry import Polygon

    assert abs(s.height - 0.75) < 1e-4 and abs(Polygon(s.polygon).area - 0.96) < 0.01 and s.clearance is None
    assert Polygon(s.polygon).exterior.is_ccw
    # a bookcase on a plinth: boards with tops at 0.08, 0.48, 0.88 m between two side panels
    shelf = trimesh.util.concatenate([_box((0.8, 0.3, 0.02), (0, 0, z)) for z in (0.07, 0.47, 0.87)] + [
        _box((0.02, 0.3, 0.88), (x, 0, 0.44)) for x in (-0.41, 0.41)])
    sup = sorted(extract_supports(_mesh(shelf)), key=lambda s: s.height)
    assert [round(s.height, 3) for s in sup] == [0.08, 0.48, 0.88]
    assert abs(sup[0].clearance - 0.38) < 1e-3 and abs(sup[1].clearance - 0.38) < 1e-3 and sup[2].clearance is None


def test_normalize_loaded_drops_unused_vertices_and_rejects_nan():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [9, 9, 9]], dtype=float)
    tm = trimesh.Trimesh(vertices=v, faces=[[0, 1, 2], [0, 1, 3], [0, 2, 3]], process=False)
    out = normalize_loaded(tm, size=(1, 1, 1))
    assert len(out.mesh.vertices) == 4 and np.allclose(out.size, (1, 1, 1))
    tm_nan = trimesh.Trimesh(vertices=np.where(v == 9, np.nan, v), faces=[[0, 1, 4]], process=False)
    with pytest.raises(ValueError, match="NaN"):
        normalize_loaded(tm_nan)


# ------------------------------------------------------------------------------------ folder import


@pytest.fixture
def mesh_folder(tmp_path: Path) -> Path:
    folder = tmp_path / "objs"
    (folder / "sub").mkdir(parents=True)
    b = trimesh.creation.box((1.0, 0.5, 0.8))  # z-up box
    b.visual.face_colors = [200, 10, 10, 255]
    for ext in ("glb", "ply", "stl", "off", "obj"):
        b.export(folder / f"box.{ext}")
    b.export(folder / "sub" / "cup.ply")
    (folder / "empty.obj").write_text("")
    (folder / "nan.obj").write_text("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (folder / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n")
    (folder / "corrupt.glb").write_bytes(b"glTF\x02\x00\x00\x00garbage")
    (folder / "points.xyz").write_text("0 0 0\n")
    outside = tmp_path / "outside.obj"
    outside.write_text("v 0 0 0\nv 1 0 0\nv 0 1 1\nf 1 2 3\n")
    os.symlink(outside, folder / "link.obj")
    (tmp_path / "outside.mtl").write_text("newmtl red\nKd 1 0 0\n")
    (folder / "escape.obj").write_text("mtllib ../outside.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 1\nusemtl red\nf 1 2 3\n")
    return folder


MANIFEST_ROWS = [
    {"path": "box.glb", "class": "Storage Boxes", "size": [1.2, 0.6, 0.9], "up": "+z", "front": "-y", "license": "CC0"},
    {"path": "box.ply", "class": "crate", "groups": "floor", "up": "+z", "front": "-y"},
    {"path": "box.stl", "class": "crate", "groups": "floor;obj", "up": "z", "front": "-y", "scale": 0.5},
    {"path": "box.off", "class": "cabinet", "height": 2.0, "up": "+z", "front": "-y"},
    {"path": "box.obj", "class": "table"},  # default +y up: the 0.5 m side becomes the height
    {"path": "sub/cup.ply", "class": "cup", "size": "0.08 x 0.08 x 0.1", "up": "+z", "front": "-y"},
    {"path": "escape.obj", "class": "sheet", "up": "+z", "front": "-y"},  # its MTL lies outside: not read
    {"path": "empty.obj", "class": "thing"},
    {"path": "nan.obj", "class": "thing"},
    {"path": "flat.obj", "class": "thing"},
    {"path": "corrupt.glb", "class": "thing"},
    {"path": "points.xyz", "class": "thing"},
    {"path": "../outside.obj", "class": "thing"},
    {"path": "/etc/passwd.obj", "class": "thing"},
    {"path": "link.obj", "class": "thing"},
    {"path": "missing.obj", "class": "thing"},
    {"path": "box.glb", "id": "noclass"},
    {"path": "box.glb", "class": "x", "id": "badgroup", "groups": "ceiling"},
    {"path": "box.glb", "class": "x", "id": "badsize", "size": "1,2"},
]


def test_import_meshes_json_manifest(tmp_path, mesh_folder):
    manifest = tmp_path / "manifest.json"
    manifest.write_text(json.dumps({"assets": MANIFEST_ROWS}))
    cat = Catalog.open_or_create(tmp_path / "lib")
    report = import_meshes(cat, mesh_folder, manifest, workers=1)
    got = {r.extra["path"]: r for r in cat.records}
    assert set(got) == {"box.glb", "box.ply", "box.stl", "box.off", "box.obj", "sub/cup.ply", "escape.obj"}
    assert np.all(cat.load_mesh(got["escape.obj"]).face_colors == 160)  # grey: the outside MTL was refused
    assert np.allclose(got["box.glb"].size, (1.2, 0.6, 0.9), rtol=1e-5)
    assert got["box.glb"].class_name == "storage box" and got["box.glb"].license == "CC0"
    assert np.allclose(got["box.ply"].size, (1.0, 0.5, 0.8), rtol=1e-5) and got["box.ply"].groups == ("floor",)
    assert np.allclose(got["box.stl"].size, (0.5, 0.25, 0.4), rtol=1e-5) and got["box.stl"].groups == ("floor", "obj")
    assert np.allclose(got["box.off"].size, (2.5, 1.25, 2.0), rtol=1e-5)
    assert np.allclose(got["box.obj"].size, (1.0, 0.8, 0.5), rtol=1e-5)
    assert got["sub/cup.ply"].groups == ("obj",)
    assert np.all(cat.load_mesh(got["box.ply"]).face_colors == (200, 10, 10))
    reasons = " | ".join(f"{s.path}: {s.reason}" for s in report.skipped)
    for needle in ("empty", "NaN", "degenerate", "corrupt.glb", "unknown mesh format", "('..')", "absolute",
                   "outside the folder", "not found", "no 'class'", "groups", "three numbers"):
        assert needle in reasons, (needle, reasons)
    assert len(report.skipped) == 12
    # re-running replaces the collection's records: same ids, no duplicated skip reports
    again = import_meshes(Catalog.open(tmp_path / "lib"), mesh_folder, manifest, workers=1)
    cat2 = Catalog.open(tmp_path / "lib")
    assert again.total == 7 and len(cat2) == 7 and len(cat2.skipped) == 12


def test_import_meshes_csv_manifest_and_unreadable_manifest(tmp_path, mesh_folder):
    manifest = tmp_path / "m.csv"
    manifest.write_text("path,class,size,up,front\nbox.glb,box,\"1,1,1\",+z,-y\nbox.ply,box,,+q,-y\n")
    cat = Catalog.open_or_create(tmp_path / "lib")
    report = import_meshes(cat, mesh_folder, manifest, workers=1, collection="mine")
    assert [r.id for r in cat.records] == ["meshes:mine/box.glb"]
    assert len(report.skipped) == 1 and "m.csv:row 3" in report.skipped[0].path and "axis" in report.skipped[0].reason
    from assist3d.core.errors import AssetError

    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(AssetError, match="bad.json"):
        import_meshes(cat, mesh_folder, tmp_path / "bad.json")
    with pytest.raises(AssetError, match="not found"):
        import_meshes(cat, mesh_folder, tmp_path / "none.csv")


# ------------------------------------------------------------------------------------ CLI


def test_cli_import_and_stats_json(tmp_path, mesh_folder, monkeypatch):
    from typer.testing import CliRunner

    from assist3d.cli import app

    manifest = tmp_path / "manifest.json"
    manifest.write_text(json.dumps(MANIFEST_ROWS[:6]))
    lib = tmp_path / "lib"
    runner = CliRunner()
    res = runner.invoke(app, ["assets", "import", "meshes", str(mesh_folder), "--manifest", str(manifest),
                              "--library", str(lib), "--workers", "1", "--no-progress", "--json"])
    assert res.exit_code == 0, res.output
    monkeypatch.setenv("ASSIST3D_ASSETS", str(lib))  # the environment variable locates the catalog
    res = runner.invoke(app, ["assets", "stats", "--json"])
    assert res.exit_code == 0, res.output
    stats = json.loads(res.stdout)
    assert stats["assets"] == 6 and stats["sources"] == {"meshes": 6}
    assert set(stats["groups"]) == {"floor", "wall", "obj"} and stats["classes"] == 5 and stats["skipped"] == []
    res = runner.invoke(app, ["assets", "list", "--group", "obj", "--json"])
    assert res.exit_code == 0 and {r["class"] for r in json.loads(res.stdout)} == {"cup", "crate"}

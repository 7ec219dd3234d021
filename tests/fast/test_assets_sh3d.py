"""Sweet Home 3D importer: properties parsing, naming, groups, real catalogs, crafted bad inputs."""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from assist3d.assets.catalog import Catalog
from assist3d.assets.naming import assign_groups, class_from_name
from assist3d.assets.properties import parse_properties
from assist3d.assets.sh3d import SH3D_JAR, convert_entry, import_sh3d, read_catalog
from assist3d.core.contracts import AssetRecord, SkippedAsset

# ------------------------------------------------------------------------------------ helpers


def box_obj(w: float = 2.0, d: float = 1.0, h: float = 3.0, *, mtl: str | None = None, material: str | None = None,
            marker_front: bool = False) -> str:
    """An OBJ box (Y up, width x, depth z) with UVs; optionally a thin post at the front (+z) top."""
    lines = []
    if mtl:
        lines.append(f"mtllib {mtl}")
    boxes = [((-w / 2, 0, -d / 2), (w / 2, h, d / 2))]
    if marker_front:
        boxes.append(((-0.05, h, d / 2 - 0.1), (0.05, h * 1.5, d / 2)))
    lines += ["vt 0.25 0.25", "vt 0.75 0.25", "vt 0.75 0.75", "vt 0.25 0.75"]
    if material:
        lines.append(f"usemtl {material}")
    base = 0
    for lo, hi in boxes:
        for x in (lo[0], hi[0]):
            for y in (lo[1], hi[1]):
                for z in (lo[2], hi[2]):
                    lines.append(f"v {x} {y} {z}")
        quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
        for q in quads:
            lines.append("f " + " ".join(f"{base + i}/{k + 1}" for k, i in enumerate(q)))
        base += 8
    return "\n".join(lines) + "\n"


def png_bytes(rgb: tuple[int, int, int]) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.new("RGB", (8, 8), rgb).save(buf, format="PNG")
    return buf.getvalue()


def model_props(n: int, name: str, model: str, w=100, d=50, h=80, **extra) -> str:
    lines = [f"id#{n}=Test#{name.replace(' ', '')}{n}", f"name#{n}={name}", f"category#{n}=Living room",
             f"model#{n}=/{model}", f"width#{n}={w}", f"depth#{n}={d}", f"height#{n}={h}", f"creator#{n}=Tester"]
    lines += [f"{k}#{n}={v}" for k, v in extra.items()]
    return "\n".join(lines) + "\n"


@pytest.fixture
def crafted_sh3f(tmp_path: Path) -> Path:
    """A small .sh3f holding good models and every kind of broken one."""
    props = "license=Creative Commons Attribution 3.0 license\nname=Crafted\n"
    props += model_props(1, "Red box", "good/box.obj")
    props += model_props(2, "Tall box", "good/box2.obj", w=40, d=40, h=200, dropOnTopElevation=50)
    props += model_props(3, "Missing", "missing/none.obj")
    props += model_props(4, "Empty", "bad/empty.obj")
    props += model_props(5, "Nan", "bad/nan.obj")
    props += model_props(6, "Flat", "bad/flat.obj")
    props += model_props(7, "Window", "good/box.obj", doorOrWindow="true")
    props += "name#8=Broken \\u12G4 escape\n"  # a malformed escape: the line is skipped
    props += model_props(9, "Rotated", "good/marker.obj", w=60, d=30, h=90, modelRotation="1 0 0 0 0 1 0 -1 0")
    props += model_props(10, "Front marker", "good/marker.obj", w=60, d=30, h=90)
    props += model_props(11, "Bad size", "good/box.obj", w="abc")
    props += model_props(12, "Bad elevation", "good/box.obj", elevation="high")
    props += model_props(13, "Bad rotation", "good/box.obj", modelRotation="1 0 0")
    path = tmp_path / "Crafted.sh3f"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("PluginFurnitureCatalog.properties", props.encode("iso-8859-1"))
        z.writestr("good/box.obj", box_obj(mtl="box.mtl", material="red"))
        z.writestr("good/box.mtl", "newmtl red\nKd 1 1 1\nmap_Kd tex/red.png\n")
        z.writestr("good/tex/red.png", png_bytes((220, 20, 30)))
        z.writestr("good/box2.obj", box_obj(1, 1, 5))
        z.writestr("good/marker.obj", box_obj(2, 1, 2, marker_front=True))
        z.writestr("bad/empty.obj", "")
        z.writestr("bad/nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
        z.writestr("bad/flat.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 1 0 1\nf 1 2 3\nf 2 4 3\n")
    return path


# ------------------------------------------------------------------------------------ properties


def test_properties_escapes_continuations_separators_and_comments():
    text = (b"# comment\n! another\n  key1 = value one\nkey2:colon\nkey3 space separated\n"
            b"multi=first \\\n    second\nesc=caf\\u00e9 \\t tab \\\\ back\nlatin=Caf\xe9\n"
            b"name#3=Chair\nwidth#3=40\nkey\\=with\\:seps=v\nbad=\\uZZZZ\nlast=ok\n")
    p = parse_properties(text, source="t.properties")
    v = p.values
    assert v["key1"] == "value one" and v["key2"] == "colon" and v["key3"] == "space separated"
    assert v["multi"] == "first second"
    assert v["esc"] == "café \t tab \\ back"
    assert v["latin"] == "Café"  # ISO-8859-1
    assert v["key=with:seps"] == "v"
    assert "bad" not in v and v["last"] == "ok"
    assert len(p.errors) == 1 and "t.properties:" in p.errors[0] and "uZZZZ" in p.errors[0]
    assert p.indexed == {3: {"name": "Chair", "width": "40"}}


# ------------------------------------------------------------------------------------ naming / groups


@pytest.mark.parametrize("name,expected", [
    ("Bed 140x190", "bed"), ("Blue light source", "light source"), ("Shelves", "shelf"), ("Glasses", "glasses"),
    ("Convertible sofa BZ", "convertible sofa"), ("TV 16:9", "tv"), ("Parking slot 45°", "parking slot"),
    ("White board", "whiteboard"), ("Frame Hôi An", "frame hoi an"), ("Bill 10€", "bill"), ("42", "object"),
])
def test_class_from_name(name, expected):
    assert class_from_name(name) == expected


def test_assign_groups():
    assert assign_groups((1.6, 2.0, 0.7), name="Bed") == ("floor",)
    assert assign_groups((0.1, 0.1, 0.2), name="Cup") == ("obj",)
    assert assign_groups((0.4, 0.4, 0.5), name="Bedside table") == ("floor", "obj")
    assert assign_groups((0.6, 0.4, 0.7), elevation=1.45, name="Upper cabinet") == ("wall",)
    assert assign_groups((0.5, 0.02, 0.35), name="Frame") == ("wall",)
    assert assign_groups((0.6, 0.1, 0.5), elevation=0.1, name="Radiator") == ("wall",)
    assert assign_groups((0.3, 0.3, 0.05), elevation=2.4, name="Ceiling lamp") == ("wall",)


# ------------------------------------------------------------------------------------ crafted catalog


def test_crafted_catalog_good_models_import_and_bad_ones_are_skipped(tmp_path, crafted_sh3f):
    corrupt = tmp_path / "Corrupt.sh3f"
    corrupt.write_bytes(b"PK\x03\x04 this is not really a zip")
    cat = Catalog.open_or_create(tmp_path / "lib")
    report = import_sh3d(cat, [crafted_sh3f, corrupt], workers=1)
    ids = {r.id for r in cat.records}
    assert ids == {"sh3d:Crafted/Redbox1", "sh3d:Crafted/Tallbox2", "sh3d:Crafted/Rotated9", "sh3d:Crafted/Frontmarker10"}
    reasons = {s.path: s.reason for s in report.skipped}
    joined = "\n".join(f"{p} -> {r}" for p, r in reasons.items())
    assert any("Corrupt.sh3f" in p and "zip" in r for p, r in reasons.items()), joined
    assert any("none.obj" in p and "missing" in r for p, r in reasons.items()), joined
    assert any("empty.obj" in p and "empty" in r for p, r in reasons.items()), joined
    assert any("nan.obj" in p and "NaN" in r for p, r in reasons.items()), joined
    assert any("flat.obj" in p and "degenerate" in r for p, r in reasons.items()), joined
    assert any("'Window'" in p and "door or window" in r for p, r in reasons.items()), joined
    assert any("properties" in p and "uxxxx" in r.lower() for p, r in reasons.items()), joined
    assert any("'Bad size'" in p and "width" in r for p, r in reasons.items()), joined
    assert any("'Bad elevation'" in p and "elevation" in r for p, r in reasons.items()), joined
    assert any("'Bad rotation'" in p and "modelRotation" in r for p, r in reasons.items()), joined
    assert all("\n" not in r for r in reasons.values())
    # the texture colour reaches the faces; sizes are the catalog's (cm -> m)
    red = cat.get("sh3d:Crafted/Redbox1")
    mesh = cat.load_mesh(red)
    assert np.allclose(red.size, (1.0, 0.5, 0.8), rtol=1e-5)
    assert np.all(np.abs(mesh.face_colors.astype(int) - (220, 20, 30)).max(1) <= 3)
    assert red.license == "CC-BY-3.0" and "Tester" in red.attribution and red.family == "Living room"
    # dropOnTopElevation in cm gives the first support surface
    tall = cat.get("sh3d:Crafted/Tallbox2")
    assert tall.supports and abs(tall.supports[0].height - 0.5) < 1e-6
    stats = cat.stats().to_json()
    assert stats["assets"] == 4 and len(stats["skipped"]) == len(report.skipped)


def test_obj_front_maps_to_minus_y_and_model_rotation_is_applied(tmp_path, crafted_sh3f):
    cat = Catalog.open_or_create(tmp_path / "lib")
    import_sh3d(cat, [crafted_sh3f], workers=1)
    plain = cat.load_mesh("sh3d:Crafted/Frontmarker10").vertices
    top = plain[plain[:, 2] > 0.8 * plain[:, 2].max()]
    assert top[:, 1].mean() < -0.1  # the OBJ's front (+z) post is at the canonical front (-y)
    rotated = cat.load_mesh("sh3d:Crafted/Rotated9").vertices
    assert np.allclose(rotated.max(0) - rotated.min(0), (0.6, 0.3, 0.9), rtol=1e-5)
    # modelRotation (x, y, z) -> (x, z, -y) turns the post (OBJ +y above the box, at the front +z)
    # into a bar sticking out at the back (+y) along the top tenth of the height
    frac = (rotated - rotated.min(0)) / (rotated.max(0) - rotated.min(0))
    back = frac[:, 1] > 0.7
    assert back.any() and np.all(frac[back, 2] >= 0.89)


def test_reimport_is_idempotent_and_interrupted_import_keeps_complete_entries(tmp_path, crafted_sh3f):
    lib = tmp_path / "lib"
    cat = Catalog.open_or_create(lib)
    import_sh3d(cat, [crafted_sh3f], workers=1)
    first = json.loads((lib / "index.json").read_text())
    mesh_bytes = {p.name: p.read_bytes() for p in (lib / "meshes").glob("*.npz")}
    cat2 = Catalog.open(lib)
    import_sh3d(cat2, [crafted_sh3f], workers=1)
    second = json.loads((lib / "index.json").read_text())
    assert first["assets"] == second["assets"]  # same records, nothing duplicated
    assert len(first["skipped"]) == len(second["skipped"])
    assert {p.name: p.read_bytes() for p in (lib / "meshes").glob("*.npz")} == mesh_bytes  # byte-identical

    # kill the import after the second model: the saved index lists only loadable meshes
    lib2 = tmp_path / "lib2"
    cat3 = Catalog.open_or_create(lib2)

    def stop(done, total, name):
        if done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        import_sh3d(cat3, [crafted_sh3f], workers=1, save_every=1, progress=stop)
    saved = Catalog.open(lib2)
    assert 0 < len(saved) <= 3
    for r in saved.records:
        assert len(saved.load_mesh(r).faces) == r.triangles


# ------------------------------------------------------------------------------------ real data


@pytest.fixture(scope="module")
def jar_entries():
    if not SH3D_JAR.is_file():
        pytest.skip("sweethome3d.jar not installed (apt-get install sweethome3d)")
    got = read_catalog(SH3D_JAR)
    assert len(got.entries) >= 90 and not got.skipped
    return {e.asset_id: e for e in got.entries}


def _convert(entry) -> tuple[AssetRecord, object]:
    result = convert_entry(entry)
    assert not isinstance(result, SkippedAsset), result
    return result


def test_jar_models_sizes_frame_and_supports(jar_entries):
    checked = 0
    for key in ("roundTable", "bookcase", "chair", "bed140x190"):
        entry = jar_entries[f"sh3d:DefaultFurnitureCatalog/{key}"]
        rec, mesh = _convert(entry)
        want = np.array([float(entry.props[k]) for k in ("width", "depth", "height")]) / 100
        ext = mesh.vertices.max(0) - mesh.vertices.min(0)
        assert np.all(np.abs(ext - want) <= 0.05 * want), (key, ext, want)
        lo, hi = mesh.vertices.min(0), mesh.vertices.max(0)
        assert abs(lo[2]) < 1e-5 and np.allclose((lo[:2] + hi[:2]) / 2, 0, atol=1e-5)
        assert rec.license and rec.attribution and rec.family
        assert not np.all(mesh.face_colors == 160)  # named materials (no MTL in the jar) give colours
        checked += 1
    table, _ = _convert(jar_entries["sh3d:DefaultFurnitureCatalog/roundTable"])
    top = max(table.supports, key=lambda s: s.height)
    assert abs(top.height - 0.74) < 0.02
    from shapely.geometry import Polygon

    assert Polygon(top.polygon).area > 0.8 * np.pi * 0.63 ** 2 * 0.9 and top.clearance is None
    shelf, _ = _convert(jar_entries["sh3d:DefaultFurnitureCatalog/bookcase"])
    inner = [s for s in shelf.supports if s.clearance is not None]
    assert len(inner) >= 3 and all(0.1 < s.clearance < 0.5 for s in inner)
    assert any(abs(s.height - 0.972) < 1e-3 for s in shelf.supports)  # dropOnTopElevation 97.2 cm
    assert checked == 4
    assert jar_entries["sh3d:DefaultFurnitureCatalog/bed140x190"].props["name"] == "Bed 140x190"


def test_jar_door_is_skipped(jar_entries):
    doors = [e for e in jar_entries.values() if e.props.get("doorOrWindow") == "true"]
    assert doors
    result = convert_entry(doors[0])
    assert isinstance(result, SkippedAsset) and "door or window" in result.reason


def test_real_reallusion_catalog_imports(tmp_path, sh3d_dir):
    path = sh3d_dir / "Reallusion.sh3f"
    if not path.is_file():
        pytest.skip("Reallusion.sh3f not installed")
    cat = Catalog.open_or_create(tmp_path / "lib")
    report = import_sh3d(cat, [path], workers=2)
    entries = {e.asset_id: e for e in read_catalog(path).entries}
    assert report.total == len(entries) == 25 and not report.skipped
    for r in cat.records:
        want = np.array([float(entries[r.id].props[k]) for k in ("width", "depth", "height")]) / 100
        assert np.all(np.abs(np.array(r.size) - want) <= 0.05 * want)
        assert r.license == "CC-BY-3.0-US" and r.groups == ("floor",) and r.class_name
    textured = cat.load_mesh(cat.records[0])
    assert len(np.unique(textured.face_colors, axis=0)) > 3  # colours sampled from the textures


# ------------------------------------------------------------------------------------ fast OBJ reader


def test_fast_obj_reader_forms_polygons_materials_and_fallbacks():
    from assist3d.assets.objfile import ObjUnsupported, face_colors, parse_mtl, parse_obj

    obj = parse_obj(b"# c\r\nmtllib m.mtl\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0 # note\r\nv 0 1 0\r\nvt 0.1 0.1\r\nvt 0.9 0.9\r\n"
                    b"usemtl tex\r\nf 1/2 2/2 3/1 4/2\r\nusemtl red\r\nf 1//1 3//1 4//1\r\nf 1/2/1 2/1/1 3\r\n")
    assert obj.faces.tolist() == [[0, 1, 2], [0, 2, 3], [0, 2, 3], [0, 1, 2]]
    assert obj.face_material.tolist() == [0, 0, 1, 1] and obj.material_names == ("tex", "red")
    assert obj.face_uv[0].tolist() == [1, 1, 0] and obj.face_uv[2].tolist() == [-1, -1, -1]
    assert obj.mtllibs == ("m.mtl",)
    mats = parse_mtl(b"newmtl tex\nKd 1 1 1\nmap_Kd -s 1 1 1 wood.png\nnewmtl red\nKd 1 0 0\n")
    assert mats["tex"].texture == "wood.png" and np.allclose(mats["red"].kd, (255, 0, 0))
    tex = np.zeros((2, 2, 3))
    tex[:, 1] = (0, 0, 250)  # right half blue, left half black
    colours = face_colors(obj, mats, lambda name: tex if name == "wood.png" else None)
    assert colours[2].tolist() == [255, 0, 0] and colours[0].tolist() == [0, 0, 250]  # UV centroid u = 0.63
    for bad in (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n", b"v 0 0 0\nv 1 0 x\nf 1 2 3\n",
                b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n 3\n"):
        with pytest.raises(ObjUnsupported):
            parse_obj(bad)


def test_fast_reader_agrees_with_trimesh_on_real_models(jar_entries):
    from assist3d.assets.normalize import compact
    from assist3d.assets.sh3d import _load_arrays

    for key in ("chair", "bookcase", "roundTable"):
        entry = jar_entries[f"sh3d:DefaultFurnitureCatalog/{key}"]
        va, fa, ca = compact(*_load_arrays(entry, fast=True))
        vb, fb, cb = compact(*_load_arrays(entry, fast=False))
        assert len(fa) == len(fb) and np.allclose(np.ptp(va, 0), np.ptp(vb, 0))
        assert np.abs(ca.mean(0) - cb.mean(0)).max() < 3


@pytest.mark.acceptance
def test_full_debian_import_acceptance(tmp_path, sh3d_dir):
    """Issue 2 acceptance on all installed catalogs (~1.5 min on 2 cores; the same figures are
    printed by `assist3d assets import sh3d --json`): >= 800 assets, >= 400 classes, every group
    non-empty, sizes within 5 % of the catalog's, only doors/windows and line-only models skipped."""
    from assist3d.assets.sh3d import default_sh3d_paths

    cat = Catalog.open_or_create(tmp_path / "lib")
    report = import_sh3d(cat)
    stats = cat.stats().to_json()
    assert stats["assets"] >= 800 and stats["classes"] >= 400 and all(stats["groups"].values())
    props = {e.asset_id: e.props for p in default_sh3d_paths() for e in read_catalog(p).entries}
    for r in cat.records:
        want = np.array([float(props[r.id][k]) for k in ("width", "depth", "height")]) / 100
        assert np.all(np.abs(np.array(r.size) - want) <= 0.05 * want + 1e-9), r.id
    assert all(s.reason.startswith(("door or window", "no triangles")) for s in report.skipped)


def test_outdoor_models_carry_nothing(tmp_path):
    # A box table indoors has its top as a support; the same box in the Exterior or Vehicles
    # category (pools, cars) has none.
    props = "license=Creative Commons Attribution 3.0 license\nname=Outdoor\n"
    props += model_props(1, "Box table", "m/box.obj", w=100, d=60, h=75)
    props += model_props(2, "Pool", "m/box.obj", w=100, d=60, h=75).replace("category#2=Living room", "category#2=Exterior")
    props += model_props(3, "Car", "m/box.obj", w=100, d=60, h=75).replace("category#3=Living room", "category#3=Vehicles")
    path = tmp_path / "Outdoor.sh3f"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("PluginFurnitureCatalog.properties", props.encode("iso-8859-1"))
        z.writestr("m/box.obj", box_obj(1, 1, 1))
    cat = Catalog.open_or_create(tmp_path / "lib")
    import_sh3d(cat, [path], workers=1)
    by_name = {r.name: r for r in cat.records}
    assert by_name["Box table"].supports and abs(by_name["Box table"].supports[0].height - 0.75) < 0.01
    assert by_name["Pool"].supports == () and by_name["Car"].supports == ()

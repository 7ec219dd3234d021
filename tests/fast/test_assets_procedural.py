"""The built-in procedural library: every family yields valid canonical meshes with true supports,
and libraries are deterministic, prefix-stable and idempotent."""

from __future__ import annotations

import hashlib
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import trimesh

from assist3d.assets.catalog import Catalog
from assist3d.assets.procedural import (ATTRIBUTION, FAMILIES, GROUP_WEIGHTS, LICENSE, SOURCE, build_asset,
                                        build_family, build_library, family_names, family_of)
from assist3d.assets.procedural._build import SCREEN
from assist3d.core.contracts import GROUPS, AssetRecord, MeshData
from assist3d.core.errors import AssetError

NAMES = sorted(FAMILIES)
SEEDS = (0, 7)


def _trimesh(mesh: MeshData) -> trimesh.Trimesh:
    return trimesh.Trimesh(mesh.vertices.astype(np.float64), mesh.faces, process=False)


def _cast(tm: trimesh.Trimesh, origins: np.ndarray, direction: tuple[float, float, float]) -> np.ndarray:
    """Distance to the first hit of each ray (inf = miss)."""
    dirs = np.tile(np.asarray(direction, dtype=np.float64), (len(origins), 1))
    loc, ray, _ = tm.ray.intersects_location(origins, dirs, multiple_hits=False)
    dist = np.full(len(origins), np.inf)
    dist[ray] = np.linalg.norm(loc - origins[ray], axis=1)
    return dist


def test_registry_has_enough_families_in_every_group():
    assert len(FAMILIES) >= 60
    primary = Counter(f.groups[0] for f in FAMILIES.values())
    assert set(primary) == set(GROUPS) == set(GROUP_WEIGHTS)
    assert primary["floor"] >= 20 and primary["wall"] >= 10 and primary["obj"] >= 25
    for fam in FAMILIES.values():
        assert fam.groups and set(fam.groups) <= set(GROUPS) and len(set(fam.groups)) == len(fam.groups)
        assert fam.weight > 0
    assert sorted(family_names()) == NAMES  # the first pass visits every family exactly once


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.slow
def test_family_builds_valid_canonical_mesh(name):
    fam = FAMILIES[name]
    for seed in SEEDS:
        shape = build_family(name, rng=np.random.default_rng(seed))
        m = shape.mesh
        where = f"{name} seed {seed}"
        assert m.vertices.dtype == np.float32 and m.faces.dtype == np.int32 and m.face_colors.dtype == np.uint8
        assert np.isfinite(m.vertices).all(), where
        assert 4 <= len(m.faces) <= 5000, f"{where}: {len(m.faces)} triangles"
        assert m.faces.min() >= 0 and m.faces.max() < len(m.vertices)
        tm = _trimesh(m)
        assert tm.area_faces.min() > 1e-10, f"{where}: degenerate triangles"
        assert tm.is_watertight, f"{where}: not watertight"
        assert tm.is_winding_consistent, f"{where}: inconsistent winding"
        # every closed part has positive volume, i.e. outward normals
        parts = trimesh.graph.connected_components(tm.face_adjacency, nodes=np.arange(len(m.faces)), min_len=1)
        for part in parts:
            assert trimesh.Trimesh(tm.vertices, m.faces[part], process=False).volume > 0, f"{where}: inward part"
        # canonical frame: base at z = 0, footprint centred, recorded size = bounding box
        lo, hi = m.vertices.min(0).astype(np.float64), m.vertices.max(0).astype(np.float64)
        assert abs(lo[2]) <= 1e-4, where
        assert abs(lo[0] + hi[0]) <= 2e-4 and abs(lo[1] + hi[1]) <= 2e-4, f"{where}: footprint not centred"
        np.testing.assert_allclose(hi - lo, shape.size, rtol=0.01, err_msg=where)
        assert all(0.003 < s < 3.0 for s in shape.size), f"{where}: implausible size {shape.size}"
        assert shape.class_name and shape.class_name == shape.class_name.lower().strip()
        if "wall" in fam.groups:
            assert 0.0 <= shape.elevation and shape.elevation + shape.size[2] <= 2.45, f"{where}: hangs too high"
        else:
            assert shape.elevation == 0.0


@pytest.mark.parametrize("name", [n for n in NAMES if n not in {"superquadric", "blob", "convex_shape"}])
@pytest.mark.slow
def test_supports_lie_on_the_mesh(name):
    """A ray dropped from just above a support polygon lands on it; nothing intrudes below its clearance."""
    seen = 0
    for seed in range(4):
        shape = build_family(name, rng=np.random.default_rng(seed))
        if not shape.supports:
            continue
        tm = _trimesh(shape.mesh)
        half = np.array(shape.size[:2]) / 2
        for k, sup in enumerate(shape.supports):
            where = f"{name} seed {seed} support {k}"
            poly = np.asarray(sup.polygon)
            assert len(poly) >= 3
            area = 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
            assert area > 0, f"{where}: polygon not counter-clockwise"
            assert (np.abs(poly) <= half + 1e-6).all(), f"{where}: polygon outside the footprint"
            assert 0 < sup.height <= shape.size[2] + 1e-6
            pts = np.vstack([poly, poly.mean(0), (poly + np.roll(poly, -1, 0)) / 2])
            eps = 0.005
            origins = np.column_stack([pts, np.full(len(pts), sup.height + eps)])
            down = _cast(tm, origins, (0.0, 0.0, -1.0))
            np.testing.assert_allclose(down, eps, atol=1e-3, err_msg=f"{where}: not on a surface")
            up = _cast(tm, origins, (0.0, 0.0, 1.0))
            if sup.clearance is None:
                assert np.isinf(up).all(), f"{where}: blocked above but no clearance recorded"
            else:
                assert sup.clearance > 0.03
                assert (up >= sup.clearance - eps - 1e-3).all(), f"{where}: clearance {sup.clearance} overstated"
                assert np.isfinite(up).any(), f"{where}: clearance recorded but nothing above"
            seen += 1
    if name in {"table_rect", "bookshelf", "bed", "cabinet", "wall_shelf", "sofa", "kitchen_counter", "tray"}:
        assert seen > 0, f"{name}: expected support surfaces"


@pytest.mark.parametrize("name", ["chair", "sofa", "armchair", "bed", "office_chair", "toilet"])
def test_backs_are_at_plus_y(name):
    for seed in SEEDS:
        v = build_family(name, rng=np.random.default_rng(seed)).mesh.vertices
        top = v[v[:, 2] > np.percentile(v[:, 2], 85)]
        assert top[:, 1].mean() > 0, f"{name} seed {seed}: tallest part should be at the back (+y)"


@pytest.mark.parametrize("name", ["tv_wall", "monitor", "tv_on_foot"])
def test_screens_face_minus_y(name):
    for seed in SEEDS:
        m = build_family(name, rng=np.random.default_rng(seed)).mesh
        tm = _trimesh(m)
        z = (m.vertices[:, 2].min() + m.vertices[:, 2].max()) / 2
        hit = tm.ray.intersects_first(np.array([[0.0, -10.0, z]]), np.array([[0.0, 1.0, 0.0]]))[0]
        assert hit >= 0 and tuple(m.face_colors[hit]) == SCREEN, f"{name} seed {seed}: screen not seen from -y"


def test_wall_items_have_a_flat_back_at_plus_y():
    for name in NAMES:
        if FAMILIES[name].groups[0] != "wall":
            continue
        for seed in SEEDS:
            m = build_family(name, rng=np.random.default_rng(seed)).mesh
            tm = _trimesh(m)
            back = np.abs(m.vertices[:, 1] - m.vertices[:, 1].max()) < 1e-4
            assert back.sum() >= 3, f"{name}: no flat back"
            # faces on the back plane point +y
            on_back = back[m.faces].all(axis=1)
            assert (tm.face_normals[on_back][:, 1] > 0.99).all()


def test_big_assets_of_floor_obj_families_stay_on_the_floor():
    from assist3d.assets.procedural import asset_groups

    assert asset_groups(("obj", "floor"), (0.3, 0.2, 0.25)) == ("obj", "floor")
    assert asset_groups(("obj", "floor"), (0.3, 0.2, 0.9)) == ("floor",)
    assert asset_groups(("floor", "obj"), (0.8, 0.3, 0.3)) == ("floor",)
    assert asset_groups(("obj",), (0.8, 0.8, 0.9)) == ("obj",)  # single-group families keep theirs


def test_assets_are_deterministic_and_independent_of_count():
    rec_a, mesh_a = build_asset(5, 130)
    rec_b, mesh_b = build_asset(5, 130)
    assert rec_a == rec_b
    for field in ("vertices", "faces", "face_colors"):
        assert getattr(mesh_a, field).tobytes() == getattr(mesh_b, field).tobytes()
    rec_c, mesh_c = build_asset(6, 130)
    assert rec_c.id != rec_a.id or mesh_c.vertices.tobytes() != mesh_a.vertices.tobytes()
    assert family_of(5, 3) == family_names()[3]
    with pytest.raises(AssetError, match="index"):
        build_asset(0, -1)


def _hashes(root: Path) -> dict[str, str]:
    cat = Catalog.open(root)
    out = {}
    for r in cat.records:
        with np.load(root / r.mesh_file) as z:
            h = hashlib.sha256()
            for k in ("vertices", "faces", "face_colors"):
                h.update(z[k].tobytes())
        out[r.id] = h.hexdigest()
    return out


@pytest.mark.slow
def test_library_is_byte_identical_for_a_seed_and_a_prefix_of_bigger_ones(tmp_path):
    a = build_library(tmp_path / "a", count=40, seed=11)
    b = build_library(tmp_path / "b", count=40, seed=11)
    assert len(a) == len(b) == 40
    ha, hb = _hashes(tmp_path / "a"), _hashes(tmp_path / "b")
    assert ha == hb
    assert (tmp_path / "a" / "index.json").read_bytes() == (tmp_path / "b" / "index.json").read_bytes()
    # a bigger library starts with the same assets
    build_library(tmp_path / "c", count=60, seed=11)
    hc = _hashes(tmp_path / "c")
    assert {k: hc[k] for k in ha} == ha
    # another seed changes the shapes
    build_library(tmp_path / "d", count=40, seed=12)
    hd = _hashes(tmp_path / "d")
    assert sum(hd.get(k) == v for k, v in ha.items()) == 0


def test_workers_do_not_change_the_output(tmp_path):
    build_library(tmp_path / "one", count=24, seed=3, workers=1)
    build_library(tmp_path / "two", count=24, seed=3, workers=2)
    assert _hashes(tmp_path / "one") == _hashes(tmp_path / "two")
    assert (tmp_path / "one" / "index.json").read_bytes() == (tmp_path / "two" / "index.json").read_bytes()


@pytest.mark.slow
def test_library_of_200_covers_every_family_and_group(tmp_path):
    cat = build_library(tmp_path / "lib", count=200, seed=0)
    recs = cat.records
    assert len(recs) == 200
    assert {r.family for r in recs} == set(FAMILIES)
    stats = cat.stats()
    assert all(stats.groups[g] > 0 for g in GROUPS)
    assert stats.groups["obj"] > stats.groups["wall"]
    assert stats.sources == {SOURCE: 200}
    assert stats.classes >= 60
    for r in recs:
        fam, idx = r.id.removeprefix("proc:").split("/")
        assert r.family == fam == family_of(0, int(idx)) and len(idx) == 6
        assert r.source == SOURCE and r.license == LICENSE and r.attribution == ATTRIBUTION
        assert r.groups and set(r.groups) <= set(FAMILIES[fam].groups)
        assert r.groups == FAMILIES[fam].groups or ("obj" not in r.groups and max(r.size) > 0.5)
        mesh = cat.load_mesh(r)
        assert r.triangles == len(mesh.faces)
        np.testing.assert_allclose(mesh.vertices.max(0) - mesh.vertices.min(0), r.size, rtol=0.01)
    # the records survive the JSON round trip
    reopened = Catalog.open(tmp_path / "lib")
    assert reopened.records == recs
    assert all(isinstance(r, AssetRecord) for r in reopened.records)


def test_build_library_is_idempotent_and_keeps_other_sources(tmp_path):
    root = tmp_path / "lib"
    cat = build_library(root, count=30, seed=1)
    other = AssetRecord(id="meshes:x/one", source="meshes", name="one", class_name="thing", groups=("obj",),
                        size=(1.0, 1.0, 1.0))
    cat.add(other, build_asset(1, 0)[1])
    cat.save()
    index = (root / "index.json").read_bytes()
    mtimes = {p: p.stat().st_mtime_ns for p in (root / "meshes").iterdir()}
    again = build_library(root, count=30, seed=1)  # up to date: nothing rewritten
    assert (root / "index.json").read_bytes() == index
    assert {p: p.stat().st_mtime_ns for p in (root / "meshes").iterdir()} == mtimes
    assert len(again) == 31
    smaller = build_library(root, count=10, seed=1)  # replaces the procedural part only
    assert len([r for r in smaller.records if r.source == SOURCE]) == 10
    assert "meshes:x/one" in smaller


def test_concurrent_builds_of_one_library_agree(tmp_path):
    """Parallel scene workers may all build the missing default library at once: harmless."""
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=3) as pool:
        list(pool.map(lambda _: build_library(tmp_path / "lib", count=25, seed=9), range(3)))
    build_library(tmp_path / "ref", count=25, seed=9)
    assert _hashes(tmp_path / "lib") == _hashes(tmp_path / "ref")
    assert len(list((tmp_path / "lib" / "meshes").iterdir())) == 25


def test_smaller_rebuild_removes_orphan_meshes(tmp_path):
    root = tmp_path / "lib"
    build_library(root, count=20, seed=2)
    assert len(list((root / "meshes").glob("*.npz"))) == 20
    cat = build_library(root, count=8, seed=2)
    files = sorted(p.name for p in (root / "meshes").glob("*.npz"))
    assert files == sorted(Path(r.mesh_file).name for r in cat.records)
    assert not list((root / "meshes").glob(".*.tmp"))  # no half-written leftovers


def test_open_catalog_falls_back_to_the_procedural_library():
    from assist3d.assets import open_catalog, procedural_library_dir

    cat = open_catalog(procedural_count=15, procedural_seed=4)  # the cache folder is isolated by conftest
    assert len(cat) == 15 and cat.root == procedural_library_dir(15, 4)
    assert {r.source for r in cat.records} == {SOURCE}


def test_bad_arguments_raise_clear_errors(tmp_path):
    with pytest.raises(AssetError, match="did you mean 'chair'"):
        build_family("chiar", rng=np.random.default_rng(0))
    with pytest.raises(AssetError, match=">= 1"):
        build_library(tmp_path / "x", count=0, seed=0)


def test_open_catalog_rebuilds_a_library_from_an_older_generator_version():
    from dataclasses import replace

    from assist3d.assets import open_catalog, procedural_library_dir
    from assist3d.assets.catalog import Catalog

    open_catalog(None, procedural_count=12, procedural_seed=3)
    cat = Catalog.open(procedural_library_dir(12, 3))
    for r in cat.records:  # pretend an older assist3d built it
        cat.update_record(replace(r, extra={**r.extra, "version": -1}))
    cat.save()
    again = open_catalog(None, procedural_count=12, procedural_seed=3)
    assert len(again) == 12 and all(r.extra["version"] != -1 for r in again.records)

"""Readers on small files written in the exact layouts of the real datasets."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pytest

from assist3d.data import open_dataset, parse_spec
from assist3d.data.ply import read_ply, write_ply
from assist3d.core.errors import ConfigError, DataError

# A 4 x 2 grid of vertices on the z = 0 plane, two triangles per cell.
GRID = np.array([[x, y, 0.0] for y in range(2) for x in range(4)], np.float32)
FACES = np.array([[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6]])
RGB = (np.arange(24).reshape(8, 3) * 10).astype(np.uint8)
SEG = [5, 5, 17, 17, 9, 9, 9, 42]  # arbitrary, non-contiguous segment ids per vertex
TSV = (
    "id\traw_category\tcategory\tcount\tnyu40id\teigen13id\tnyuClass\n"
    "1\twall\twall\t8277\t1\t12\twall\n"
    "2\tchair\tchair\t4646\t5\t4\tchair\n"
    "3\ttable\ttable\t1170\t7\t5\ttable\n"
    "4\tceiling\tceiling\t806\t22\t3\tceiling\n"
)


def write_scannet_scene(root: Path, scene: str = "scene0000_00", *, segs: list[int] = SEG) -> Path:
    d = root / "scans" / scene
    d.mkdir(parents=True)
    write_ply(d / f"{scene}_vh_clean_2.ply", GRID, RGB, FACES)
    (d / f"{scene}_vh_clean_2.0.010000.segs.json").write_text(json.dumps(
        {"params": {"kThresh": "0.0001", "segMinVerts": "20"}, "sceneId": scene, "segIndices": segs}))
    (d / f"{scene}.aggregation.json").write_text(json.dumps({
        "sceneId": f"scannet.{scene}", "appId": "Aggregator.v2",
        "segGroups": [
            {"id": 0, "objectId": 0, "segments": [5], "label": "wall"},
            {"id": 1, "objectId": 1, "segments": [17], "label": "chair"},
            {"id": 2, "objectId": 2, "segments": [9], "label": "table"},
        ],
        "segmentsFile": f"scannet.{scene}_vh_clean_2.0.010000.segs.json",
    }))
    return d


def test_ply_binary_header_and_faces(tmp_path):
    p = tmp_path / "m.ply"
    write_ply(p, GRID, RGB, FACES)
    head = p.read_bytes()[:400].decode("ascii", "replace")
    assert "format binary_little_endian 1.0" in head and "property uchar alpha" in head
    mesh = read_ply(p, faces=True)
    assert np.array_equal(mesh.xyz(), GRID) and np.array_equal(mesh.rgb(), RGB)
    assert np.array_equal(mesh.faces, FACES)


def test_ply_ascii(tmp_path):
    p = tmp_path / "a.ply"
    p.write_text("ply\nformat ascii 1.0\ncomment hi\nelement vertex 3\nproperty float x\nproperty float y\n"
                 "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                 "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n3 0 1 2\n")
    mesh = read_ply(p, faces=True)
    assert mesh.xyz().tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    assert mesh.rgb()[2].tolist() == [0, 0, 255]
    assert mesh.faces.tolist() == [[0, 1, 2]]


def test_ply_truncated_and_garbage(tmp_path):
    p = tmp_path / "m.ply"
    write_ply(p, GRID, RGB, FACES)
    p.write_bytes(p.read_bytes()[:-100])
    with pytest.raises(DataError, match=r"m\.ply.*truncated"):
        read_ply(p, faces=True)
    q = tmp_path / "g.ply"
    q.write_bytes(b"not a mesh")
    with pytest.raises(DataError, match=r"g\.ply.*not a PLY"):
        read_ply(q)


def test_scannet_reader(tmp_path):
    write_scannet_scene(tmp_path)
    (tmp_path / "scannetv2-labels.combined.tsv").write_text(TSV)
    ds = open_dataset(f"scannet:{tmp_path}")
    assert ds.scene_ids == ["scene0000_00"] and ds.format == "scannet"
    s = ds[0]
    # wall (seg 5) -> void, ScanNet-20 index 0; chair (17) -> object 0, index 4; table (9) ->
    # object 1, index 6; unannotated (42) -> void, -1.
    assert s.instance.tolist() == [-1, -1, 0, 0, 1, 1, 1, -1]
    assert s.segment.tolist() == [0, 0, 4, 4, 6, 6, 6, -1]
    assert np.array_equal(s.coord, GRID) and np.array_equal(s.color, RGB)
    assert np.allclose(np.abs(s.normal[:, 2]), 1.0)  # flat mesh: vertical normals
    assert s.valid.all() and s.instance.dtype == np.int32


def test_scannet_annotated_objects_option(tmp_path):
    """``?objects=annotated`` counts every annotated instance the label map knows but the room's
    structure: a lamp (outside the 18 benchmark classes) becomes an object, the wall and the ceiling
    stay void, and a label the map lacks stays void; classes (``segment``) do not change."""
    d = write_scannet_scene(tmp_path)
    (tmp_path / "scannetv2-labels.combined.tsv").write_text(TSV + "5\tlamp\tlamp\t300\t35\t13\tlamp\n")
    (d / "scene0000_00_vh_clean_2.0.010000.segs.json").write_text(json.dumps(
        {"segIndices": [5, 5, 17, 17, 9, 33, 7, 42]}))
    (d / "scene0000_00.aggregation.json").write_text(json.dumps({"segGroups": [
        {"objectId": 0, "segments": [5], "label": "wall"}, {"objectId": 1, "segments": [17], "label": "chair"},
        {"objectId": 2, "segments": [9], "label": "lamp"}, {"objectId": 3, "segments": [33], "label": "ceiling"},
        {"objectId": 4, "segments": [7], "label": "no such label"}]}))
    bench = open_dataset(f"scannet:{tmp_path}")[0]
    assert bench.instance.tolist() == [-1, -1, 0, 0, -1, -1, -1, -1]
    every = open_dataset(f"scannet:{tmp_path}?objects=annotated")[0]
    assert every.instance.tolist() == [-1, -1, 0, 0, 1, -1, -1, -1]
    assert np.array_equal(every.segment, bench.segment)
    with pytest.raises(ConfigError, match=r"objects='all'.*benchmark, annotated"):
        open_dataset(f"scannet:{tmp_path}?objects=all")


def test_scannet_label_map_option_and_errors(tmp_path):
    write_scannet_scene(tmp_path / "ds")
    with pytest.raises(DataError, match="labels="):
        open_dataset(f"scannet:{tmp_path / 'ds'}")[0]
    tsv = tmp_path / "elsewhere.tsv"
    tsv.write_text(TSV)
    s = open_dataset(f"scannet:{tmp_path / 'ds'}?labels={tsv}")[0]
    assert s.instance.max() == 1


def test_scannet_bad_files(tmp_path):
    d = write_scannet_scene(tmp_path, segs=SEG[:-1])
    (tmp_path / "scannetv2-labels.combined.tsv").write_text(TSV)
    with pytest.raises(DataError, match=r"segs\.json.*7 segment indices.*8 vertices"):
        open_dataset(f"scannet:{tmp_path}")[0]
    (d / "scene0000_00_vh_clean_2.0.010000.segs.json").write_text('{"segIndices": [1, 2,')
    with pytest.raises(DataError, match=r"segs\.json: bad JSON"):
        open_dataset(f"scannet:{tmp_path}")[0]
    (d / "scene0000_00.aggregation.json").unlink()
    (d / "scene0000_00_vh_clean_2.0.010000.segs.json").write_text(json.dumps({"segIndices": SEG}))
    with pytest.raises(DataError, match=r"aggregation\.json"):
        open_dataset(f"scannet:{tmp_path}")[0]


def test_scannetpp_reader_with_ignore_mask(tmp_path):
    scans = tmp_path / "data" / "0a5c013435" / "scans"
    scans.mkdir(parents=True)
    write_ply(scans / "mesh_aligned_0.05.ply", GRID, RGB, FACES)
    (scans / "segments.json").write_text(json.dumps({"segIndices": SEG}))
    (scans / "segments_anno.json").write_text(json.dumps({"segGroups": [
        {"id": 1, "objectId": 1, "segments": [5], "label": "wall", "obb": {}},
        {"id": 2, "objectId": 2, "segments": [17], "label": "office chair", "obb": {}},
        {"id": 3, "objectId": 3, "segments": [9], "label": "REMOVE", "obb": {}},
        {"id": 4, "objectId": 4, "segments": [42], "label": "Ceiling", "obb": {}},
    ]}))
    (scans / "mesh_aligned_0.05_mask.txt").write_text("3\n6\n")
    ds = open_dataset(f"scannetpp:{tmp_path}")
    assert ds.scene_ids == ["0a5c013435"]
    s = ds.load("0a5c013435")
    assert s.instance.tolist() == [-1, -1, 0, 0, -1, -1, -1, -1]
    assert s.segment.tolist() == [0, 0, 1, 1, -1, -1, -1, 0]
    assert np.flatnonzero(~s.valid).tolist() == [3, 6]
    (scans / "mesh_aligned_0.05_mask.txt").write_text("3\n99\n")
    with pytest.raises(DataError, match=r"mask\.txt.*out of range"):
        ds.load("0a5c013435")


def _s3dis_room(root: Path) -> Path:
    anno = root / "Stanford3dDataset_v1.2_Aligned_Version" / "Area_5" / "hallway_6" / "Annotations"
    anno.mkdir(parents=True)
    rng = np.random.default_rng(0)

    def write(name: str, n: int) -> None:
        rows = np.column_stack([rng.random((n, 3)) * 5, rng.integers(0, 256, (n, 3))])
        (anno / name).write_text("\n".join(f"{r[0]:.3f} {r[1]:.3f} {r[2]:.3f} {int(r[3])} {int(r[4])} {int(r[5])}" for r in rows) + "\n")

    for name, n in (("ceiling_1.txt", 6), ("chair_1.txt", 4), ("chair_2.txt", 3), ("wall_1.txt", 5),
                    ("door_1.txt", 2), ("stairs_1.txt", 2)):
        write(name, n)
    lines = (anno / "ceiling_1.txt").read_text().splitlines()
    lines[3] = lines[3].replace(" ", "\x10 ", 1)  # the release's stray character
    (anno / "ceiling_1.txt").write_text("\n".join(lines) + "\n")
    return anno


class _Collect(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


def test_s3dis_reader_tolerates_the_corrupt_line(tmp_path):
    _s3dis_room(tmp_path)
    ds = open_dataset(f"s3dis:{tmp_path}")
    assert ds.scene_ids == ["Area_5_hallway_6"]
    handler = _Collect()
    logger = logging.getLogger("assist3d.data.s3dis")
    logger.addHandler(handler)
    try:
        s = ds[0]
    finally:
        logger.removeHandler(handler)
    assert any("ceiling_1.txt" in m and "line 4" in m for m in handler.messages), handler.messages
    assert len(s) == 6 + 4 + 3 + 5 + 2 + 2
    # order: ceiling_1, chair_1, chair_2, door_1, stairs_1, wall_1 -> objects chair, chair, door, stairs
    assert s.instance.tolist() == [-1] * 6 + [0] * 4 + [1] * 3 + [2] * 2 + [3] * 2 + [-1] * 5
    assert s.segment[-5:].tolist() == [2] * 5 and s.segment[-7:-5].tolist() == [12, 12]  # stairs -> clutter


def test_s3dis_other_malformed_content_is_an_error(tmp_path):
    anno = _s3dis_room(tmp_path)
    (anno / "chair_1.txt").write_text("1 2 3 4 5\n")
    with pytest.raises(DataError, match=r"chair_1\.txt.*6 columns"):
        open_dataset(f"s3dis:{tmp_path}")[0]


def _pointcept_scene(d: Path, seg_name: str = "segment20", labels: type = np.int64) -> None:
    d.mkdir(parents=True)
    n = 6
    np.save(d / "coord.npy", np.arange(n * 3, dtype=np.float32).reshape(n, 3))
    np.save(d / "color.npy", np.full((n, 3), 7, np.uint8))
    np.save(d / "normal.npy", np.tile(np.array([0, 0, 1], np.float32), (n, 1)))
    np.save(d / f"{seg_name}.npy", np.array([0, 1, 4, 4, -1, 6], labels))
    np.save(d / "instance.npy", np.array([0, 1, 2, 2, 3, -1], labels))


def test_pointcept_split_folders_and_scannet_rule(tmp_path):
    _pointcept_scene(tmp_path / "train" / "scene0000_00")
    _pointcept_scene(tmp_path / "val" / "scene0011_00")
    ds = open_dataset(f"pointcept:{tmp_path}")
    assert ds.scene_ids == ["scene0000_00", "scene0011_00"]
    s = ds.load("scene0011_00")
    # wall (0), floor (1) and unlabelled (-1) instances are not objects
    assert s.instance.tolist() == [-1, -1, 2, 2, -1, -1]
    assert s.segment.dtype == np.int32 and s.segment.tolist() == [0, 1, 4, 4, -1, 6]
    assert s.normal[0].tolist() == [0, 0, 1]
    s2 = open_dataset(f"pointcept:{tmp_path / 'val'}?ignore=4")[0]
    assert s2.instance.tolist() == [0, 1, -1, -1, 3, -1]


def test_assist3d_format_keeps_every_instance(tmp_path):
    d = tmp_path / "out" / "scene_00000"
    _pointcept_scene(d, "segment", labels=np.int32)  # the writer's dtypes
    (d / "meta.json").write_text("{}")
    (d / "layout.json").write_text("{}")
    (tmp_path / "out" / "manifest.json").write_text("{}")
    _pointcept_scene(tmp_path / "out" / "scene_00001", "segment")  # unfinished: no meta.json
    ds = open_dataset(f"assist3d:{tmp_path / 'out'}")
    assert ds.scene_ids == ["scene_00000"]
    s = ds[0]
    assert s.scene_id == "scene_00000"
    assert s.instance.tolist() == [0, 1, 2, 2, 3, -1]


def test_assist3d_format_is_read_strictly(tmp_path):
    """Our own format has one reader, the writer's strict one: a wrong dtype or a missing array is an
    error naming the file (the lax pointcept: reader would have converted or defaulted it)."""
    d = tmp_path / "out" / "scene_00000"
    _pointcept_scene(d, "segment")  # int64 labels: not what the writer writes
    (d / "meta.json").write_text("{}")
    with pytest.raises(DataError, match=r"instance\.npy: expected int32"):
        open_dataset(f"assist3d:{tmp_path / 'out'}")[0]
    np.save(d / "instance.npy", np.array([0, 1, 2, 2, 3, -1], np.int32))
    np.save(d / "segment.npy", np.array([0, 1, 4, 4, -1, 6], np.int32))
    (d / "normal.npy").unlink()
    with pytest.raises(DataError, match=r"normal\.npy: missing"):
        open_dataset(f"assist3d:{tmp_path / 'out'}")[0]


def test_pointcept_shape_mismatch(tmp_path):
    d = tmp_path / "s"
    _pointcept_scene(d)
    np.save(d / "instance.npy", np.zeros(5, np.int64))
    with pytest.raises(DataError, match=r"instance\.npy.*\(6,\)"):
        open_dataset(f"pointcept:{d}")[0]


def test_array_reader(tmp_path):
    a = np.zeros((5, 8), np.float32)
    a[:, 6] = [0, 1, 2, 3, 20]
    a[:, 7] = [1, 2, 3, 4, 5]
    np.save(tmp_path / "scene0451_01.npy", a)
    ds = open_dataset(f"array:{tmp_path / 'scene0451_01.npy'}")
    s = ds[0]
    assert s.scene_id == "scene0451_01"
    assert s.instance.tolist() == [-1, -1, -1, 4, 5]
    assert s.segment.tolist() == [-1, 0, 1, 2, 19]
    # every annotated instance but walls and floors: a label-0 object (a lamp, say) counts too, an
    # unannotated point (instance 0) does not
    a[:, 7] = [1, 2, 3, 4, 0]
    a[4, 6] = 0
    np.save(tmp_path / "scene0451_01.npy", a)
    assert open_dataset(f"array:{tmp_path / 'scene0451_01.npy'}")[0].instance.tolist() == [-1, -1, -1, 4, -1]
    every = open_dataset(f"array:{tmp_path / 'scene0451_01.npy'}?objects=annotated")[0]
    assert every.instance.tolist() == [1, -1, -1, 4, -1]
    with pytest.raises(ConfigError, match="objects="):
        open_dataset(f"array:{tmp_path}?objects=everything")
    np.save(tmp_path / "bad.npy", np.zeros((5, 7), np.float32))
    with pytest.raises(DataError, match=r"bad\.npy.*\(N, 8\)"):
        open_dataset(f"array:{tmp_path}").load("bad")


def test_specs():
    with pytest.raises(ConfigError, match="did you mean 'scannet'"):
        parse_spec("scanet:/x")
    with pytest.raises(ConfigError, match="unknown option"):
        parse_spec("array:/x?labels=y")
    assert parse_spec("scannet:/a/b?labels=/c.tsv") == ("scannet", Path("/a/b"), {"labels": "/c.tsv"})
    with pytest.raises(DataError, match="not found"):
        open_dataset("s3dis:/nonexistent/s3dis")


def test_ply_big_endian(tmp_path):
    v = np.zeros(2, dtype=[("x", ">f4"), ("y", ">f4"), ("z", ">f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    v["x"], v["red"] = [1.5, 2.5], [10, 20]
    f = np.zeros(1, dtype=[("n", "u1"), ("i", ">i4", (3,))])
    f["n"], f["i"] = 3, [0, 1, 1]
    header = ("ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
              "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
              "element face 1\nproperty list uchar int vertex_indices\nend_header\n").encode()
    p = tmp_path / "b.ply"
    p.write_bytes(header + v.tobytes() + f.tobytes())
    mesh = read_ply(p, faces=True)
    assert mesh.xyz()[:, 0].tolist() == [1.5, 2.5] and mesh.rgb()[:, 0].tolist() == [10, 20]
    assert mesh.faces.tolist() == [[0, 1, 1]]


def test_s3dis_cache_returns_the_same_room_and_tracks_edits(tmp_path):
    anno = _s3dis_room(tmp_path)
    ds = open_dataset(f"s3dis:{tmp_path}?cache=1")
    first = ds[0]
    from assist3d.core.paths import cache_root

    assert len(list((cache_root() / "s3dis").glob("Area_5_hallway_6-*.npz"))) == 1
    again = ds[0]  # from the cache
    for name in ("coord", "color", "instance", "segment"):
        assert np.array_equal(getattr(first, name), getattr(again, name))
    (anno / "chair_3.txt").write_text("1 1 1 10 20 30\n")
    assert len(ds[0]) == len(first) + 1


def test_scannet_face_index_out_of_range_names_the_mesh(tmp_path):
    d = write_scannet_scene(tmp_path)
    (tmp_path / "scannetv2-labels.combined.tsv").write_text(TSV)
    write_ply(d / "scene0000_00_vh_clean_2.ply", GRID, RGB, np.array([[0, 1, 99]]))
    with pytest.raises(DataError, match=r"vh_clean_2\.ply.*out of range"):
        open_dataset(f"scannet:{tmp_path}")[0]


def test_scan_files_are_a_reader_too(tmp_path):
    """``scan:PATH`` reads the files `segment` takes (a .ply, an (N, 3|6|8) .npy, a folder of them) as a
    dataset: no ground truth unless the array carries it; non-finite points refused, naming the file."""
    g = np.random.default_rng(0)
    xyz = g.random((50, 3)).astype(np.float32)
    rgb = (g.random((50, 3)) * 255).astype(np.uint8)
    write_ply(tmp_path / "a.ply", xyz, rgb)
    np.save(tmp_path / "b.npy", np.concatenate([xyz, rgb.astype(np.float32)], 1))
    np.save(tmp_path / "c.npy", xyz)
    full = np.zeros((50, 8), np.float32)
    full[:, :3], full[:, 6], full[:, 7] = xyz, 5, 1 + (np.arange(50) >= 25)
    np.save(tmp_path / "d.npy", full)
    (tmp_path / "notes.txt").write_text("not a scan")
    ds = open_dataset(f"scan:{tmp_path}")
    assert ds.scene_ids == ["a", "b", "c", "d"]
    a, b, c, d = (ds.load(s) for s in ds.scene_ids)
    assert np.allclose(a.coord, xyz) and np.array_equal(a.color, rgb) and np.array_equal(b.color, rgb)
    assert (c.color == 0).all() and all((s.instance == -1).all() for s in (a, b, c))
    assert sorted(np.unique(d.instance)) == [1, 2]  # the (N, 8) array keeps its objects
    bad = xyz.copy()
    bad[3] = np.nan
    np.save(tmp_path / "nan.npy", bad)
    with pytest.raises(DataError, match=r"nan\.npy: 1 of 50 points have non-finite"):
        open_dataset(f"scan:{tmp_path / 'nan.npy'}").load("nan")
    (tmp_path / "empty").mkdir()
    with pytest.raises(DataError, match="no .ply or .npy scans"):
        open_dataset(f"scan:{tmp_path / 'empty'}")

"""``assist3d export scannet``: a generated dataset as ScanNet v2 scans (docs/ecosystem.md, "ScanNet
export"), read back by our ScanNet reader with the same objects; and predictions round-tripped
through the ScanNet benchmark's text format score the same against the exported scans as the .npz
predictions against the dataset itself."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from assist3d.data import open_dataset
from assist3d.data.ply import read_ply
from assist3d.bench.evaluation import save_predictions
from assist3d.cli import app
from assist3d.core.contracts import PointSample, Room, SceneLayout
from assist3d.core.errors import DataError
from assist3d.core.taxonomy.scannet import scannet200_classes
from assist3d.export import Manifest, write_scene
from assist3d.interop.scannet import scannet_name

CLASSES = ("chair", "air conditioner", "table")


def _grid(a: np.ndarray, b: np.ndarray, origin: np.ndarray, step: float = 0.04) -> np.ndarray:
    u, v = np.meshgrid(np.arange(0, 1, step), np.arange(0, 1, step))
    return origin + u.reshape(-1, 1) * a + v.reshape(-1, 1) * b


def _scene(seed: int) -> tuple[PointSample, SceneLayout]:
    """A floor, a wall, and three boxes' tops and fronts (instances 0-2, one per class)."""
    rng = np.random.default_rng(seed)
    pts, nrm, inst = [], [], []

    def add(p: np.ndarray, n, k: int) -> None:
        pts.append(p), nrm.append(np.tile(np.asarray(n, np.float32), (len(p), 1))), inst.append(np.full(len(p), k))

    add(_grid(np.array([3.0, 0, 0]), np.array([0, 3.0, 0]), np.zeros(3)), (0, 0, 1), -1)  # floor
    add(_grid(np.array([3.0, 0, 0]), np.array([0, 0, 2.5]), np.array([0, 3.0, 0])), (0, -1, 0), -1)  # wall
    for k in range(3):
        o = np.array([0.3 + k, 0.5 + 0.3 * seed, 0.0])
        add(_grid(np.array([0.5, 0, 0]), np.array([0, 0.5, 0]), o + [0, 0, 0.6], 0.02), (0, 0, 1), k)  # top
        add(_grid(np.array([0.5, 0, 0]), np.array([0, 0, 0.6]), o, 0.02), (0, -1, 0), k)  # front
    coord = np.concatenate(pts).astype(np.float32)
    instance = np.concatenate(inst).astype(np.int32)
    sample = PointSample(f"s{seed}", coord, rng.integers(0, 255, (len(coord), 3), dtype=np.uint8),
                         np.concatenate(nrm), instance, instance.copy(), np.ones(len(coord), bool))
    room = Room(((0.0, 0.0), (3.0, 0.0), (3.0, 3.0), (0.0, 3.0)), 2.5)
    return sample, SceneLayout(room, (), (), seed, 0.0, classes=CLASSES)


@pytest.fixture
def dataset(tmp_path):
    root = tmp_path / "data"
    m = Manifest(root, {}, 0, CLASSES, "test")
    for k in (0, 1):
        sample, layout = _scene(k)
        meta = write_scene(root / f"scene_{k:06d}", sample, layout, {"id": f"scene_{k:06d}", "index": k, "seed": k})
        m.add(meta)
    m.write()
    return root


def test_scene_names_parse_as_scannet_names():
    assert scannet_name(7) == "scene0007_00" and scannet_name(10007) == "scene0007_01"
    with pytest.raises(DataError, match="scene index 1000000"):
        scannet_name(1_000_000)


def test_export_writes_scannet_scans_our_reader_reads_with_the_same_objects(dataset, tmp_path):
    out = tmp_path / "sn"
    res = CliRunner().invoke(app, ["export", "scannet", str(dataset), str(out), "--json"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert summary["scenes"] == 2 and summary["splits"] == {"train": 1, "val": 1, "test": 0}
    scan = out / "scans" / "scene0001_00"
    for suffix in ("_vh_clean_2.ply", "_vh_clean_2.labels.ply", "_vh_clean_2.0.010000.segs.json",
                   ".aggregation.json", ".txt"):
        assert (scan / f"scene0001_00{suffix}").is_file(), suffix
    assert (out / "Tasks" / "Benchmark" / "scannetv2_val.txt").read_text() == "scene0000_00\n"
    assert (out / "Tasks" / "Benchmark" / "scannetv2_train.txt").read_text() == "scene0001_00\n"
    assert (scan / "scene0001_00.txt").read_text().splitlines()[-1].startswith("sceneType = ")  # Mask3D reads it

    sample, _ = _scene(1)
    mesh = read_ply(scan / "scene0001_00_vh_clean_2.ply", faces=True)
    assert np.array_equal(mesh.xyz(), sample.coord) and np.array_equal(mesh.rgb(), sample.color)
    assert mesh.vertex.dtype.names[:7] == ("x", "y", "z", "red", "green", "blue", "alpha")  # ScanNet's order
    assert mesh.faces.shape == (len(sample), 3)
    # every face turns towards its point's normal (the preprocessing scripts derive normals from faces)
    p = mesh.xyz().astype(np.float64)
    fn = np.cross(p[mesh.faces[:, 1]] - p[mesh.faces[:, 0]], p[mesh.faces[:, 2]] - p[mesh.faces[:, 0]])
    assert np.all(np.einsum("ij,ij->i", fn, sample.normal) >= 0)

    seg = np.asarray(json.loads((scan / "scene0001_00_vh_clean_2.0.010000.segs.json").read_text())["segIndices"])
    agg = json.loads((scan / "scene0001_00.aggregation.json").read_text())
    assert len(seg) == len(sample) and len(np.unique(seg)) > 3  # more than one segment per object
    labels = [g["label"] for g in agg["segGroups"]]
    assert labels == ["chair", "object", "table", "wall", "floor"]
    for g, k in zip(agg["segGroups"][:3], range(3)):  # each object is exactly the union of its segments
        assert np.array_equal(np.isin(seg, g["segments"]), sample.instance == k)
    label_ply = read_ply(scan / "scene0001_00_vh_clean_2.labels.ply", faces=True)
    assert np.array_equal(label_ply.xyz(), sample.coord)
    nyu = np.asarray(label_ply.vertex["label"])
    assert nyu[sample.instance == 0][0] == 5 and nyu[sample.instance == 1][0] == 39  # chair; other -> otherfurniture
    assert set(np.unique(nyu[sample.instance < 0]).tolist()) == {1, 2}  # wall, floor

    with open(out / "scannetv2-labels.combined.tsv", newline="") as f:
        rows = {r["raw_category"]: r for r in csv.DictReader(f, delimiter="\t")}
    ids = {c.name: c.id for c in scannet200_classes()}
    assert set(rows) == {"chair", "object", "table", "wall", "floor"}
    assert all(int(r["id"]) == ids[name] for name, r in rows.items())  # ScanNet's own label ids
    assert {name: int(r["nyu40id"]) for name, r in rows.items()} == {"chair": 5, "object": 39, "table": 7,
                                                                      "wall": 1, "floor": 2}

    ours, theirs = open_dataset(f"assist3d:{dataset}"), open_dataset(f"scannet:{out}")
    assert theirs.scene_ids == ["scene0000_00", "scene0001_00"]
    for a, b in zip(ours.scene_ids, theirs.scene_ids):
        x, y = ours.load(a), theirs.load(b)
        assert np.array_equal(x.coord, y.coord)
        pairs = np.unique(np.stack([x.instance, y.instance], 1), axis=0)
        assert len(pairs) == len(np.unique(x.instance)) == len(np.unique(y.instance))  # the same partition
        assert np.array_equal(x.instance < 0, y.instance < 0)


def test_export_refuses_a_folder_that_is_not_a_dataset(tmp_path):
    res = CliRunner().invoke(app, ["export", "scannet", str(tmp_path), str(tmp_path / "out")])
    # a DataError: the command line's entry point prints it as one line naming the folder
    assert isinstance(res.exception, DataError) and str(tmp_path) in str(res.exception)
    assert "no manifest.json" in str(res.exception)


def test_predictions_through_the_benchmark_text_format_score_the_same_on_the_exported_scans(dataset, tmp_path):
    """Our predictions as .npz against the dataset, and the same predictions converted by
    ``convert-predictions --to txt`` (label 39) against its ScanNet export: identical figures."""
    runner = CliRunner()
    out = tmp_path / "sn"
    assert runner.invoke(app, ["export", "scannet", str(dataset), str(out)]).exit_code == 0
    ours = open_dataset(f"assist3d:{dataset}")
    rng = np.random.default_rng(0)
    for k, sid in enumerate(ours.scene_ids):
        inst = ours.load(sid).instance
        masks = np.stack([inst == i for i in range(3)] + [rng.random(len(inst)) > 0.7])
        masks[1] &= rng.random(len(inst)) > 0.4  # a poor mask: IoU about 0.6
        scores = np.array([0.9, 0.8, 0.3, 0.7], np.float32)
        save_predictions(tmp_path / "npz" / f"{sid}.npz", masks, scores)
        save_predictions(tmp_path / "npz_sn" / f"{scannet_name(k)}.npz", masks, scores)
    res = runner.invoke(app, ["convert-predictions", str(tmp_path / "npz_sn"), str(tmp_path / "txt"), "--to", "txt"])
    assert res.exit_code == 0, res.output
    first = (tmp_path / "txt" / "scene0000_00.txt").read_text().splitlines()[0].split()
    assert first[1] == "39"
    a = runner.invoke(app, ["evaluate", "--gt", f"assist3d:{dataset}", "--pred", str(tmp_path / "npz"), "--json"])
    b = runner.invoke(app, ["evaluate", "--gt", f"scannet:{out}", "--pred", str(tmp_path / "txt"), "--json"])
    assert a.exit_code == 0 and b.exit_code == 0, a.output + b.output
    ra, rb = json.loads(a.stdout), json.loads(b.stdout)
    keys = ("AP", "AP50", "AP25", "AR", "AR50", "AR25")
    assert 0.3 < ra["AP"] < 1.0 and {k: rb[k] for k in keys} == {k: ra[k] for k in keys}


def test_s3dis_export_is_read_back_with_the_same_objects(dataset, tmp_path):
    out = tmp_path / "s3"
    res = CliRunner().invoke(app, ["export", "s3dis", str(dataset), str(out), "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["areas"] == {"Area_1": 1, "Area_5": 1}  # scene 1 trains, scene 0 validates
    anno = out / "Area_1" / "scene_000001" / "Annotations"
    assert sorted(p.name for p in anno.iterdir()) == ["chair_1.txt", "clutter_1.txt", "floor_1.txt", "table_1.txt",
                                                       "wall_1.txt"]
    assert (out / "Area_1" / "Area_1_alignmentAngle.txt").read_text().splitlines()[1:] == ["scene_000001 0"]
    theirs = open_dataset(f"s3dis:{out / 'Area_1'}").load("Area_1_scene_000001")
    ours = open_dataset(f"assist3d:{dataset}").load("scene_000001")

    def order(c: np.ndarray) -> np.ndarray:
        r = np.round(c.astype(np.float64), 3)
        return np.lexsort((r[:, 2], r[:, 1], r[:, 0]))

    a, b = order(theirs.coord), order(ours.coord)
    assert len(a) == len(b) and np.abs(theirs.coord[a] - ours.coord[b]).max() < 1e-4
    assert np.array_equal(theirs.color[a], ours.color[b])
    pairs = np.unique(np.stack([theirs.instance[a], ours.instance[b]], 1), axis=0)
    assert len(pairs) == len(np.unique(ours.instance)) == len(np.unique(theirs.instance))


@pytest.mark.slow  # starts two worker processes (about 5 s)
def test_export_with_worker_processes_writes_the_same_bytes(dataset, tmp_path):
    from assist3d.interop.scannet import export_scannet

    export_scannet(dataset, tmp_path / "one")
    export_scannet(dataset, tmp_path / "two", workers=2)
    files = sorted(p.relative_to(tmp_path / "one") for p in (tmp_path / "one").rglob("*") if p.is_file())
    assert len(files) == 2 * 5 + 5  # five files per scan; label map, three split lists, export.json
    for rel in files:
        assert (tmp_path / "one" / rel).read_bytes() == (tmp_path / "two" / rel).read_bytes(), rel

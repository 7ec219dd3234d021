"""Our side of the contract with Pointcept (docs/ecosystem.md, "Pointcept"): the files a scene folder
holds, their dtypes and label ranges, the split lists Pointcept's ``DefaultDataset`` reads, the
ScanNet-20 / ScanNet200 class of every class and of the room's surfaces, and the class-agnostic
folding the shipped configuration trains on."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from assist3d.core.contracts import PointSample, Room, SceneLayout
from assist3d.core.taxonomy.scannet import (SCANNET20_NAMES, SCANNET20_NYU40, scannet200_classes, scannet_label,
                                            surface_label)
from assist3d.export import Manifest, write_scene
from assist3d.export.manifest import split_of
from assist3d.interop.pointcept import AGNOSTIC_CLASSES, agnostic_segment

CLASSES = ("chair", "sofa", "nightstand", "air conditioner", "bookcase")
HEIGHT = 2.5


def _scene() -> tuple[PointSample, SceneLayout]:
    """Wall, floor and ceiling points (instance -1) and one object of each class."""
    rng = np.random.default_rng(0)
    parts = []  # (coord, normal, instance, segment)
    up, down, side = (0, 0, 1), (0, 0, -1), (1, 0, 0)
    parts.append(([0.5, 0.5, 0.0], up, -1, -1))  # floor
    parts.append(([0.0, 1.0, 1.2], side, -1, -1))  # wall
    parts.append(([1.0, 1.0, HEIGHT], down, -1, -1))  # ceiling
    for k in range(len(CLASSES)):
        parts.append(([1.0 + k * 0.2, 1.0, 0.4], up, k, k))  # an object's top: normal up, not floor
    n_each = 20
    coord = np.concatenate([np.asarray(c, np.float32) + rng.normal(0, 0.01, (n_each, 3)).astype(np.float32) * [1, 1, 0]
                            for c, *_ in parts]).astype(np.float32)
    normal = np.repeat(np.asarray([p[1] for p in parts], np.float32), n_each, axis=0)
    instance = np.repeat(np.asarray([p[2] for p in parts], np.int32), n_each)
    segment = np.repeat(np.asarray([p[3] for p in parts], np.int32), n_each)
    color = rng.integers(0, 255, (len(coord), 3), dtype=np.uint8)
    sample = PointSample("s", coord, color, normal, instance, segment, np.ones(len(coord), bool))
    room = Room(((0.0, 0.0), (3.0, 0.0), (3.0, 3.0), (0.0, 3.0)), HEIGHT, ceiling=True)
    return sample, SceneLayout(room, (), (), 0, 0.0, classes=CLASSES)


def test_scene_folder_holds_what_pointcepts_scannet_datasets_read(tmp_path):
    sample, layout = _scene()
    write_scene(tmp_path / "scene_000000", sample, layout, {"id": "scene_000000", "index": 0, "seed": 0})
    d = tmp_path / "scene_000000"
    # ScanNetDataset reads coord, color, normal, segment20, instance; ScanNet200Dataset segment200
    for name, dtype, shape in (("coord", np.float32, (3,)), ("color", np.uint8, (3,)), ("normal", np.float32, (3,)),
                               ("instance", np.int32, ()), ("segment20", np.int32, ()), ("segment200", np.int32, ())):
        a = np.load(d / f"{name}.npy")
        assert a.dtype == dtype and a.shape == (len(sample),) + shape, name
    s20, s200 = np.load(d / "segment20.npy"), np.load(d / "segment200.npy")
    assert s20.min() >= -1 and s20.max() < 20 and s200.min() >= 0 and s200.max() < 200
    per_part = lambda a: a.reshape(-1, 20)[:, 0].tolist()  # noqa: E731 (one value per block of 20 points)
    names200 = [c.name for c in scannet200_classes()]
    # floor, wall, ceiling (no ScanNet-20 class: -1 as in ScanNet), chair, sofa, nightstand (NYU40
    # "night stand" is not one of the 20: otherfurniture), air conditioner (no match: other), bookcase
    assert [SCANNET20_NAMES[i] if i >= 0 else None for i in per_part(s20)] == [
        "floor", "wall", None, "chair", "sofa", "otherfurniture", "otherfurniture", "bookshelf"]
    assert [names200[i] for i in per_part(s200)] == [
        "floor", "wall", "ceiling", "chair", "couch", "nightstand", "object", "bookshelf"]
    # every object point is a thing for a ScanNet configuration (segment_ignore_index (-1, 0, 1) / (-1, 0, 2))
    obj = sample.instance >= 0
    assert s20[obj].min() >= 2 and not np.isin(s200[obj], [0, 2]).any()
    # the arrays of the scene itself are untouched
    assert np.array_equal(np.load(d / "segment.npy"), sample.segment)


def test_split_lists_name_scene_folders_by_a_fixed_rule(tmp_path):
    m = Manifest(tmp_path, {}, 0, ("chair",), "proc")
    for k in (0, 1, 2, 3, 4, 5, 11):
        (tmp_path / f"scene_{k:06d}").mkdir()
        m.add({"id": f"scene_{k:06d}", "index": k, "seed": k})
    m.write()
    train = json.loads((tmp_path / "train.json").read_text())
    val = json.loads((tmp_path / "val.json").read_text())
    assert val == ["scene_000000", "scene_000005"]
    assert train == ["scene_000001", "scene_000002", "scene_000003", "scene_000004", "scene_000011"]
    # what Pointcept's DefaultDataset does with a split that names a file: join each entry to data_root
    for name in train + val:
        assert os.path.isdir(os.path.join(tmp_path, name))
    assert [split_of(k) for k in range(6)] == ["val", "train", "train", "train", "train", "val"]


def test_every_builtin_class_has_scannet_ids_in_range():
    table = scannet200_classes()
    assert len(table) == 200 and [c.index for c in table] == list(range(200))
    assert len({c.id for c in table}) == 200 and table[0].name == "wall" and table[2].name == "floor"
    from assist3d.core.taxonomy.classes import builtin_class_list

    for name in builtin_class_list("scannet200").classes + ("air conditioner", "superquadric", ""):
        lab = scannet_label(name)
        assert 2 <= lab.index20 < 20 and lab.nyu40id == SCANNET20_NYU40[lab.index20]
        assert lab.scannet200.name not in ("wall", "floor", "ceiling")
    assert scannet_label("superquadric").scannet200.name == "object" and not scannet_label("superquadric").matched
    assert [surface_label(c).index20 for c in range(3)] == [0, 1, -1]
    assert [surface_label(c).nyu40id for c in range(3)] == [1, 2, 22]


def test_class_agnostic_folding():
    assert AGNOSTIC_CLASSES == ("wall", "floor", "object")
    out = agnostic_segment(np.array([-1, 0, 1, 2, 5, 19], np.int64))
    assert out.dtype == np.int32 and out.tolist() == [-1, 0, 1, 2, 2, 2]


def test_pointcept_config_matches_the_dataset_contract():
    """The shipped config trains three classes with wall and floor ignored as instances, reads the
    split lists we write and loads our dataset class."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "configs" / "pointcept" / "insseg-pointgroup-spunet-assist3d-agnostic.py"
    ns: dict = {}
    exec(compile(path.read_text(encoding="utf-8"), str(path), "exec"), ns)  # a plain Python file: Pointcept's format
    assert ns["custom_imports"]["imports"] == ["assist3d.interop.pointcept"]
    assert tuple(ns["class_names"]) == AGNOSTIC_CLASSES and ns["num_classes"] == 3
    assert ns["segment_ignore_index"] == (-1, 0, 1)
    assert ns["data"]["train"]["split"] == "train.json" and ns["data"]["val"]["split"] == "val.json"
    assert {ns["data"][k]["type"] for k in ("train", "val", "test")} == {"Assist3DAgnosticDataset"}
    assert ns["model"]["semantic_num_classes"] == 3


def test_pointcept_module_imports_without_pointcept():
    import importlib.util

    if importlib.util.find_spec("pointcept") is not None:
        pytest.skip("Pointcept is installed here: the module registers its dataset class instead")
    import assist3d.interop.pointcept as mod

    assert mod.DATASETS is None and not hasattr(mod, "Assist3DAgnosticDataset")


def test_the_documented_class_table_is_what_the_code_writes():
    """docs/ecosystem.md's table of the built-in classes names the ScanNet200 and ScanNet-20 class
    (and index) that :func:`scannet_label` gives each."""
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[2] / "docs" / "ecosystem.md").read_text(encoding="utf-8")
    section = doc.split("### ScanNet classes of the built-in classes", 1)[1].split("\n## ", 1)[0]
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in section.splitlines()
            if line.startswith("| ") and not line.startswith("| class") and not line.startswith("| ---")]
    seen = set()
    for name, s200, s20 in rows:
        if name.startswith("*room: "):
            lab = surface_label(("wall", "floor", "ceiling").index(name[7:-1]))
        else:
            lab = scannet_label(name)
            seen.add(name)
        assert s200 == f"{lab.scannet200.name} ({lab.scannet200.index})" + ("" if lab.matched else ", no match"), name
        assert s20 == (f"{lab.name20} ({lab.index20})" if lab.index20 >= 0 else "none (-1)"), name
    assert len(seen) >= 150 and {"door", "window", "chair", "air conditioner"} <= seen

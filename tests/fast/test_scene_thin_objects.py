"""Thin and flat objects on one support never interpenetrate (issue 14: a loaf through a banknote)."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.assets.catalog import Catalog
from assist3d.config import GenerateConfig
from assist3d.core.contracts import AssetRecord, MeshData, SupportSurface
from assist3d.core.geometry import z_overlap
from assist3d.scene.checks import check_layout, check_siblings
from assist3d.scene.layout import build_layout

trimesh = pytest.importorskip("trimesh")

# (class, size in metres); the banknote and the paper are thinner than the 1 mm height tolerance
FLAT = [("bread", (0.216, 0.147, 0.076)), ("banknote", (0.133, 0.072, 0.0008)), ("paper", (0.21, 0.297, 0.0002)),
        ("plate", (0.25, 0.25, 0.02)), ("coaster", (0.1, 0.1, 0.004)), ("book", (0.15, 0.22, 0.03))]


def _box(size):
    m = trimesh.creation.box(extents=size)
    m.apply_translation((0, 0, size[2] / 2))
    return MeshData(np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.int32),
                    np.full((len(m.faces), 3), 180, np.uint8))


def _catalog(root) -> Catalog:
    cat = Catalog(root)
    top = (0.9, 0.6, 0.75)  # a small table: crowded on purpose
    hw, hd = top[0] * 0.48, top[1] * 0.48
    cat.add(AssetRecord(id="toy:table", source="toy", name="table", class_name="table", groups=("floor",), size=top,
                        supports=(SupportSurface(top[2], ((-hw, -hd), (hw, -hd), (hw, hd), (-hw, hd))),)), _box(top))
    for cls, size in FLAT:
        cat.add(AssetRecord(id=f"toy:{cls}", source="toy", name=cls, class_name=cls, groups=("obj",), size=size),
                _box(size))
    cat.save()
    return cat


def test_height_test_catches_a_banknote_under_a_loaf():
    boxes = {"z0": np.array([0.75]), "z1": np.array([0.7508])}  # a 0.8 mm banknote on a table
    assert z_overlap(np.array([0.75]), np.array([0.826]), boxes).all()  # a loaf on the same table
    assert not z_overlap(np.array([0.7508]), np.array([0.8]), boxes).any()  # resting on top of it is fine


@pytest.mark.slow
def test_flat_objects_on_one_support_do_not_interpenetrate(tmp_path):
    cat = _catalog(tmp_path / "cat")
    cfg = GenerateConfig.model_validate({"selection": {"floor_count": 3, "wall_count": 0, "on_top_count": 6,
                                                       "complementary_fraction": 0.0},
                                         "layout": {"group_budget_s": 60.0, "max_on_top_per_support": 8}})
    on_top = thin = 0
    for seed in range(6):
        lay = build_layout(cat, cfg, seed)
        on_top += sum(i.group == "obj" for i in lay.instances)
        thin += sum(i.asset in ("toy:banknote", "toy:paper") for i in lay.instances)
        assert check_siblings(lay, cat) == [], seed  # boxes: sees a 1 mm banknote inside a loaf
        assert [p for p in check_layout(lay, cat) if "interpenetrat" in p or "inside" in p] == [], seed
    assert on_top >= 60 and thin >= 10  # the supports were really crowded, with thin objects among the rest

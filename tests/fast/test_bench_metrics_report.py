"""Dataset summaries: a generated-format dataset finds the catalog its manifest names, scores its
layouts, and fills every metric of the JSON contract."""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest
import trimesh

from assist3d.assets.catalog import Catalog
from assist3d.core.contracts import AssetRecord, MeshData, PlacedInstance, Room, SceneLayout
from assist3d.bench.metrics.plausibility import score_layout
from assist3d.bench.metrics.diversity import geometry_diversity
from assist3d.bench.metrics.features import FEATURE_DIM
from assist3d.bench.metrics.report import DatasetSummary, metrics_table, shared_codebook, summarize_dataset


def _pose(x, y, z=0.0):
    p = np.eye(4)
    p[:3, 3] = (x, y, z)
    return p


def _box_and_tall(seed=0):
    """A one-room layout: a box and a tall box on the floor."""
    room = Room(((0, 0), (4, 0), (4, 3), (0, 3)), 2.6, ())
    return SceneLayout(room, (PlacedInstance(1, "box", "box", "floor", _pose(1, 1)),
                              PlacedInstance(2, "tall", "tall", "floor", _pose(3, 2))), (), seed=seed, seconds=0.0)


def _write_dataset(root, catalog_dir, layouts):
    cat = Catalog.open_or_create(catalog_dir)
    for aid, size in (("box", (0.6, 0.4, 0.8)), ("tall", (0.3, 0.3, 1.6))):
        m = trimesh.creation.box(size)
        m.apply_translation((0, 0, size[2] / 2))
        cat.add(AssetRecord(id=aid, source="test", name=aid, class_name=aid, groups=("floor",), size=size),
                MeshData(m.vertices.astype(np.float32), m.faces.astype(np.int32),
                         np.full((len(m.faces), 3), 150, np.uint8)))
    cat.save()
    root.mkdir()
    rng = np.random.default_rng(0)
    for k, layout in enumerate(layouts):
        d = root / f"scene_{k:06d}"
        d.mkdir()
        coords, inst = [], []
        for i in layout.instances:
            size = cat.get(i.asset).size
            pts, _ = trimesh.sample.sample_surface(trimesh.creation.box(size), 400, seed=int(rng.integers(1 << 30)))
            coords.append(pts + i.pose[:3, 3] + (0, 0, size[2] / 2))
            inst.append(np.full(400, i.id))
        coord = np.concatenate(coords).astype(np.float32)
        np.save(d / "coord.npy", coord)
        np.save(d / "instance.npy", np.concatenate(inst).astype(np.int32))
        np.save(d / "segment.npy", np.zeros(len(coord), np.int32))
        np.save(d / "color.npy", np.full((len(coord), 3), 128, np.uint8))  # every array the writer writes
        np.save(d / "normal.npy", np.tile(np.array([0, 0, 1], np.float32), (len(coord), 1)))
        (d / "layout.json").write_text(json.dumps(layout.to_json()))
        (d / "meta.json").write_text("{}")
    # `assist3d generate` records the catalog folder under "assets"
    (root / "manifest.json").write_text(json.dumps({"format": "assist3d-dataset", "assets": str(catalog_dir)}))
    return cat


def test_generated_dataset_summary_uses_manifest_catalog(tmp_path):
    room = Room(((0, 0), (4, 0), (4, 3), (0, 3)), 2.6, ())
    layouts = [
        SceneLayout(room, (PlacedInstance(1, "box", "box", "floor", _pose(1, 1)),
                           PlacedInstance(2, "tall", "tall", "floor", _pose(3, 2))), (), seed=0, seconds=0.0),
        # the second scene floats its box: a lower layout score
        SceneLayout(room, (PlacedInstance(1, "box", "box", "floor", _pose(1, 1, 0.5)),), (), seed=1, seconds=0.0),
    ]
    cat = _write_dataset(tmp_path / "ds", tmp_path / "lib", layouts)
    s = summarize_dataset(str(tmp_path / "ds"))
    assert s.scenes == 2 and s.instances == 3 and s.features.shape[0] == 3
    assert s.scene_classes == [{"box", "tall"}, {"box"}]
    expected = [score_layout(lay, cat).score for lay in layouts]
    assert s.layout_scores == expected and expected[1] < expected[0]
    # keyed by the dataset as given (a bare folder); its FORMAT:PATH form is under "dataset"
    row = metrics_table([s], shared_codebook([s], seed=0))[str(tmp_path / "ds")]
    assert row["dataset"] == f"assist3d:{tmp_path / 'ds'}"
    assert set(row) >= {"geometry_diversity", "context_complexity", "layout_score", "scenes", "instances"}
    assert row["layout_score"] == round(float(np.mean(expected)), 2)
    # box: P(tall | box) = 1/2; tall: P(box | tall) = 1
    assert row["context_complexity"] == 0.75
    assert 0 <= row["geometry_diversity"] <= math.log(row["codes"]) + 1e-3


def test_metrics_cli_json_keys_are_the_datasets_as_given(tmp_path, monkeypatch):
    """`assist3d metrics DIR FORMAT:PATH --json`: one row per argument, keyed by the argument."""
    from typer.testing import CliRunner

    from assist3d.cli import app

    _write_dataset(tmp_path / "ds", tmp_path / "lib", [_box_and_tall()])
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(app, ["metrics", "ds", "assist3d:ds", "--json"])
    assert res.exit_code == 0, res.output
    table = json.loads(res.stdout.strip().splitlines()[-1])
    assert list(table) == ["ds", "assist3d:ds"]
    assert table["ds"]["dataset"] == table["assist3d:ds"]["dataset"] == "assist3d:ds"
    for row in table.values():
        assert {"geometry_diversity", "context_complexity", "layout_score", "scenes", "instances"} <= set(row)
        assert row["scenes"] == 1 and row["instances"] == 2
    assert table["ds"]["geometry_diversity"] == table["assist3d:ds"]["geometry_diversity"]
    for row in table.values():  # layout_realism: a number, or null with the reason
        assert "layout_realism" in row
        assert row["layout_realism"] is not None or row["notes"]["layout_realism"]
        # its standard error over scenes: null with the reason for a one-scene dataset
        assert row["layout_realism_se"] is None
        assert row["layout_realism"] is None or row["notes"]["layout_realism_se"] == "fewer than 2 scenes"
        # which way it differs from the real scans: objects a scene and each statistic's median, both sides
        prof = row["layout_realism_profile"]
        assert (prof is None) == (row["layout_realism"] is None)
        if prof is not None:
            assert set(prof) == {"objects_per_scene", *row["layout_realism_components"]}
            assert prof["objects_per_scene"]["reference"] > prof["objects_per_scene"]["dataset"] > 0


def test_realism_hint_names_the_farthest_statistics_with_their_medians():
    from assist3d.bench.metrics.report import realism_hint

    row = {"layout_realism_components": {"wall_distance": 0.1, "misalignment": 0.3, "height": 0.5, "neighbour": 0.2,
                                         "free_space": 0.1, "coverage": 0.66},
           "layout_realism_profile": {"objects_per_scene": {"dataset": 12.84, "reference": 32.8},
                                      "height": {"dataset": 0.12, "reference": 0.38},
                                      "coverage": {"dataset": 0.13, "reference": 0.49}}}
    hint = realism_hint(row)
    assert hint.index("coverage (KS 0.66; median 0.13 against 0.49)") < hint.index("height (KS 0.50; median 0.12 m")
    assert "misalignment" not in hint and hint.endswith("12.8 objects a scene against 32.8")
    row["layout_realism_profile"]["objects_per_scene"]["reference"] = None
    assert realism_hint(row).endswith("12.8 objects a scene")


def test_plot_labels_are_short_when_unambiguous():
    from assist3d.bench.metrics.report import short_labels

    assert short_labels(["/tmp/cmp/assist3d", "assist3d:/tmp/cmp/randomrooms"]) == ["assist3d", "randomrooms"]
    # two folders of the same name in different comparisons keep their full names
    assert short_labels(["/a/assist3d", "/b/assist3d"]) == ["/a/assist3d", "/b/assist3d"]
    assert short_labels(["array:/data/scene0451_01.npy"]) == ["scene0451_01.npy"]


def test_descriptors_do_not_depend_on_where_the_dataset_lies_or_what_else_is_read(tmp_path):
    """The same scenes give the same shape descriptors (so the same geometry diversity) in a copy
    of the dataset at another path, and a scene read alone gives what it gives among the others."""
    _write_dataset(tmp_path / "ds", tmp_path / "lib", [_box_and_tall(k) for k in range(2)])
    shutil.copytree(tmp_path / "ds", tmp_path / "moved" / "copy")
    shutil.copytree(tmp_path / "ds", tmp_path / "second_only")
    shutil.rmtree(tmp_path / "second_only" / "scene_000000")
    a, b, c = (summarize_dataset(str(tmp_path / d)) for d in ("ds", "moved/copy", "second_only"))
    assert a.features.shape == (4, a.features.shape[1])
    assert np.array_equal(a.features, b.features)
    assert np.array_equal(a.features[2:], c.features)
    # the descriptors are random draws: another seed gives other ones
    assert not np.array_equal(a.features, summarize_dataset(str(tmp_path / "ds"), seed=1).features)
    table = metrics_table([a, b], shared_codebook([a, b], seed=0))
    here, moved = table[str(tmp_path / "ds")], table[str(tmp_path / "moved/copy")]
    assert here["geometry_diversity"] == moved["geometry_diversity"]


def test_shared_codebook_does_not_depend_on_the_order_datasets_are_listed_in():
    """`assist3d metrics A B C` and `assist3d metrics C A B` code every dataset alike."""
    rng = np.random.default_rng(5)
    sets = [DatasetSummary(name, features=(rng.normal(size=(m, FEATURE_DIM)) * sd).astype(np.float32))
            for name, m, sd in (("a", 300, 1.0), ("b", 120, 0.5), ("c", 500, 2.0))]
    books = [shared_codebook(order, seed=0) for order in (sets, sets[::-1], [sets[2], sets[0], sets[1]])]
    for book in books[1:]:
        assert np.array_equal(book.centers, books[0].centers)
        for s in sets:
            assert geometry_diversity(s.features, book) == geometry_diversity(s.features, books[0])
    assert not np.array_equal(shared_codebook(sets, seed=1).centers, books[0].centers)  # seeded, not fixed


@pytest.mark.slow
def test_geometry_diversity_sd_is_the_spread_over_codebook_draws():
    """`geometry_diversity_sd`: the standard deviation of a dataset's value over draw 0 (the codebook
    the value is read with, unchanged) and the other draws, which differ and do not depend on the order."""
    from assist3d.bench.metrics.report import CODEBOOK_DRAWS, codebook_draws

    rng = np.random.default_rng(7)
    sets = [DatasetSummary(name, features=(rng.normal(size=(m, FEATURE_DIM)) * sd).astype(np.float32))
            for name, m, sd in (("a", 400, 1.0), ("b", 150, 0.5), ("c", 600, 2.0))]
    book = shared_codebook(sets, seed=3)
    assert np.array_equal(book.centers, shared_codebook(sets, seed=3, draw=0).centers)
    others = codebook_draws(sets, seed=3)
    assert len(others) == CODEBOOK_DRAWS - 1
    assert len({b.centers.tobytes() for b in [book, *others]}) == CODEBOOK_DRAWS  # every draw is another fit
    for b, r in zip(others, codebook_draws(sets[::-1], seed=3)):
        assert np.array_equal(b.centers, r.centers)
    table = metrics_table(sets, book, seed=3, other_codebooks=others)
    plain = metrics_table(sets, book, seed=3)
    for s in sets:
        values = [geometry_diversity(s.features, b) for b in [book, *others]]
        assert table[s.name]["geometry_diversity"] == plain[s.name]["geometry_diversity"] == round(values[0], 4)
        assert table[s.name]["geometry_diversity_sd"] == round(float(np.std(values, ddof=1)), 4) > 0
        assert plain[s.name]["geometry_diversity_sd"] is None and plain[s.name]["notes"]["geometry_diversity_sd"]
        # summaries made without per-scene counts cannot be resampled by scene: null with the reason
        assert table[s.name]["geometry_diversity_se"] is None
        assert table[s.name]["notes"]["geometry_diversity_se"] == "descriptors not attributed to scenes"


def test_geometry_diversity_se_resamples_a_datasets_scenes(tmp_path):
    """`geometry_diversity_se` of a read dataset: its scenes' codes under the value's codebook, resampled
    by scene with the `--seed` stream; null with the reason for one scene."""
    from assist3d.bench.metrics.diversity import geometry_diversity_se
    from assist3d.core.rng import make_rng

    _write_dataset(tmp_path / "ds", tmp_path / "lib", [_box_and_tall(k) for k in range(3)])
    s = summarize_dataset(str(tmp_path / "ds"))
    assert s.feature_counts == [2, 2, 2]
    book = shared_codebook([s], seed=0, k=4)
    row = metrics_table([s], book, seed=5)[str(tmp_path / "ds")]
    codes = book.assign(s.features)
    want, _ = geometry_diversity_se([codes[0:2], codes[2:4], codes[4:6]], len(book.centers),
                                    make_rng(5, "geometry_diversity_se"))
    assert row["geometry_diversity_se"] == round(want, 4) > 0
    one = summarize_dataset(str(tmp_path / "ds"), max_scenes=1)
    row1 = metrics_table([one], book)[str(tmp_path / "ds")]
    assert row1["geometry_diversity_se"] is None and row1["notes"]["geometry_diversity_se"] == "fewer than 2 scenes"


def test_metrics_cli_geometry_sd_null_with_a_given_codebook(tmp_path, monkeypatch):
    from typer.testing import CliRunner

    from assist3d.cli import app

    _write_dataset(tmp_path / "ds", tmp_path / "lib", [_box_and_tall()])
    monkeypatch.chdir(tmp_path)
    fitted = CliRunner().invoke(app, ["metrics", "ds", "--json", "--save-codebook", "book.npz"])
    assert fitted.exit_code == 0, fitted.output
    row = json.loads(fitted.stdout.strip().splitlines()[-1])["ds"]
    assert row["geometry_diversity_sd"] is not None
    given = CliRunner().invoke(app, ["metrics", "ds", "--json", "--codebook", "book.npz"])
    assert given.exit_code == 0, given.output
    row2 = json.loads(given.stdout.strip().splitlines()[-1])["ds"]
    assert row2["geometry_diversity"] == row["geometry_diversity"]
    assert row2["geometry_diversity_sd"] is None and "codebook" in row2["notes"]["geometry_diversity_sd"]

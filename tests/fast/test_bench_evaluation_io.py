"""Prediction files, the evaluate command, and out-of-domain recall."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from assist3d.cli import app
from assist3d.data import open_dataset
from assist3d.core.errors import DataError
from assist3d.bench.evaluation import (
    convert_predictions,
    evaluate_dataset,
    export_scannet_txt,
    import_scannet_txt,
    load_predictions,
    ood_mask,
    save_predictions,
)


def _array_scene(path, n_obj: int = 3, pts: int = 200, seed: int = 0) -> np.ndarray:
    """An (N, 8) array scene: n_obj chairs (label 5) of ``pts`` points, then 200 wall points."""
    rng = np.random.default_rng(seed)
    rows = []
    for k in range(n_obj):
        xyz = rng.random((pts, 3)) * 0.5 + [k * 2.0, 0, 0]
        rows.append(np.column_stack([xyz, np.full((pts, 3), 100.0), np.full(pts, 5.0), np.full(pts, k + 1.0)]))
    wall = np.column_stack([rng.random((200, 3)) * [8, 0.01, 3], np.full((200, 3), 50.0), np.ones(200), np.full(200, 99.0)])
    a = np.concatenate(rows + [wall]).astype(np.float32)
    np.save(path, a)
    return a


def _gt_masks(a: np.ndarray) -> np.ndarray:
    inst = a[:, 7]
    obj = (a[:, 6] >= 3)
    return np.stack([(inst == i) & obj for i in np.unique(inst[obj])])


def test_npz_round_trip_loads_with_plain_numpy(tmp_path):
    masks = np.random.default_rng(0).random((4, 300)) > 0.5
    scores = np.array([0.1, 0.9, 0.5, 0.5], np.float32)
    p = save_predictions(tmp_path / "s.npz", masks, scores)
    with np.load(p) as z:
        assert z["masks"].dtype == bool and z["masks"].shape == (4, 300)
        assert z["scores"].dtype == np.float32
    m2, s2 = load_predictions(p, 300)
    assert np.array_equal(m2, masks) and np.array_equal(s2, scores)
    with pytest.raises(DataError, match="s.npz.*301"):
        load_predictions(p, 301)


def test_benchmark_text_format_round_trip(tmp_path):
    masks = np.random.default_rng(1).random((3, 120)) > 0.3
    scores = np.array([0.25, 0.75, 0.5], np.float32)
    txt = export_scannet_txt(tmp_path, "scene0001_00", masks, scores)
    first = txt.read_text().splitlines()[0].split()
    assert first[0] == "pred_mask/scene0001_00_000.txt" and first[1] == "39"  # an object class the official script scores
    assert (tmp_path / first[0]).read_text().splitlines()[:3] == [str(int(v)) for v in masks[0, :3]]
    m2, s2 = import_scannet_txt(txt, 120)
    assert np.array_equal(m2, masks) and np.allclose(s2, scores)
    out = tmp_path / "npz"
    assert convert_predictions(tmp_path, out, to="npz") == 1
    m3, _ = load_predictions(out / "scene0001_00.npz")
    assert np.array_equal(m3, masks)
    with pytest.raises(DataError, match="scene0001_00_000.txt.*121"):
        import_scannet_txt(txt, 121)


def test_evaluate_command_json(tmp_path):
    (tmp_path / "gt").mkdir()
    a = _array_scene(tmp_path / "gt" / "sceneA.npy")
    pred = tmp_path / "pred"
    masks = _gt_masks(a)
    save_predictions(pred / "sceneA.npz", masks[:2], np.array([0.9, 0.8], np.float32))
    res = CliRunner().invoke(app, ["evaluate", "--gt", f"array:{tmp_path / 'gt'}", "--pred", str(pred), "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert set(["AP", "AP50", "AP25", "AR", "AR50", "AR25", "scenes"]) <= set(d)
    assert d["scenes"] == 1
    assert d["AR50"] == pytest.approx(2 / 3)
    assert d["AP"] == pytest.approx(2 / 3)  # precision 1 up to recall 2/3
    table = CliRunner().invoke(app, ["evaluate", "--gt", f"array:{tmp_path / 'gt'}", "--pred", str(pred), "--per-scene"])
    assert table.exit_code == 0 and "AP50" in table.stdout and "sceneA" in table.stdout


def test_missing_predictions_and_wrong_mask_length(tmp_path):
    gt = tmp_path / "gt"
    gt.mkdir()
    a = _array_scene(gt / "sceneA.npy")
    _array_scene(gt / "sceneB.npy", seed=1)
    pred = tmp_path / "pred"
    save_predictions(pred / "sceneA.npz", _gt_masks(a), np.ones(3, np.float32))
    ds = open_dataset(f"array:{gt}")
    with pytest.raises(DataError, match="sceneB"):
        evaluate_dataset(ds, pred)
    r = evaluate_dataset(ds, pred, allow_missing=True)
    assert r.missing == ("sceneB",)
    assert r.overall["AR50"] == pytest.approx(0.5)  # 3 of 6 objects found
    assert r.per_scene["sceneB"]["AP"] == 0.0
    save_predictions(pred / "sceneB.npz", np.zeros((1, 10), bool), np.ones(1, np.float32))
    with pytest.raises(DataError, match="sceneB.npz.*10 points"):
        evaluate_dataset(ds, pred)


def test_benchmark_txt_predictions_evaluate_like_npz(tmp_path):
    gt = tmp_path / "gt"
    gt.mkdir()
    a = _array_scene(gt / "sceneA.npy")
    masks = _gt_masks(a)
    export_scannet_txt(tmp_path / "txt", "sceneA", masks[:1], np.array([0.5], np.float32))
    r = evaluate_dataset(open_dataset(f"array:{gt}"), tmp_path / "txt")
    assert r.overall["AR"] == pytest.approx(1 / 3)


def test_ood_mask_selects_objects_beyond_every_reference_distance():
    ref = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 1.0], [1.0, -1.0]])  # mean (1, 0), d_max 1
    test = np.array([[1.0, 0.0], [2.0, 0.0], [2.1, 0.0], [1.0, -1.5]])
    assert ood_mask(ref, test).tolist() == [False, False, True, True]


def test_ood_recall_with_a_pluggable_feature(tmp_path):
    # Reference objects are 200-point blobs of size 0.5 m; in the test scene object 3 is a 4 m
    # long bar. With "extent along x" as the feature, only the bar is out-of-domain, and recall
    # on it is 1 when it is predicted and 0 when it is not.
    gt, ref = tmp_path / "gt", tmp_path / "ref"
    gt.mkdir(), ref.mkdir()
    _array_scene(ref / "r.npy", n_obj=4, seed=3)
    a = _array_scene(gt / "t.npy", n_obj=3, seed=4)
    bar = a[:, 7] == 3
    a[bar, 0] = np.linspace(4.0, 8.0, bar.sum())
    np.save(gt / "t.npy", a)
    masks = _gt_masks(a)

    def extent_x(points: np.ndarray) -> np.ndarray:
        return np.array([np.ptp(points[:, 0])], np.float32)

    pred = tmp_path / "pred"
    save_predictions(pred / "t.npz", masks, np.ones(3, np.float32))
    ds, rds = open_dataset(f"array:{gt}"), open_dataset(f"array:{ref}")
    r = evaluate_dataset(ds, pred, ood_reference=rds, feature=extent_x)
    assert r.ood is not None and r.ood.num_gt == 1
    assert r.ood["AR50"] == pytest.approx(1.0)
    save_predictions(pred / "t.npz", masks[:2], np.ones(2, np.float32))
    r2 = evaluate_dataset(ds, pred, ood_reference=rds, feature=extent_x)
    assert r2.ood["AR"] == 0.0 and r2.overall["AR50"] == pytest.approx(2 / 3)


def test_ood_default_feature_runs(tmp_path):
    gt = tmp_path / "gt"
    gt.mkdir()
    a = _array_scene(gt / "t.npy")
    pred = tmp_path / "pred"
    save_predictions(pred / "t.npz", _gt_masks(a), np.ones(3, np.float32))
    ds = open_dataset(f"array:{gt}")
    r = evaluate_dataset(ds, pred, ood_reference=ds)
    assert r.ood is not None and r.ood.num_gt == 0  # nothing is farther than itself


def test_workers_give_the_same_result(tmp_path):
    gt, pred = tmp_path / "gt", tmp_path / "pred"
    gt.mkdir()
    for k in range(3):
        a = _array_scene(gt / f"s{k}.npy", seed=k)
        masks = _gt_masks(a)
        save_predictions(pred / f"s{k}.npz", masks[: k + 1], np.linspace(0.9, 0.5, k + 1).astype(np.float32))
    ds = open_dataset(f"array:{gt}")
    one = evaluate_dataset(ds, pred).to_dict(per_scene=True)
    two = evaluate_dataset(ds, pred, workers=2).to_dict(per_scene=True)
    assert one == two and one["AR50"] == pytest.approx(6 / 9)


def test_predictions_round_trip_through_the_benchmark_text_format_and_score_the_same(tmp_path):
    """convert-predictions --to txt writes a label the ScanNet script scores (39 by default, --label-id N
    otherwise; 1 was 'wall', which that script drops); back to npz and through our evaluator the figures
    are those of the original predictions."""
    from typer.testing import CliRunner

    from assist3d.bench.evaluation.ap import match_scene, summarize
    from assist3d.bench.evaluation.predictions import SCANNET_INSTANCE_IDS
    from assist3d.cli import app

    rng = np.random.default_rng(4)
    gt = np.repeat(np.arange(-1, 5), 150)  # 5 objects of 150 points and 150 void points
    masks = np.stack([gt == k for k in range(5)] + [rng.random(900) > 0.8])
    masks[0, :30] = ~masks[0, :30]  # a slightly wrong object
    scores = np.array([0.9, 0.8, 0.7, 0.6, 0.5, 0.95], np.float32)
    save_predictions(tmp_path / "npz" / "s.npz", masks, scores)
    runner = CliRunner()
    res = runner.invoke(app, ["convert-predictions", str(tmp_path / "npz"), str(tmp_path / "txt"), "--to", "txt"])
    assert res.exit_code == 0, res.output
    labels = {line.split()[1] for line in (tmp_path / "txt" / "s.txt").read_text().splitlines()}
    assert labels == {"39"} and 39 in SCANNET_INSTANCE_IDS
    res = runner.invoke(app, ["convert-predictions", str(tmp_path / "txt"), str(tmp_path / "back"), "--to", "npz"])
    assert res.exit_code == 0, res.output
    m2, s2 = load_predictions(tmp_path / "back" / "s.npz", 900)
    before = summarize([match_scene(gt, masks, scores, scene_id="s")])
    after = summarize([match_scene(gt, m2, s2, scene_id="s")])
    assert before["AP50"] > 0.5 and {k: after[k] for k in ("AP", "AP50", "AP25")} == {k: before[k] for k in ("AP", "AP50", "AP25")}
    res = runner.invoke(app, ["convert-predictions", str(tmp_path / "npz"), str(tmp_path / "t5"), "--to", "txt",
                              "--label-id", "5"])
    assert res.exit_code == 0 and (tmp_path / "t5" / "s.txt").read_text().split()[1] == "5"

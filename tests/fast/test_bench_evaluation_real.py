"""Evaluation on the real ScanNet scan (skipped when ../shared is absent)."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.data import open_dataset
from assist3d.bench.evaluation import MIN_REGION_SIZE, evaluate_dataset, evaluate_scene, save_predictions


@pytest.fixture
def real(real_scan_path):
    sample = open_dataset(f"array:{real_scan_path}")[0]
    ids, counts = np.unique(sample.instance[sample.instance >= 0], return_counts=True)
    ids = ids[counts >= MIN_REGION_SIZE]
    masks = np.stack([sample.instance == i for i in ids])
    scores = np.linspace(0.99, 0.5, len(ids)).astype(np.float32)
    return sample, masks, scores


def test_ground_truth_as_prediction_scores_one(real):
    sample, masks, scores = real
    m = evaluate_scene(sample.instance, masks, scores)
    assert m.num_gt == len(masks) > 10
    for k in ("AP", "AP50", "AP25", "AR", "AR50", "AR25"):
        assert m[k] == pytest.approx(1.0, abs=1e-9)


def test_removing_half_the_objects_halves_recall(real):
    sample, masks, scores = real
    keep = np.arange(0, len(masks), 2)
    m = evaluate_scene(sample.instance, masks[keep], scores[keep])
    assert m["AR50"] == pytest.approx(len(keep) / len(masks))
    assert m["AR50"] == pytest.approx(0.5, abs=0.03)
    assert m["AP50"] == pytest.approx(m["AR50"])  # precision stays 1: AP equals the recall reached


def test_eroding_masks_lowers_ap_monotonically(real):
    sample, masks, scores = real
    rng = np.random.default_rng(1234)
    u = rng.random(len(sample))
    aps = []
    for frac in (0.0, 0.1, 0.2, 0.3, 0.4, 0.5):
        aps.append(evaluate_scene(sample.instance, masks & (u >= frac), scores)["AP"])
    assert aps[0] == pytest.approx(1.0)
    assert all(later < earlier for earlier, later in zip(aps, aps[1:])), aps
    assert aps[-1] < 0.2


def test_real_scan_through_the_dataset_runner(real, tmp_path, real_scan_path):
    sample, masks, scores = real
    save_predictions(tmp_path / f"{sample.scene_id}.npz", masks, scores)
    result = evaluate_dataset(open_dataset(f"array:{real_scan_path}"), tmp_path)
    assert result.overall["AP"] == pytest.approx(1.0)
    assert list(result.per_scene) == ["scannet_scene0451_01"]

"""Class-agnostic AP/AR against values computed by hand from the ScanNet benchmark's rules.

The toy scene: GT object A = points 0..199, B = 200..399, void 400..599, a too-small GT object
C = 600..649 (50 points), 650 points in all.
"""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.bench.evaluation import ALL_THRESHOLDS, THRESHOLDS, average_precision, evaluate_scene, match_scene, summarize

N = 650
A = np.arange(0, 200)
B = np.arange(200, 400)
VOID = np.arange(400, 600)
C = np.arange(600, 650)


def scene() -> np.ndarray:
    inst = np.full(N, -1, np.int32)
    inst[A] = 7
    inst[B] = 3
    inst[C] = 11
    return inst


def mask(*parts: np.ndarray) -> np.ndarray:
    m = np.zeros(N, bool)
    for p in parts:
        m[p] = True
    return m


def run(masks: list[np.ndarray], scores: list[float], **kw):
    return evaluate_scene(scene(), np.stack(masks), np.asarray(scores, np.float32), **kw)


def test_thresholds_are_the_benchmarks():
    assert len(THRESHOLDS) == 9
    assert THRESHOLDS[0] == 0.5 and THRESHOLDS[-1] == pytest.approx(0.9)
    assert ALL_THRESHOLDS[-1] == 0.25


def test_perfect_predictions_score_one():
    m = run([mask(A), mask(B)], [0.9, 0.8])
    for k in ("AP", "AP50", "AP25", "AR", "AR50", "AR25"):
        assert m[k] == pytest.approx(1.0)
    assert m.num_gt == 2  # C is too small to count


def test_one_missed_object():
    # precision [1, 1], recall [0.5, 0] -> widths [0.25, 0.25] -> AP 0.5
    m = run([mask(A)], [0.9])
    assert m["AP"] == pytest.approx(0.5)
    assert m["AR50"] == pytest.approx(0.5)
    assert m["AR"] == pytest.approx(0.5)


def test_duplicate_becomes_false_positive_three_prediction_curve():
    # A (0.9) TP, A minus 10 points (0.8, IoU 0.95) duplicate FP, B (0.7) TP.
    # Ascending: 0.7 T, 0.8 F, 0.9 T -> precision [2/3, 1/2, 1, 1], recall [1, 1/2, 1/2, 0],
    # widths [1/4, 1/4, 1/4, 1/4] -> AP = 19/24.
    m = run([mask(A), mask(A[10:]), mask(B)], [0.9, 0.8, 0.7])
    assert m["AP"] == pytest.approx(19 / 24)
    assert m["AP50"] == pytest.approx(19 / 24)
    assert m["AR"] == pytest.approx(1.0)


def test_duplicate_keeps_the_higher_score_as_true_positive_whatever_the_file_order():
    a = run([mask(A[10:]), mask(A), mask(B)], [0.8, 0.9, 0.7])
    assert a["AP"] == pytest.approx(19 / 24)


def test_prediction_on_void_is_ignored():
    m = run([mask(A), mask(B), mask(VOID)], [0.9, 0.8, 0.95])
    assert m["AP"] == pytest.approx(1.0)


def test_partly_void_prediction_ignored_only_above_the_fraction():
    # P = 60 void + 60 points of B (IoU with B 60/260 < 0.25): void fraction 0.5.
    # 0.25: 0.5 > 0.25 -> ignored -> AP25 = 1. 0.5 .. 0.9: 0.5 <= th -> FP with the top score.
    # Ascending: 0.8 T, 0.9 T, 0.95 F -> precision [2/3, 1/2, 0, 1], recall [1, 1/2, 0, 0],
    # widths [1/4, 1/2, 1/4, 0] -> AP = 1/6 + 1/4 = 5/12.
    m = run([mask(A), mask(B), mask(VOID[:60], B[:60])], [0.9, 0.8, 0.95])
    assert m["AP25"] == pytest.approx(1.0)
    assert m["AP50"] == pytest.approx(5 / 12)
    assert m["AP"] == pytest.approx(5 / 12)


def test_tiny_regions_are_ignored():
    # A perfect 50-point prediction of C is dropped (< 100 points); a 150-point prediction on
    # C + void is ignored at every threshold; a 99-point copy of A is dropped, so no duplicate.
    m = run([mask(A), mask(B), mask(C), mask(C, VOID[:100]), mask(A[:99])], [0.9, 0.8, 0.99, 0.97, 0.95])
    assert m["AP"] == pytest.approx(1.0)
    assert m["AP25"] == pytest.approx(1.0)
    assert m.num_gt == 2
    assert m.num_pred == 3


def test_iou_must_be_strictly_above_the_threshold():
    # P = 100 points of A: IoU exactly 0.5 -> no match at 0.5 (FP, A missed), a match at 0.25.
    # 0.5: ascending 0.8 T, 0.9 F, hard FN 1 -> precision [1/2, 0, 1], recall [1/2, 0, 0],
    # widths [1/4, 1/4, 0] -> AP50 = 1/8.
    m = run([mask(A[:100]), mask(B)], [0.9, 0.8])
    assert m["AP50"] == pytest.approx(1 / 8)
    assert m["AR50"] == pytest.approx(0.5)
    assert m["AP25"] == pytest.approx(1.0)
    assert m["AR25"] == pytest.approx(1.0)


def test_score_ties_form_one_point_of_the_curve():
    # All three at 0.8: one unique score -> precision [2/3, 1], recall [1, 0], widths [1/2, 1/2]
    # -> AP = 5/6 (a sequential treatment of the ties would give 19/24).
    m = run([mask(A), mask(A[10:]), mask(B)], [0.8, 0.8, 0.8])
    assert m["AP"] == pytest.approx(5 / 6)


def test_no_predictions_scores_zero_and_no_gt_is_nan():
    inst = scene()
    empty = np.zeros((0, N), bool)
    m = evaluate_scene(inst, empty, np.zeros(0, np.float32))
    assert m["AP"] == 0.0 and m["AR"] == 0.0
    m2 = evaluate_scene(np.full(N, -1, np.int32), np.stack([mask(A)]), np.ones(1, np.float32))
    assert np.isnan(m2["AP"]) and np.isnan(m2["AR"])


def test_dataset_level_pools_matches_before_the_curve():
    # Scene 1 perfect (0.9, 0.8). Scene 2: its only object A is hit by P = 100 points of A
    # (IoU 0.5): at 0.5..0.9 a FP at 0.95 and one hard FN.
    # Pooled, ascending 0.8 T, 0.9 T, 0.95 F, FN 1: precision [2/3, 1/2, 0, 1],
    # recall [2/3, 1/3, 0, 0], widths [1/6, 1/3, 1/6, 0] -> AP = 1/9 + 1/6 = 5/18
    # (the mean of the two scene APs would be 0.5).
    s1 = match_scene(scene(), np.stack([mask(A), mask(B)]), np.array([0.9, 0.8], np.float32), scene_id="s1")
    inst2 = np.full(N, -1, np.int32)
    inst2[A] = 0
    s2 = match_scene(inst2, np.stack([mask(A[:100])]), np.array([0.95], np.float32), scene_id="s2")
    pooled = summarize([s1, s2])
    assert summarize([s2])["AP"] == 0.0
    assert pooled["AP"] == pytest.approx(5 / 18)
    assert pooled["AR50"] == pytest.approx(2 / 3)
    assert pooled["AP25"] == pytest.approx(1.0)


def test_invalid_points_are_removed_from_gt_and_predictions():
    # P = A + 200 void points: IoU 0.5 and void fraction 0.5 -> a FP at 0.5. With the void
    # points marked invalid, P equals A.
    inst = scene()
    masks = np.stack([mask(A, VOID), mask(B)])
    scores = np.array([0.9, 0.8], np.float32)
    assert evaluate_scene(inst, masks, scores)["AP50"] < 1.0
    valid = np.ones(N, bool)
    valid[VOID] = False
    assert evaluate_scene(inst, masks, scores, valid=valid)["AP"] == pytest.approx(1.0)


def test_average_precision_direct():
    # y ascending 0.2 F, 0.5 T, 0.9 T with 1 hard FN:
    # 0.2: tp 2 fp 1 fn 1 -> p 2/3 r 2/3; 0.5: tp 2 fp 0 fn 1 -> p 1 r 2/3;
    # 0.9: tp 1 fp 0 fn 2 -> p 1 r 1/3; then (0, 1). padded [2/3, 2/3, 2/3, 1/3, 0, 0]
    # widths [0, 1/6, 1/3, 1/6] -> AP = 0 + 1/6 + 1/3 + 1/6 = 2/3.
    ap = average_precision(np.array([1.0, 0.0, 1.0]), np.array([0.9, 0.2, 0.5]), 1, True, True)
    assert ap == pytest.approx(2 / 3)


def test_bad_shapes_raise():
    from assist3d.core.errors import DataError

    with pytest.raises(DataError, match="points per mask"):
        evaluate_scene(scene(), np.zeros((1, N - 1), bool), np.ones(1, np.float32))
    with pytest.raises(DataError, match="scores"):
        evaluate_scene(scene(), np.zeros((2, N), bool), np.ones(1, np.float32))

"""Class-agnostic instance-segmentation AP and AR, computed the way the ScanNet benchmark does.

Rules (ScanNet ``evaluate_semantic_instance.py``, with one class "object"):

* IoU thresholds ``np.arange(0.5, 0.95, 0.05)`` (0.50 .. 0.90, nine values) plus 0.25.
  AP is the mean over the nine, AP50 and AP25 the single thresholds.
* Ground-truth objects are the points' ``instance >= 0`` ids; ``instance == -1`` is void.
  Points with ``valid == False`` are removed from ground truth and predictions alike.
* Regions below 100 points are dropped: small GT objects are never matched (and never missed);
  small predictions are discarded before anything else.
* Per threshold, GT objects are walked in id order and each one's overlapping predictions in
  descending score order (ties: file order); the first prediction not yet used whose IoU is
  *strictly* above the threshold is a true positive; any further one above the threshold for the
  same GT adds a false positive with the lower of the two scores (and is not marked used).
* A prediction above the threshold with no GT object at all is ignored when more than the
  threshold fraction of its points lies on void or on too-small GT objects, else a false positive.
  A prediction whose only match is a too-small GT object is ignored.
* Precision/recall at every unique score, the point (recall 0, precision 1) appended, and
  AP = sum_i p_i (r_{i-1} - r_{i+1}) / 2 (a convolution with [-0.5, 0, 0.5]); GT but no
  predictions -> 0; no GT -> NaN.
* Dataset-level AP pools every scene's matches before the curve (not a mean of scene APs).
* AR: the fraction of GT objects matched (as above, all predictions) at each threshold; AR is
  the mean over the nine thresholds, AR50 and AR25 the single ones.

The intersections between all GT objects and all predictions of a scene come from one sparse
product (one ``bincount`` over the masks' non-zero entries): one pass over the masks per scene.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from ...core.errors import DataError

log = logging.getLogger(__name__)

#: The nine AP thresholds of the benchmark, exactly as it builds them.
THRESHOLDS: np.ndarray = np.arange(0.5, 0.95, 0.05)
#: The nine thresholds followed by 0.25 (the order of every per-threshold array here).
ALL_THRESHOLDS: np.ndarray = np.append(THRESHOLDS, 0.25)
I50 = int(np.flatnonzero(np.isclose(ALL_THRESHOLDS, 0.5))[0])
I25 = len(ALL_THRESHOLDS) - 1
MIN_REGION_SIZE = 100
METRIC_KEYS: tuple[str, ...] = ("AP", "AP50", "AP25", "AR", "AR50", "AR25")


@dataclass(frozen=True)
class SceneMatches:
    """The matching of one scene's predictions to its GT objects at every threshold.

    gt_ids (G,) int32: ids of the GT objects that count (>= the minimum size), in matching order;
    gt_matched (T, G) bool: whether each was matched at each threshold of :data:`ALL_THRESHOLDS`;
    y_true / y_score: per threshold, 1/0 and score of every true and false positive;
    hard_fn (T,) int: unmatched GT objects; num_pred: predictions kept (>= the minimum size).
    """

    scene_id: str
    gt_ids: np.ndarray
    gt_matched: np.ndarray
    y_true: tuple[np.ndarray, ...]
    y_score: tuple[np.ndarray, ...]
    hard_fn: np.ndarray
    num_pred: int

    @property
    def num_gt(self) -> int:
        return len(self.gt_ids)


@dataclass(frozen=True)
class Metrics:
    """AP and recall per threshold (order of :data:`ALL_THRESHOLDS`) and the summary figures."""

    ap: np.ndarray
    recall: np.ndarray
    num_gt: int
    num_pred: int
    summary: dict[str, float] = field(init=False)

    def __post_init__(self) -> None:
        nine = slice(0, len(THRESHOLDS))
        with np.errstate(invalid="ignore"):
            s = {
                "AP": _mean(self.ap[nine]), "AP50": float(self.ap[I50]), "AP25": float(self.ap[I25]),
                "AR": _mean(self.recall[nine]), "AR50": float(self.recall[I50]), "AR25": float(self.recall[I25]),
            }
        object.__setattr__(self, "summary", s)

    def __getitem__(self, key: str) -> float:
        return self.summary[key]


def _mean(x: np.ndarray) -> float:
    return float("nan") if np.all(np.isnan(x)) else float(np.nanmean(x))


def _check_inputs(scene_id: str, n: int, masks: np.ndarray, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    masks = np.asarray(masks)
    scores = np.asarray(scores)
    if masks.ndim != 2:
        raise DataError(f"scene {scene_id}: masks must be a 2-d (M, N) array, got shape {masks.shape}")
    if masks.shape[1] != n:
        raise DataError(f"scene {scene_id}: masks have {masks.shape[1]} points per mask, the scene has {n}")
    if scores.shape != (masks.shape[0],):
        raise DataError(f"scene {scene_id}: {scores.shape} scores for {masks.shape[0]} masks")
    if not np.all(np.isfinite(scores)):
        raise DataError(f"scene {scene_id}: scores must be finite")
    return masks.astype(bool, copy=False), scores.astype(np.float64)


def match_scene(
    instance: np.ndarray,
    masks: np.ndarray,
    scores: np.ndarray,
    *,
    valid: np.ndarray | None = None,
    scene_id: str = "",
    min_region_size: int = MIN_REGION_SIZE,
) -> SceneMatches:
    """Match one scene's predictions to its GT objects at every threshold.

    instance (N,) int: GT object id per point, -1 = void; masks (M, N) bool; scores (M,) float;
    valid (N,) bool or None: points to keep (False = excluded from the evaluation).
    """
    instance = np.asarray(instance)
    n = len(instance)
    masks, scores = _check_inputs(scene_id, n, masks, scores)
    if valid is not None and not np.all(valid):
        valid = np.asarray(valid, bool)
        if valid.shape != (n,):
            raise DataError(f"scene {scene_id}: valid mask has shape {valid.shape}, expected ({n},)")
        instance = instance[valid]
        masks = masks[:, valid]

    # GT objects (every id, small ones included) and one column for void.
    is_obj = instance >= 0
    ids, inverse = np.unique(instance[is_obj], return_inverse=True)
    g_all = len(ids)
    gt_col = np.full(len(instance), g_all, np.int64)
    gt_col[is_obj] = inverse
    gt_size = np.bincount(gt_col, minlength=g_all + 1)[:g_all]
    big = gt_size >= min_region_size

    # Intersections of every prediction with every GT object and void: the sparse product
    # masks (M, N) x one-hot(gt_col) (N, G + 1), as one bincount over the masks' non-zeros.
    n_valid = masks.shape[1]
    flat = np.flatnonzero(masks)
    rows = flat // n_valid
    cols = flat - rows * n_valid
    inter_all = np.bincount(rows * (g_all + 1) + gt_col[cols], minlength=len(masks) * (g_all + 1))
    inter_all = inter_all.reshape(len(masks), g_all + 1)

    # Predictions: drop small ones, order by score (stable: ties keep file order).
    pred_size_all = inter_all.sum(axis=1)
    keep = np.flatnonzero(pred_size_all >= min_region_size)
    keep = keep[np.argsort(-scores[keep], kind="stable")]
    score_k = scores[keep]
    pred_size = pred_size_all[keep]
    inter = inter_all[keep]
    m = len(keep)
    inter_gt = inter[:, :g_all]
    ignore_pts = inter[:, g_all] + inter_gt[:, ~big].sum(axis=1)
    union = gt_size[None, :] + pred_size[:, None] - inter_gt
    iou = np.divide(inter_gt, union, out=np.zeros(inter_gt.shape), where=union > 0)

    big_cols = np.flatnonzero(big)
    nt = len(ALL_THRESHOLDS)
    gt_matched = np.zeros((nt, len(big_cols)), bool)
    hard_fn = np.zeros(nt, np.int64)
    y_true: list[np.ndarray] = []
    y_score: list[np.ndarray] = []
    for t, th in enumerate(ALL_THRESHOLDS):
        above = iou > th
        tp_score = np.full(len(big_cols), -np.inf)
        dup_scores: list[float] = []
        used = np.zeros(m, bool)
        g_idx, p_idx = np.nonzero(above[:, big_cols].T)  # sorted by GT, then by score order
        for gi, p in zip(g_idx.tolist(), p_idx.tolist()):
            if used[p]:
                continue
            if gt_matched[t, gi]:
                dup_scores.append(min(tp_score[gi], score_k[p]))
                tp_score[gi] = max(tp_score[gi], score_k[p])
            else:
                gt_matched[t, gi] = True
                tp_score[gi] = score_k[p]
                used[p] = True
        hard_fn[t] = int(np.count_nonzero(~gt_matched[t]))
        no_gt = ~above.any(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            fp = no_gt & (ignore_pts / np.maximum(pred_size, 1) <= th)
        y_true.append(np.concatenate([np.ones(int(gt_matched[t].sum())), np.zeros(len(dup_scores) + int(fp.sum()))]))
        y_score.append(np.concatenate([tp_score[gt_matched[t]], np.asarray(dup_scores, np.float64), score_k[fp]]))
    return SceneMatches(
        scene_id=scene_id,
        gt_ids=ids[big_cols].astype(np.int32),
        gt_matched=gt_matched,
        y_true=tuple(y_true),
        y_score=tuple(y_score),
        hard_fn=hard_fn,
        num_pred=m,
    )


def average_precision(y_true: np.ndarray, y_score: np.ndarray, hard_fn: int, has_gt: bool, has_pred: bool) -> float:
    """The benchmark's area under the precision-recall curve for pooled matches.

    y_true (K,) 1 for a true positive, 0 for a false positive; y_score (K,) their scores;
    hard_fn: GT objects never matched. GT but no prediction -> 0.0; no GT -> NaN.
    """
    if not has_gt:
        return float("nan")
    if not has_pred:
        return 0.0
    order = np.argsort(y_score, kind="stable")
    ys = np.asarray(y_score, np.float64)[order]
    cum = np.cumsum(np.asarray(y_true, np.float64)[order])
    _, first = np.unique(ys, return_index=True)
    num_examples = len(ys)
    num_true = cum[-1] if len(cum) else 0.0
    cum = np.append(cum, 0.0)  # cum[-1] = 0 serves the first unique score (index 0)
    before = cum[first - 1]
    tp = num_true - before
    fp = num_examples - first - tp
    fn = before + hard_fn
    precision = np.append(tp / (tp + fp), 1.0)
    recall = np.append(tp / (tp + fn), 0.0)
    padded = np.concatenate([recall[:1], recall, [0.0]])
    widths = np.convolve(padded, [-0.5, 0.0, 0.5], "valid")
    return float(np.dot(precision, widths))


def summarize(matches: Sequence[SceneMatches]) -> Metrics:
    """Dataset-level metrics: pool the matches of all scenes, then one PR curve per threshold."""
    nt = len(ALL_THRESHOLDS)
    num_gt = sum(s.num_gt for s in matches)
    num_pred = sum(s.num_pred for s in matches)
    ap = np.zeros(nt)
    recall = np.full(nt, np.nan)
    for t in range(nt):
        yt = np.concatenate([s.y_true[t] for s in matches]) if matches else np.zeros(0)
        ys = np.concatenate([s.y_score[t] for s in matches]) if matches else np.zeros(0)
        fn = int(sum(int(s.hard_fn[t]) for s in matches))
        ap[t] = average_precision(yt, ys, fn, num_gt > 0, num_pred > 0)
        if num_gt:
            recall[t] = sum(int(s.gt_matched[t].sum()) for s in matches) / num_gt
    return Metrics(ap=ap, recall=recall, num_gt=num_gt, num_pred=num_pred)


def recall_on(matches: Sequence[SceneMatches], selected: dict[str, np.ndarray]) -> Metrics:
    """Recall restricted to chosen GT objects (``selected[scene_id]`` = object ids); AP is NaN."""
    nt = len(ALL_THRESHOLDS)
    hit = np.zeros(nt)
    total = 0
    for s in matches:
        ids = selected.get(s.scene_id)
        if ids is None or len(ids) == 0:
            continue
        cols = np.isin(s.gt_ids, np.asarray(ids))
        total += int(cols.sum())
        hit += s.gt_matched[:, cols].sum(axis=1)
    recall = hit / total if total else np.full(nt, np.nan)
    return Metrics(ap=np.full(nt, np.nan), recall=recall, num_gt=total, num_pred=sum(s.num_pred for s in matches))


def evaluate_scene(
    instance: np.ndarray,
    masks: np.ndarray,
    scores: np.ndarray,
    *,
    valid: np.ndarray | None = None,
    scene_id: str = "",
) -> Metrics:
    """AP/AR of one scene (the benchmark run on a one-scene dataset)."""
    return summarize([match_scene(instance, masks, scores, valid=valid, scene_id=scene_id)])

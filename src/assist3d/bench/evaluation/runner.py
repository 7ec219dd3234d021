"""Evaluate a prediction folder against a dataset: per scene, pooled, and out-of-domain."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ...data.base import SceneDataset
from ...core.errors import DataError
from ...core.errors import shown as show_text
from ...core.interrupts import worker_pool
from .ap import (ALL_THRESHOLDS, METRIC_KEYS, MIN_REGION_SIZE, Metrics, SceneMatches, match_scene, recall_on,
                 summarize)
from .ood import FeatureFn, dataset_features, default_feature, instance_features, ood_threshold
from .predictions import import_scannet_txt, load_predictions

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class EvaluationResult:
    """Dataset-level metrics (pooled like the benchmark), per-scene metrics, optional OOD recall."""

    dataset: str
    overall: Metrics
    per_scene: dict[str, Metrics]
    ood: Metrics | None = None
    missing: tuple[str, ...] = ()

    def to_dict(self, *, per_scene: bool = False) -> dict[str, Any]:
        """A JSON-ready dict: the six figures, ``scenes``, counts and per-threshold arrays (NaN -> null)."""
        d: dict[str, Any] = {k: _num(self.overall[k]) for k in METRIC_KEYS}
        d["scenes"] = len(self.per_scene)
        d["dataset"] = self.dataset
        d["num_gt"] = self.overall.num_gt
        d["num_pred"] = self.overall.num_pred
        d["missing_predictions"] = list(self.missing)
        d["thresholds"] = [round(float(t), 4) for t in ALL_THRESHOLDS]
        d["ap_per_threshold"] = [_num(x) for x in self.overall.ap]
        d["recall_per_threshold"] = [_num(x) for x in self.overall.recall]
        if self.ood is not None:
            d["ood"] = {"AR": _num(self.ood["AR"]), "AR50": _num(self.ood["AR50"]), "AR25": _num(self.ood["AR25"]),
                        "num_objects": self.ood.num_gt}
        if per_scene:
            d["per_scene"] = {
                sid: {**{k: _num(m[k]) for k in METRIC_KEYS}, "num_gt": m.num_gt, "num_pred": m.num_pred}
                for sid, m in self.per_scene.items()
            }
        return d


def _num(x: float) -> float | None:
    return None if x is None or (isinstance(x, float) and math.isnan(x)) else float(x)


def prediction_path(pred_dir: Path, scene_id: str) -> Path | None:
    """``<scene_id>.npz`` in ``pred_dir``, else the benchmark's ``<scene_id>.txt``, else None."""
    for suffix in (".npz", ".txt"):
        p = pred_dir / f"{scene_id}{suffix}"
        if p.is_file():
            return p
    return None


def read_scene_predictions(path: Path, n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Masks and scores from an ``.npz`` or benchmark ``.txt``, checked against ``n_points``."""
    if path.suffix == ".txt":
        return import_scannet_txt(path, n_points)
    return load_predictions(path, n_points)


def _score_scene(job: tuple) -> tuple[SceneMatches, np.ndarray | None]:
    """Read one scene and its predictions, match them, and pick its out-of-domain objects."""
    dataset, sid, path, feature, ood_mean, d_max = job
    sample = dataset.load(sid)
    if path is None:
        masks, scores = np.zeros((0, len(sample)), bool), np.zeros(0, np.float32)
    else:
        masks, scores = read_scene_predictions(path, len(sample))
    m = match_scene(sample.instance, masks, scores, valid=sample.valid, scene_id=sid)
    if ood_mean is None:
        return m, None
    ids, feats = instance_features(sample, feature)
    if len(ids) == 0:
        return m, ids
    if feats.shape[1] != len(ood_mean):
        raise DataError(f"scene {sid}: feature dimension {feats.shape[1]} differs from the reference's {len(ood_mean)}")
    return m, ids[np.linalg.norm(feats.astype(np.float64) - ood_mean, axis=1) > d_max]


def _warn_scenes_without_objects(dataset: SceneDataset, matches: list[SceneMatches]) -> None:
    """One warning naming the scenes with no ground-truth object to score (every label void or
    invalid, or every object under the minimum size): their AP/AR are undefined (NaN / null)."""
    empty = [m.scene_id for m in matches if m.num_gt == 0]
    if not empty:
        return
    names = ", ".join(show_text(s, 80) for s in empty[:5]) + (f", ... ({len(empty)} in all)" if len(empty) > 5 else "")
    log.warning("%s: %d of %d scenes have no ground-truth object of at least %d valid points (every label void, "
                "excluded or on too few points), so their own AP/AR are undefined (NaN, null in JSON): %s",
                dataset.name, len(empty), len(matches), MIN_REGION_SIZE, names)


def evaluate_dataset(
    dataset: SceneDataset,
    pred_dir: str | Path,
    *,
    allow_missing: bool = False,
    ood_reference: SceneDataset | None = None,
    feature: FeatureFn = default_feature,
    progress: Callable[[int, int], None] | None = None,
    workers: int = 1,
) -> EvaluationResult:
    """Score ``pred_dir`` (``<scene_id>.npz`` or ``.txt`` per scene) against ``dataset``.

    Missing prediction files raise :class:`DataError` listing them unless ``allow_missing``, in
    which case those scenes count as having no predictions. ``ood_reference``: a dataset whose
    objects define "in domain"; the result then carries AR/AR50/AR25 on the out-of-domain objects.
    ``workers > 1`` reads and matches scenes in that many processes (the dataset and ``feature``
    must then be picklable, e.g. module-level functions); results do not depend on it.
    """
    pred_dir = Path(pred_dir)
    if not pred_dir.is_dir():
        raise DataError(f"{pred_dir}: prediction folder not found")
    paths = {sid: prediction_path(pred_dir, sid) for sid in dataset.scene_ids}
    missing = tuple(sid for sid, p in paths.items() if p is None)
    known = set(dataset.scene_ids)
    extra = sorted(f.stem for f in pred_dir.glob("*.npz") if f.stem not in known)
    if extra:
        log.warning("%s: %d prediction files match no scene of %s (e.g. %s)", pred_dir, len(extra), dataset.name, extra[0])
    if missing and not allow_missing:
        shown = ", ".join(missing[:10]) + (f" ... ({len(missing)} in all)" if len(missing) > 10 else "")
        raise DataError(
            f"{pred_dir}: no predictions (<scene_id>.npz) for {len(missing)} of {len(dataset)} scenes: {shown}; "
            "pass --allow-missing to count them as scenes without predictions"
        )
    ood_mean: np.ndarray | None = None
    d_max = 0.0
    if ood_reference is not None:
        ref = dataset_features(ood_reference, feature)
        ood_mean, d_max = ood_threshold(ref)
        log.info("out-of-domain reference %s: %d objects, d_max %.4f", ood_reference.name, len(ref), d_max)

    jobs = [(dataset, sid, paths[sid], feature if ood_mean is not None else None, ood_mean, d_max)
            for sid in dataset.scene_ids]
    matches: list[SceneMatches] = []
    per_scene: dict[str, Metrics] = {}
    selected: dict[str, np.ndarray] = {}

    def collect(i: int, m: SceneMatches, chosen: np.ndarray | None) -> None:
        matches.append(m)
        per_scene[m.scene_id] = summarize([m])
        if chosen is not None:
            selected[m.scene_id] = chosen
        if progress is not None:
            progress(i + 1, len(jobs))

    if workers <= 1 or len(jobs) <= 1:
        for i, job in enumerate(jobs):
            collect(i, *_score_scene(job))
    else:
        with worker_pool(min(workers, len(jobs))) as pool:  # stopped at once on an interrupt
            for i, (m, chosen) in enumerate(pool.map(_score_scene, jobs)):
                collect(i, m, chosen)
    _warn_scenes_without_objects(dataset, matches)
    overall = summarize(matches)
    ood = recall_on(matches, selected) if ood_reference is not None else None
    return EvaluationResult(dataset=f"{dataset.format}:{dataset.root}", overall=overall, per_scene=per_scene, ood=ood, missing=missing)

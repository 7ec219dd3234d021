"""Class-agnostic instance-segmentation evaluation (ScanNet benchmark rules), predictions I/O and
out-of-domain recall, and paired per-scan comparisons of two models. See ``docs/evaluation.md``."""

from __future__ import annotations

from .ap import (
    ALL_THRESHOLDS,
    METRIC_KEYS,
    MIN_REGION_SIZE,
    THRESHOLDS,
    Metrics,
    SceneMatches,
    average_precision,
    evaluate_scene,
    match_scene,
    recall_on,
    summarize,
)
from .compare import PairedComparison, mean_over_runs, paired_comparison
from .ood import FeatureFn, dataset_features, default_feature, instance_features, ood_mask, ood_threshold
from .predictions import (
    convert_predictions,
    export_scannet_txt,
    import_scannet_txt,
    load_predictions,
    save_predictions,
)
from .runner import EvaluationResult, evaluate_dataset, prediction_path, read_scene_predictions

__all__ = [
    "ALL_THRESHOLDS", "METRIC_KEYS", "MIN_REGION_SIZE", "THRESHOLDS", "EvaluationResult", "FeatureFn",
    "Metrics", "PairedComparison", "SceneMatches", "average_precision", "convert_predictions", "dataset_features",
    "default_feature", "evaluate_dataset", "evaluate_scene", "export_scannet_txt", "import_scannet_txt",
    "instance_features", "load_predictions", "match_scene", "mean_over_runs", "ood_mask", "ood_threshold",
    "paired_comparison", "prediction_path", "read_scene_predictions", "recall_on", "save_predictions", "summarize",
]

"""Out-of-domain recall (the paper's "Effect of Geometry Diversity").

Embed every object of a reference dataset (ScanNet v2 in the paper) with a shape feature, take
the mean feature and the largest distance ``d_max`` of any reference object from it; a test
object is out-of-domain when its distance from that mean exceeds ``d_max``. AR, AR50 and AR25 are
then the recall of the ordinary matching restricted to those objects.

The feature extractor is any callable ``(points (n, 3) float32) -> (d,) float32`` (or ``None`` for
an object it cannot describe, which is then left out). The default is the project's shape
descriptor, :func:`assist3d.bench.metrics.features.shape_descriptor`, seeded identically for every
object so a run is reproducible. Objects are described from their points (only objects of at least
:data:`~assist3d.bench.evaluation.ap.MIN_REGION_SIZE` valid points, the ones the evaluation scores).
"""

from __future__ import annotations

import logging
from typing import Callable, Iterable

import numpy as np

from ...core.contracts import PointSample
from ...core.errors import DataError
from ..metrics.features import shape_descriptor
from .ap import MIN_REGION_SIZE

log = logging.getLogger(__name__)

FeatureFn = Callable[[np.ndarray], "np.ndarray | None"]
FEATURE_SEED = 0


def default_feature(points: np.ndarray) -> np.ndarray | None:
    """The metrics module's shape descriptor with a fixed seed (same points -> same feature)."""
    return shape_descriptor(points, rng=np.random.default_rng(FEATURE_SEED))


def instance_features(
    sample: PointSample,
    feature: FeatureFn = default_feature,
    *,
    min_points: int = MIN_REGION_SIZE,
) -> tuple[np.ndarray, np.ndarray]:
    """Features of a scene's objects: ``(ids (k,) int32, features (k, d) float32)``.

    Only valid points count; objects with fewer than ``min_points`` of them, or that the extractor
    returns ``None`` for, are left out. Loops over objects, never over points.
    """
    keep = sample.valid & (sample.instance >= 0)
    inst = sample.instance[keep]
    coord = sample.coord[keep]
    order = np.argsort(inst, kind="stable")
    ids, start, counts = np.unique(inst[order], return_index=True, return_counts=True)
    out_ids: list[int] = []
    feats: list[np.ndarray] = []
    for i, s, c in zip(ids.tolist(), start.tolist(), counts.tolist()):
        if c < min_points:
            continue
        f = feature(coord[order[s:s + c]])
        if f is None:
            continue
        f = np.asarray(f, np.float32).ravel()
        if feats and f.shape != feats[0].shape:
            raise DataError(f"scene {sample.scene_id}: feature extractor returned {f.shape} for object {i}, earlier {feats[0].shape}")
        out_ids.append(i)
        feats.append(f)
    if not feats:
        return np.zeros(0, np.int32), np.zeros((0, 0), np.float32)
    return np.asarray(out_ids, np.int32), np.stack(feats)


def dataset_features(samples: Iterable[PointSample], feature: FeatureFn = default_feature) -> np.ndarray:
    """All object features of a dataset stacked: ``(R, d) float32``."""
    parts = [f for _, f in (instance_features(s, feature) for s in samples) if len(f)]
    if not parts:
        return np.zeros((0, 0), np.float32)
    return np.concatenate(parts)


def ood_threshold(reference_features: np.ndarray) -> tuple[np.ndarray, float]:
    """``(mean feature (d,), d_max)``: the reference mean and the largest distance from it."""
    ref = np.asarray(reference_features, np.float64)
    if ref.ndim != 2 or len(ref) == 0:
        raise DataError(f"out-of-domain reference: need a non-empty (R, d) feature array, got shape {ref.shape}")
    mean = ref.mean(axis=0)
    return mean, float(np.linalg.norm(ref - mean, axis=1).max())


def ood_mask(reference_features: np.ndarray, test_features: np.ndarray) -> np.ndarray:
    """``(T,) bool``: test objects farther from the reference mean than any reference object."""
    mean, d_max = ood_threshold(reference_features)
    test = np.asarray(test_features, np.float64)
    if len(test) == 0:
        return np.zeros(0, bool)
    if test.ndim != 2 or test.shape[1] != len(mean):
        raise DataError(f"out-of-domain: test features have shape {test.shape}, reference dimension is {len(mean)}")
    return np.linalg.norm(test - mean, axis=1) > d_max

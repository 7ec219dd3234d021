"""Instances from per-voxel predictions: foreground voxels moved by their predicted centre offsets,
then linked within a radius (connected components of the radius graph, i.e. PointGroup's ball-query
breadth-first search).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .config import ClusterConfig


@dataclass(frozen=True)
class VoxelInstances:
    """``labels`` (V,) int64 instance per voxel (-1 none, 0..K-1 by descending score); ``scores`` (K,) float32."""

    labels: np.ndarray
    scores: np.ndarray


def radius_components(xyz: np.ndarray, radius: float) -> np.ndarray:
    """Connected-component id of every row of ``xyz`` (M, 3) in the graph linking rows within ``radius``."""
    n = len(xyz)
    if n == 0:
        return np.zeros(0, np.int64)
    pairs = cKDTree(xyz).query_pairs(radius, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs), np.int8), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    return connected_components(graph, directed=False)[1].astype(np.int64)


def instance_score(mean_fg: np.ndarray, n_voxels: np.ndarray) -> np.ndarray:
    """Mean foreground probability x ``min(1, voxels / 40) ** 0.5``: drifted fragments rank low."""
    return mean_fg * np.minimum(1.0, n_voxels / 40.0) ** 0.5


def cluster_voxels(centres: np.ndarray, fg_prob: np.ndarray, offset: np.ndarray, cfg: ClusterConfig) -> VoxelInstances:
    """Group foreground voxels into instances; score = mean foreground probability x a size factor.

    The size factor ``min(1, n / 40) ** 0.5`` ranks small fragments (a few voxels that drifted away
    from their object's centre) below whole objects.
    """
    v = len(centres)
    labels = np.full(v, -1, np.int64)
    rows = np.flatnonzero(fg_prob > cfg.fg_threshold)
    if len(rows) == 0:
        return VoxelInstances(labels, np.zeros(0, np.float32))
    comp = radius_components(centres[rows] + offset[rows], cfg.radius)
    sizes = np.bincount(comp)
    mean_fg = np.bincount(comp, weights=fg_prob[rows]) / np.maximum(sizes, 1)
    keep = np.flatnonzero(sizes >= cfg.min_voxels)
    score = instance_score(mean_fg[keep], sizes[keep])
    order = np.argsort(-score, kind="stable")
    new_id = np.full(len(sizes), -1, np.int64)
    new_id[keep[order]] = np.arange(len(keep))
    labels[rows] = new_id[comp]
    return VoxelInstances(labels, score[order].astype(np.float32))


def point_masks(labels: np.ndarray, inverse: np.ndarray, num_instances: int) -> np.ndarray:
    """``(K, N) bool`` point masks from voxel labels and each point's voxel row."""
    point_label = labels[inverse]
    return point_label[None, :] == np.arange(num_instances)[:, None]


def mask_nms(masks: np.ndarray, scores: np.ndarray, iou_max: float = 0.5) -> np.ndarray:
    """Indices of the masks kept by greedy non-maximum suppression, best score first: a mask is
    dropped when its IoU with a kept, higher-scoring one exceeds ``iou_max``. ``masks`` (M, N) bool."""
    if len(masks) == 0:
        return np.zeros(0, np.int64)
    iou = pairwise_iou(masks, masks)
    keep, suppressed = [], np.zeros(len(scores), bool)
    for i in np.argsort(-np.asarray(scores), kind="stable"):
        if not suppressed[i]:
            keep.append(i)
            suppressed |= iou[i] > iou_max
    return np.asarray(keep, np.int64)


def pairwise_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(A, B) float32 IoU of every mask of ``a`` (A, N) bool with every mask of ``b`` (B, N) bool
    (0 where both are empty), from one sparse product over their set entries."""
    sa, sb = bool_rows_csr(a), bool_rows_csr(b)
    inter = (sa @ sb.T).toarray()
    area_a = np.diff(sa.indptr).astype(np.float32)
    area_b = np.diff(sb.indptr).astype(np.float32)
    return inter / np.maximum(area_a[:, None] + area_b[None, :] - inter, 1e-9)


def bool_rows_csr(masks: np.ndarray) -> csr_matrix:
    """``masks`` (M, N) bool as a float32 sparse matrix, built from the set entries only (a dense
    float copy of M masks over a million points would take gigabytes)."""
    rows, cols = np.nonzero(masks)
    return csr_matrix((np.ones(len(rows), np.float32), (rows, cols)), shape=masks.shape)

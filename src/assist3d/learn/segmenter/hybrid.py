"""Hybrid inference, the default of ``assist3d segment``: the network's instances plus the geometric
reference's components, both ranked by the network, then snapped to superpoints.

1. the learned proposals (foreground voxels shifted by their offsets, linked within 7 cm) with
   their scores;
2. the geometric reference's proposals (structural planes removed, connected components), scored
   the same way as learned ones: mean foreground probability of their points x
   ``min(1, voxels / 40) ** 0.5`` (5 cm voxels), so the network decides which of them look like
   objects;
3. greedy non-maximum suppression over both sets (IoU 0.5; PointGroup keeps two proposal sets in
   the same way);
4. each kept mask snapped to superpoints (``superpoints.py``).

The two proposal sources fail in different rooms (docs/fidelity.md: the network in sparse rooms
whose objects stand apart, the components in cluttered ones), and snapping fixes ragged 5 cm
boundaries. Measured with 28 trained models on the dev scans and on scene0451_01 (docs/fidelity.md,
"Hybrid inference"). ``assist3d probe`` keeps the learned proposals alone: it measures training
data, and the geometric proposals do not depend on it.

Masks may overlap (a component can hold two learned instances without an IoU above 0.5 with
either); ``labels`` gives each point the best-scoring mask that holds it.
"""

from __future__ import annotations

import numpy as np

from .cluster import instance_score, mask_nms
from .config import SegmenterConfig
from .features import Voxels, voxel_features, voxelize
from .geometric import GeometricConfig, segment_geometric
from .infer import Segmentation, instances, predict_voxels
from .model import Segmenter
from .superpoints import SuperpointConfig, snap_masks, superpoints

NMS_IOU = 0.5


def labels_from_masks(masks: np.ndarray) -> np.ndarray:
    """(N,) int64: the first (best-scoring) mask holding each point, -1 for none; masks sorted by score."""
    labels = np.full(masks.shape[1], -1, np.int64)
    if len(masks):
        held = masks.any(0)
        labels[held] = np.argmax(masks[:, held], axis=0)
    return labels


def proposals(learned: Segmentation, vox: Voxels, fg: np.ndarray, components: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Steps 1-2: the network's instances ``learned`` (from :func:`infer.instances` on ``vox``) followed by
    the geometric components (C, N) bool, each scored by the network's foreground probability ``fg``
    (V,): masks (M, N) bool and scores (M,) float64, before suppression."""
    point_fg = fg[vox.inverse]
    n_vox = np.array([len(np.unique(vox.inverse[m])) for m in components], np.float64)
    mean_fg = np.array([point_fg[m].mean() for m in components], np.float64)
    masks = np.concatenate([learned.masks, components])
    scores = np.concatenate([learned.scores.astype(np.float64), instance_score(mean_fg, n_vox)])
    return masks, scores


def combine(learned: Segmentation, vox: Voxels, fg: np.ndarray, components: np.ndarray, segments: np.ndarray,
            min_cover: float = SuperpointConfig.min_cover) -> Segmentation:
    """Steps 2-4: the network's instances ``learned`` (from :func:`infer.instances` on ``vox``), its
    foreground probability ``fg`` (V,), the geometric components (C, N) bool and the superpoint id
    (N,) of every point."""
    masks, scores = proposals(learned, vox, fg, components)
    keep = mask_nms(masks, scores, NMS_IOU)
    masks, scores = masks[keep], scores[keep]
    if len(masks):
        masks = snap_masks(masks, segments, min_cover)
    return Segmentation(masks=masks, scores=scores.astype(np.float32), labels=labels_from_masks(masks))


def segment_hybrid(model: Segmenter, cfg: SegmenterConfig, coord: np.ndarray, color: np.ndarray | None = None, *,
                   geometric: GeometricConfig = GeometricConfig(),
                   superpoint: SuperpointConfig = SuperpointConfig(), device: str = "cpu") -> Segmentation:
    """Segment one scan with the hybrid recipe: ``coord`` (N, 3) metres (z up), ``color`` (N, 3) uint8 or None."""
    coord = np.asarray(coord, np.float32)
    if cfg.net.use_color and color is None:
        color = np.full((len(coord), 3), 128, np.uint8)
    vox = voxelize(coord, cfg.net.voxel_size, color)
    fg, offset = predict_voxels(model, vox.coords, voxel_features(vox, use_color=cfg.net.use_color), device)
    return combine(instances(vox, fg, offset, cfg.cluster), vox, fg, segment_geometric(coord, geometric).masks,
                   superpoints(coord, superpoint), superpoint.min_cover)

"""Hybrid inference, ``assist3d segment --method hybrid``: the network's instances plus the geometric
reference's components, both ranked by the network, fallback proposals ranked below them, then
snapped to superpoints.

1. the learned proposals (foreground voxels shifted by their offsets, linked within 7 cm) with
   their scores;
2. the geometric reference's proposals (structural planes removed, connected components; each
   RANSAC plane refit twice to its inliers, ``HYBRID_GEOMETRIC``), scored the same way as learned
   ones: mean foreground probability of their points x ``min(1, voxels / 40) ** 0.5`` (5 cm
   voxels), so the network decides which of them look like objects;
3. fallback proposals: the network's instances linked at ``fallback_radius`` (5 cm), which split
   objects that touch, ranked below every proposal of steps 1-2 (scores ``s / 2`` for them,
   ``(1 + s) / 2`` for the others). Proposals ranked below all others only add points at the end
   of the precision-recall curve and never move its earlier points, so under the ScanNet protocol
   they cannot lower AP, AP50 or AP25 of a scan or of a dataset;
4. greedy non-maximum suppression over all of them (IoU 0.5; PointGroup keeps two proposal sets in
   the same way): a fallback proposal is dropped when it repeats one of steps 1-2;
5. each kept mask snapped to superpoints (``superpoints.py``).

The two proposal sources fail in different rooms (the network in sparse rooms whose objects stand
apart, the components in cluttered ones), and snapping fixes ragged 5 cm boundaries; the measurements
are in experiments/fidelity-log.md ("Hybrid inference", "Fallback proposals"). ``assist3d probe`` scores the learned
proposals alone (it measures training data, and the geometric proposals do not depend on it); ``probe
--hybrid`` scores this recipe too.

Three variants were measured and not adopted, and have left the code (a stability ranking, instances
linked without the structural planes' voxels, ranking by agreement with the superpoints); experiments/fidelity-log.md
and their experiment folders keep what they did.

Masks may overlap (a component can hold two learned instances without an IoU above 0.5 with
either); ``labels`` gives each point the best-scoring mask that holds it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cluster import instance_score, mask_nms
from .config import ClusterConfig, SegmenterConfig
from .features import Voxels, voxelize
from .geometric import GeometricConfig, segment_geometric, structural_points
from .infer import Segmentation, instances, predict_scan
from .model import Network
from .superpoints import SuperpointConfig, snap_masks, superpoints

NMS_IOU = 0.5


#: The geometric settings of hybrid inference: the reference's, with each RANSAC plane refit twice to
#: its inliers, which keeps the components steadier when a scan moves by a millimetre (experiments/fidelity-log.md,
#: "Noisy scans"). The reference row itself (``segment --method geometric``) keeps ``GeometricConfig()``.
HYBRID_GEOMETRIC = GeometricConfig(refine=2)


@dataclass(frozen=True)
class HybridConfig:
    """``fallback_radius`` (metres; None: no fallback proposals) is step 3 of the module docstring;
    ``fallback_radius=None`` gives the first hybrid recipe (network and geometric proposals, NMS,
    snapping)."""

    fallback_radius: float | None = 0.05
    nms_iou: float = NMS_IOU


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
    (V,): masks (M, N) bool and scores (M,) float64, before fallback proposals and suppression."""
    masks = np.concatenate([learned.masks, components])
    scores = np.concatenate([learned.scores.astype(np.float64), network_score(components, vox, fg)])
    return masks, scores


def network_score(masks: np.ndarray, vox: Voxels, fg: np.ndarray) -> np.ndarray:
    """The network's score of point masks (M, N) bool: :func:`cluster.instance_score` of their points'
    mean foreground probability and of their number of voxels."""
    point_fg = fg[vox.inverse]
    n_vox = np.array([len(np.unique(vox.inverse[m])) for m in masks], np.float64)
    mean_fg = np.array([point_fg[m].mean() if m.any() else 0.0 for m in masks], np.float64)
    return instance_score(mean_fg, n_vox)


def combine(learned: Segmentation, vox: Voxels, fg: np.ndarray, offset: np.ndarray, cluster: ClusterConfig,
            components: np.ndarray, segments: np.ndarray, min_cover: float = SuperpointConfig.min_cover,
            hybrid: HybridConfig = HybridConfig()) -> Segmentation:
    """Steps 2-5: the network's instances ``learned`` (from :func:`infer.instances` on ``vox`` with
    ``cluster``), its foreground probability ``fg`` (V,) and offsets ``offset`` (V, 3), the geometric
    components (C, N) bool and the superpoint id (N,) of every point."""
    masks, scores = proposals(learned, vox, fg, components)
    first = len(masks)
    if hybrid.fallback_radius is not None:
        extra = instances(vox, fg, offset, cluster.model_copy(update={"radius": hybrid.fallback_radius}))
        masks = np.concatenate([masks, extra.masks])
        scores = np.concatenate([scores, extra.scores.astype(np.float64)])
        scores = np.concatenate([(1.0 + scores[:first]) / 2.0, scores[first:] / 2.0])
    keep = mask_nms(masks, scores, hybrid.nms_iou)
    masks, scores = masks[keep], scores[keep]
    if len(masks):
        masks = snap_masks(masks, segments, min_cover)
    return Segmentation(masks=masks, scores=scores.astype(np.float32), labels=labels_from_masks(masks))


def segment_hybrid(model: Network, cfg: SegmenterConfig, coord: np.ndarray, color: np.ndarray | None = None, *,
                   geometric: GeometricConfig = HYBRID_GEOMETRIC,
                   superpoint: SuperpointConfig = SuperpointConfig(), hybrid: HybridConfig = HybridConfig(),
                   tta: bool = False, device: str = "cpu") -> Segmentation:
    """Segment one scan with the hybrid recipe: ``coord`` (N, 3) metres (z up), ``color`` (N, 3) uint8 or
    None; ``tta`` averages the network over 8 turned and mirrored copies of the scan (``infer.predict_scan``)."""
    coord = np.asarray(coord, np.float32)
    if cfg.net.use_color and color is None:
        color = np.full((len(coord), 3), 128, np.uint8)
    vox = voxelize(coord, cfg.net.voxel_size, color)
    fg, offset = predict_scan(model, cfg, coord, color, vox, tta=tta, device=device)
    on_plane = structural_points(coord, geometric)
    return combine(instances(vox, fg, offset, cfg.cluster), vox, fg, offset, cfg.cluster,
                   segment_geometric(coord, geometric, on_plane).masks, superpoints(coord, superpoint),
                   superpoint.min_cover, hybrid)

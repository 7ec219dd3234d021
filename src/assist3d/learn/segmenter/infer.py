"""Inference: points in, instance masks and scores out (the learned model or the geometric reference)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from .cluster import cluster_voxels, point_masks
from .config import ClusterConfig, SegmenterConfig
from .features import Voxels, voxel_features, voxelize
from .model import Segmenter


@dataclass(frozen=True)
class Segmentation:
    """``masks`` (M, N) bool over the input points, ``scores`` (M,) float32 descending, ``labels`` (N,)
    int64 instance index per point (-1 = none). Learned and geometric masks are disjoint; hybrid
    masks may overlap, and ``labels`` then names the best-scoring mask holding the point."""

    masks: np.ndarray
    scores: np.ndarray
    labels: np.ndarray


def batch_coords(coords: np.ndarray, b: int = 0) -> np.ndarray:
    return np.concatenate([np.full((len(coords), 1), b, np.int32), coords.astype(np.int32)], 1)


@torch.no_grad()
def predict_voxels(model: Segmenter, coords: np.ndarray, feats: np.ndarray, device: str = "cpu") -> tuple[np.ndarray, np.ndarray]:
    """Foreground probability (V,) and offsets (V, 3) for one scene's voxels."""
    model.eval()
    c = torch.from_numpy(batch_coords(coords)).to(device)
    f = torch.from_numpy(np.ascontiguousarray(feats)).to(device)
    logit, offset = model(c, f)
    return torch.sigmoid(logit).float().cpu().numpy(), offset.float().cpu().numpy()


def segment_points(model: Segmenter, cfg: SegmenterConfig, coord: np.ndarray, color: np.ndarray | None = None, *,
                   cluster: ClusterConfig | None = None, device: str = "cpu") -> Segmentation:
    """Segment one scan: ``coord`` (N, 3) metres (z up), ``color`` (N, 3) uint8 or None."""
    if cfg.net.use_color and color is None:
        color = np.full((len(coord), 3), 128, np.uint8)
    vox = voxelize(np.asarray(coord, np.float32), cfg.net.voxel_size, color)
    feats = voxel_features(vox, use_color=cfg.net.use_color)
    fg, offset = predict_voxels(model, vox.coords, feats, device)
    return instances(vox, fg, offset, cluster or cfg.cluster)


def instances(vox: Voxels, fg: np.ndarray, offset: np.ndarray, cluster: ClusterConfig) -> Segmentation:
    """The network's instances over the points of ``vox`` from its outputs fg (V,) and offset (V, 3)."""
    inst = cluster_voxels(vox.centres, fg, offset.astype(np.float64), cluster)
    masks = point_masks(inst.labels, vox.inverse, len(inst.scores))
    return Segmentation(masks=masks, scores=inst.scores, labels=inst.labels[vox.inverse])

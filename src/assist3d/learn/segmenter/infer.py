"""Inference: points in, instance masks and scores out (the learned model or the geometric reference)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from .cluster import cluster_voxels, point_masks
from .config import ClusterConfig, SegmenterConfig
from .features import Voxels, voxel_features, voxelize
from .model import Network


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
def predict_voxels(model: Network, coords: np.ndarray, feats: np.ndarray, device: str = "cpu") -> tuple[np.ndarray, np.ndarray]:
    """Foreground probability (V,) and offsets (V, 3) for one scene's voxels."""
    model.eval()
    c = torch.from_numpy(batch_coords(coords)).to(device)
    f = torch.from_numpy(np.ascontiguousarray(feats)).to(device)
    logit, offset = model(c, f)
    return torch.sigmoid(logit).float().cpu().numpy(), offset.float().cpu().numpy()


TTA_TURNS = tuple((k, m) for m in (False, True) for k in range(4))  # (quarter turns about z, mirror x)


def tta_rotation(quarter_turns: int, mirror: bool) -> np.ndarray:
    """(3, 3) rotation by ``quarter_turns`` x 90 degrees about z, after mirroring x if ``mirror``."""
    c, s = np.cos(quarter_turns * np.pi / 2), np.sin(quarter_turns * np.pi / 2)
    r = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return r @ np.diag([-1.0, 1.0, 1.0]) if mirror else r


def predict_voxels_tta(model: Network, cfg: SegmenterConfig, coord: np.ndarray, color: np.ndarray | None,
                       vox: Voxels, turns: tuple[tuple[int, bool], ...] = TTA_TURNS,
                       device: str = "cpu") -> tuple[np.ndarray, np.ndarray]:
    """Test-time augmentation: foreground probability (V,) and offsets (V, 3) on the voxels ``vox`` of
    ``coord`` (N, 3), averaged over copies of the scan turned about z (and mirrored) by ``turns``.
    Each copy is voxelised on its own, its outputs go back to ``vox`` through the points (the mean
    over a voxel's points) and its offsets are turned back."""
    n_vox = len(vox.centres)
    count = np.bincount(vox.inverse, minlength=n_vox)
    fg_sum, off_sum = np.zeros(n_vox), np.zeros((n_vox, 3))
    for k, mirror in turns:
        r = tta_rotation(k, mirror)
        v2 = voxelize((np.asarray(coord, np.float64) @ r.T).astype(np.float32), cfg.net.voxel_size, color)
        fg, off = predict_voxels(model, v2.coords, voxel_features(v2, use_color=cfg.net.use_color), device)
        point_fg, point_off = fg[v2.inverse], off[v2.inverse] @ r  # r is orthogonal: r.T undoes it
        fg_sum += np.bincount(vox.inverse, point_fg, n_vox) / count
        off_sum += np.stack([np.bincount(vox.inverse, point_off[:, j], n_vox) / count for j in range(3)], 1)
    return (fg_sum / len(turns)).astype(np.float32), (off_sum / len(turns)).astype(np.float32)


def predict_scan(model: Network, cfg: SegmenterConfig, coord: np.ndarray, color: np.ndarray | None, vox: Voxels,
                 *, tta: bool = False, device: str = "cpu") -> tuple[np.ndarray, np.ndarray]:
    """Foreground probability (V,) and offsets (V, 3) on the voxels ``vox`` of ``coord``: one pass of
    the network, or with ``tta`` the mean over the 8 copies of :data:`TTA_TURNS`."""
    if tta:
        return predict_voxels_tta(model, cfg, coord, color, vox, device=device)
    return predict_voxels(model, vox.coords, voxel_features(vox, use_color=cfg.net.use_color), device)


def segment_points(model: Network, cfg: SegmenterConfig, coord: np.ndarray, color: np.ndarray | None = None, *,
                   cluster: ClusterConfig | None = None, tta: bool = False, device: str = "cpu") -> Segmentation:
    """Segment one scan: ``coord`` (N, 3) metres (z up), ``color`` (N, 3) uint8 or None; ``tta``
    averages the network over 8 turned and mirrored copies of the scan (8 times the network's time)."""
    if cfg.net.use_color and color is None:
        color = np.full((len(coord), 3), 128, np.uint8)
    coord = np.asarray(coord, np.float32)
    vox = voxelize(coord, cfg.net.voxel_size, color)
    fg, offset = predict_scan(model, cfg, coord, color, vox, tta=tta, device=device)
    return instances(vox, fg, offset, cluster or cfg.cluster)


def instances(vox: Voxels, fg: np.ndarray, offset: np.ndarray, cluster: ClusterConfig) -> Segmentation:
    """The network's instances over the points of ``vox`` from its outputs fg (V,) and offset (V, 3)."""
    inst = cluster_voxels(vox.centres, fg, offset.astype(np.float64), cluster)
    masks = point_masks(inst.labels, vox.inverse, len(inst.scores))
    return Segmentation(masks=masks, scores=inst.scores, labels=inst.labels[vox.inverse])

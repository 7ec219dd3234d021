"""Inference: checkpoint + scenes -> ``<scene_id>.npz`` with ``masks`` (bool [M, N]) and ``scores`` (float32 [M]).

Per scene: voxelise (no augmentation), run the model, take the final layer; a query's binary mask is
``logit > 0``; its score is sigmoid(objectness) x the mean mask probability inside the mask; keep the
``top_k`` best; optionally split each mask into DBSCAN clusters (each cluster keeps the mask's score);
map voxels back to the reader's points through the inverse voxel map.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, ClassVar

import numpy as np
import torch
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ...core.contracts import PointSample
from ...core.errors import shown
from ...core.fileio import write_npz_atomic
from ...core.paths import safe_name
from ..checkpoint import Checkpoint, read_checkpoint
from .config import PredictConfig, TrainConfig, parse_train_config
from .scenes import open_spec
from .train import build_model, resolve_device
from .voxelize import collate, voxelize

log = logging.getLogger(__name__)


def dbscan_labels(xyz: np.ndarray, eps: float, min_points: int) -> np.ndarray:
    """DBSCAN cluster id per point of ``xyz`` (M, 3); ``-1`` = noise. Own implementation on a k-d tree.

    Core points have at least ``min_points`` neighbours within ``eps`` (themselves included); clusters
    are connected components of core points linked within ``eps``; border points join the cluster of
    their first core neighbour.
    """
    n = len(xyz)
    if n == 0:
        return np.zeros(0, np.int64)
    tree = cKDTree(xyz)
    pairs = tree.query_pairs(eps, output_type="ndarray")
    deg = np.bincount(pairs.ravel(), minlength=n) + 1 if len(pairs) else np.ones(n, np.int64)
    core = deg >= min_points
    cc = pairs[core[pairs[:, 0]] & core[pairs[:, 1]]] if len(pairs) else pairs
    graph = coo_matrix((np.ones(len(cc)), (cc[:, 0], cc[:, 1])), shape=(n, n)) if len(cc) else coo_matrix((n, n))
    _, comp = connected_components(graph, directed=False)
    labels = np.where(core, comp, -1).astype(np.int64)
    if len(pairs):
        # border points: a non-core point next to a core point takes that core point's cluster
        for a, b in ((0, 1), (1, 0)):
            sel = (~core[pairs[:, a]]) & core[pairs[:, b]]
            labels[pairs[sel, a]] = labels[pairs[sel, b]]
    _, labels_c = np.unique(labels, return_inverse=True)
    labels_c = labels_c.astype(np.int64)
    if (labels == -1).any():
        labels_c = np.where(labels == -1, -1, labels_c - 1)
    return labels_c


@dataclass(frozen=True)
class ScenePrediction:
    """``masks`` (M, N) bool over the reader's points; ``scores`` (M,) float32, descending."""

    masks: np.ndarray
    scores: np.ndarray


def predict_scene(model: torch.nn.Module, sample: PointSample, voxel_size: float, cfg: PredictConfig,
                  device: str = "cpu") -> ScenePrediction:
    """The model's instances of one scene (:func:`predict_points` on its points and colours)."""
    return predict_points(model, sample.coord, sample.color, voxel_size, cfg, device)


@torch.no_grad()
def predict_points(model: torch.nn.Module, coord: np.ndarray, color: np.ndarray, voxel_size: float,
                   cfg: PredictConfig, device: str = "cpu") -> ScenePrediction:
    """The model's instances of ``coord`` (N, 3) metres with ``color`` (N, 3) uint8: masks over the points."""
    model.eval()
    vox = voxelize(coord, color, None, voxel_size)
    coords, feats = collate([vox], device)
    final = model(coords, feats, 1)[0][-1]
    logits = final.masks.float()  # (V, Q)
    obj = final.objectness.float().sigmoid()
    binary = logits > 0
    prob = logits.sigmoid()
    count = binary.sum(0)
    mean_in = (prob * binary).sum(0) / count.clamp(min=1)
    scores = (obj * mean_in).cpu().numpy().astype(np.float32)
    vmasks = binary.T.cpu().numpy()  # (Q, V)
    keep = count.cpu().numpy() > 0
    vmasks, scores = vmasks[keep], scores[keep]
    order = np.argsort(-scores, kind="stable")[: cfg.top_k]
    vmasks, scores = vmasks[order], scores[order]
    if cfg.dbscan and len(vmasks):
        centres = (vox.coords.astype(np.float64) + 0.5) * voxel_size
        split_m, split_s = [], []
        for m, s in zip(vmasks, scores):
            rows = np.flatnonzero(m)
            lab = dbscan_labels(centres[rows], cfg.dbscan_eps, cfg.dbscan_min_points)
            for c in np.unique(lab[lab >= 0]):
                mm = np.zeros_like(m)
                mm[rows[lab == c]] = True
                split_m.append(mm)
                split_s.append(s)
        vmasks = np.array(split_m, dtype=bool).reshape(-1, vmasks.shape[1])
        scores = np.array(split_s, dtype=np.float32)
    masks = vmasks[:, vox.inverse]
    big = masks.sum(1) >= cfg.min_points
    masks, scores = masks[big], scores[big]
    order = np.argsort(-scores, kind="stable")
    return ScenePrediction(masks=np.ascontiguousarray(masks[order]), scores=scores[order].astype(np.float32))


@dataclass
class LoadedMask3D:
    """A Mask3D-style model in eval mode with its training configuration (``predict`` holds its settings)."""

    model: torch.nn.Module
    config: TrainConfig
    meta: dict
    name: ClassVar[str] = "mask3d"  # the model's registry name


def mask3d_from_checkpoint(ckpt: Checkpoint, device: str = "cpu") -> LoadedMask3D:
    """The model of a checkpoint already read (:func:`assist3d.learn.checkpoint.read_checkpoint`)."""
    cfg = parse_train_config(ckpt.config, "checkpoint config")
    model = build_model(cfg.model).to(device)
    model.load_state_dict(ckpt.state_dict)
    model.eval()
    return LoadedMask3D(model=model, config=cfg, meta=ckpt.meta)


def load_model(checkpoint: str | Path, device: str = "auto") -> tuple[torch.nn.Module, TrainConfig, str]:
    """Model (eval mode) and training config from a checkpoint written by :func:`assist3d.learn.engine.train.train`."""
    dev = resolve_device(device)
    loaded = mask3d_from_checkpoint(read_checkpoint(checkpoint, dev, model="mask3d"), dev)
    return loaded.model, loaded.config, dev


def predict_dataset(checkpoint: str | Path, spec: str, out_dir: str | Path, *, device: str = "auto",
                    overrides: dict | None = None,
                    on_scene: Callable[[str, int, int], None] | None = None) -> list[Path]:
    """Write ``<scene_id>.npz`` for every scene of ``spec`` into ``out_dir``; returns the files written.

    ``overrides``: :class:`PredictConfig` fields replacing the checkpoint config's (e.g. ``{"top_k": 50}``).
    """
    model, cfg, dev = load_model(checkpoint, device)
    pcfg = PredictConfig.model_validate({**cfg.predict.model_dump(), **(overrides or {})})
    ds = open_spec(spec)
    out = Path(out_dir)
    written = []
    for i, scene_id in enumerate(ds.scene_ids):
        safe_name(scene_id, what=f"{spec}: scene id")
        sample = ds.load(scene_id)
        pred = predict_scene(model, sample, cfg.data.voxel_size, pcfg, dev)
        path = out / f"{scene_id}.npz"
        write_npz_atomic(path, masks=pred.masks, scores=pred.scores)
        written.append(path)
        log.info("%s: %d masks over %d points", shown(scene_id), len(pred.scores), len(sample))
        if on_scene is not None:
            on_scene(scene_id, i + 1, len(ds.scene_ids))
    return written

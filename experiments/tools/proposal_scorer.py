"""A learned proposal scorer for hybrid inference, trained on generated scenes (experiments/fidelity-log.md,
"Inference variants"): measured, not adopted.

Why: with its own masks, hybrid inference would score dev AP50 0.41 instead of 0.245 if they were
ranked by their true IoU, so ranking costs more AP50 than recall does. PointGroup learns that ranking
(ScoreNet, trained to predict each proposal's IoU). This script tries the same idea without real
labels: a small MLP on 20 per-proposal features (size, extent, height, shape, foreground statistics,
how tightly the offsets vote, agreement with the network's instances), fitted on one model's
proposals on held-out generated scenes with their IoU as target, then used instead of the network's
score before non-maximum suppression.

    python experiments/tools/proposal_scorer.py MODEL.pt --train assist3d:HELD_OUT_DATA [--scenes 60]
        [--target all|scannet] [--eval array:../shared/data/real/dev --eval array:...scene0451_01.npy]
        [--out scorer.json]

``--target all`` counts every generated instance as an object; ``--target scannet`` follows the
ScanNet protocol (on-top props and structure are void, proposals mostly on void are left out of the
fit, as the evaluator ignores them). Generated scenes are thinned to ~2.5 points per occupied 5 cm
voxel like the real scans (seeded by the scene id). Prints and writes AP / AP50 / AP25 for the
default ranking, the scorer and the default's masks ranked by their true IoU (the ceiling of any
ranking), the rank correlation of each with the proposals' true IoU, and what the default's
predictions are at IoU 0.5 (true positives, ignored, duplicates, merges, partial masks).
"""

from __future__ import annotations

import argparse
import json
import zlib
from pathlib import Path

import numpy as np
import torch
from scipy.sparse import csr_matrix
from scipy.stats import spearmanr

from assist3d.data import open_dataset
from assist3d.bench.evaluation.ap import match_scene, summarize
from assist3d.core.fileio import write_json_atomic
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.cluster import mask_nms
from assist3d.learn.segmenter.features import floor_height, voxel_features, voxelize
from assist3d.learn.segmenter.geometric import segment_geometric
from assist3d.learn.segmenter.hybrid import proposals as hybrid_proposals
from assist3d.learn.segmenter.infer import instances, predict_voxels
from assist3d.learn.segmenter.superpoints import snap_masks, superpoints

NUM_FEATURES = 20
MIN_GT_POINTS = 100  # ScanNet's minimum instance size


def features(masks: np.ndarray, learned: np.ndarray, vox, fg: np.ndarray, offset: np.ndarray,
             voxel_instance: np.ndarray) -> np.ndarray:
    """(M, 20) features of point masks, computed on their 5 cm voxels (density independent)."""
    rows, cols = np.nonzero(masks)
    mv = csr_matrix((np.ones(len(rows)), (rows, vox.inverse[cols])), shape=(len(masks), len(vox.centres)))
    floor = floor_height(vox.centres)
    shifted = vox.centres + offset
    out = np.zeros((len(masks), NUM_FEATURES))
    for i in range(len(masks)):
        v = mv.indices[mv.indptr[i]:mv.indptr[i + 1]]
        n = len(v)
        c, p = vox.centres[v], fg[v]
        ext = np.sort(c.max(0) - c.min(0))[::-1]
        cc = c - c.mean(0)
        ev, vec = np.linalg.eigh(cc.T @ cc / n) if n >= 3 else (np.zeros(3), np.eye(3))
        l1, l2, l3 = np.sqrt(np.maximum(ev[::-1], 0)) + 1e-6
        sh = shifted[v]
        spread = np.sqrt(((sh - sh.mean(0)) ** 2).sum(1).mean())
        radius = np.sqrt((cc ** 2).sum(1).mean()) + 1e-6
        lab = voxel_instance[v]
        lab = lab[lab >= 0]
        purity = np.bincount(lab).max() / n if len(lab) else 0.0
        out[i] = [np.log(n), learned[i], p.mean(), p.std(), np.percentile(p, 10), np.percentile(p, 90),
                  (p > 0.5).mean(), *np.log(ext + 0.05), c[:, 2].min() - floor, c[:, 2].max() - floor,
                  (l1 - l2) / l1, (l2 - l3) / l1, l3 / l1, abs(vec[2, 0]), np.log(spread + 0.01),
                  spread / radius, purity, len(lab) / n]
    return out


def proposals(loaded, coord: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Raw proposals (learned + geometric), their snapped masks, the default score and the features."""
    cfg = loaded.config
    vox = voxelize(coord, cfg.net.voxel_size, None)
    fg, off = predict_voxels(loaded.model, vox.coords, voxel_features(vox, use_color=cfg.net.use_color))
    inst = instances(vox, fg, off, cfg.cluster)
    comps = segment_geometric(coord).masks
    masks, score = hybrid_proposals(inst, vox, fg, comps)  # exactly what `assist3d segment` ranks
    learned = np.concatenate([np.ones(len(inst.masks)), np.zeros(len(comps))])
    snapped = snap_masks(masks, superpoints(coord), 0.5) if len(masks) else masks
    ok = snapped.sum(1) > 0
    vlab = np.full(len(vox.centres), -1)
    vlab[vox.inverse] = inst.labels
    feats = features(snapped[ok], learned[ok], vox, fg, off.astype(np.float64), vlab)
    return masks[ok], snapped[ok], score[ok], feats


def classify(masks: np.ndarray, scores: np.ndarray, instance: np.ndarray) -> dict[str, int]:
    """What each prediction (>= 100 points) is at IoU 0.5, in score order: a true positive, ignored
    (mostly void), a duplicate of a matched object, a merge (>= 30 % of two objects), a partial mask
    (more than half of it on one object, IoU <= 0.5) or other."""
    masks = masks[np.argsort(-scores, kind="stable")]
    masks = masks[masks.sum(1) >= MIN_GT_POINTS]
    ids, counts = np.unique(instance[instance >= 0], return_counts=True)
    gt = np.stack([instance == i for i in ids[counts >= MIN_GT_POINTS]])
    out = {k: 0 for k in ("true_positive", "ignored", "duplicate", "merge", "partial", "other")}
    matched: set[int] = set()
    for m in masks:
        inter = (gt & m).sum(1)
        iou = inter / (gt | m).sum(1)
        j = int(iou.argmax())
        if iou[j] > 0.5 and j not in matched:
            matched.add(j)
            kind = "true_positive"
        elif (m & (instance < 0)).sum() > 0.5 * m.sum():
            kind = "ignored"
        elif iou[j] > 0.5:
            kind = "duplicate"
        elif (inter / gt.sum(1) > 0.3).sum() >= 2:
            kind = "merge"
        else:
            kind = "partial" if inter.max() > 0.5 * m.sum() else "other"
        out[kind] += 1
    return out


def best_iou(masks: np.ndarray, instance: np.ndarray) -> np.ndarray:
    best = np.zeros(len(masks))
    ids, counts = np.unique(instance[instance >= 0], return_counts=True)
    for i in ids[counts >= MIN_GT_POINTS]:
        g = instance == i
        best = np.maximum(best, (masks & g).sum(1) / np.maximum((masks | g).sum(1), 1))
    return best


class Scorer(torch.nn.Module):
    def __init__(self, mean: np.ndarray, std: np.ndarray, hidden: int = 32):
        super().__init__()
        self.register_buffer("mean", torch.tensor(mean, dtype=torch.float32))
        self.register_buffer("std", torch.tensor(std + 1e-6, dtype=torch.float32))
        self.net = torch.nn.Sequential(torch.nn.Linear(NUM_FEATURES, hidden), torch.nn.ReLU(),
                                       torch.nn.Linear(hidden, hidden), torch.nn.ReLU(), torch.nn.Linear(hidden, 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net((x - self.mean) / self.std).squeeze(-1)

    def score(self, feats: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return torch.sigmoid(self(torch.tensor(feats, dtype=torch.float32))).numpy().astype(np.float64)


def fit(feats: np.ndarray, iou: np.ndarray, seed: int = 0, iters: int = 3000) -> Scorer:
    torch.manual_seed(seed)
    model = Scorer(feats.mean(0), feats.std(0))
    x, y = torch.tensor(feats, dtype=torch.float32), torch.tensor(iou, dtype=torch.float32)
    opt = torch.optim.Adam(model.parameters(), 3e-3, weight_decay=1e-4)
    for _ in range(iters):
        loss = torch.nn.functional.binary_cross_entropy_with_logits(model(x), y)
        opt.zero_grad()
        loss.backward()
        opt.step()
    return model


def training_set(loaded, spec: str, scenes: int, target: str) -> tuple[np.ndarray, np.ndarray]:
    ds = open_dataset(spec)
    feats, ious = [], []
    for sid in ds.scene_ids[:scenes]:
        s = ds.load(sid)
        coord, inst = s.coord.astype(np.float32), np.asarray(s.instance)
        keep_p = min(1.0, 2.5 * len(voxelize(coord, 0.05).counts) / len(coord))
        keep = np.random.default_rng(zlib.crc32(sid.encode())).random(len(coord)) < keep_p
        coord, inst = coord[keep], inst[keep]
        _, snapped, _, f = proposals(loaded, coord)
        if target == "scannet":  # on-top props are void in ScanNet's 20-class ground truth
            layout = json.loads((Path(ds.root) / sid / "layout.json").read_text())
            props = [d["id"] for d in layout["instances"] if d["group"] == "obj"]
            inst = np.where(np.isin(inst, props), -1, inst)
            void = (snapped & (inst < 0)).sum(1) / np.maximum(snapped.sum(1), 1)
            f, snapped = f[void <= 0.5], snapped[void <= 0.5]
        feats.append(f)
        ious.append(best_iou(snapped, inst))
        print("train", sid, len(f), flush=True)
    return np.concatenate(feats), np.concatenate(ious)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("model")
    ap.add_argument("--train", required=True, help="held-out generated scenes FORMAT:PATH")
    ap.add_argument("--scenes", type=int, default=60)
    ap.add_argument("--target", choices=("all", "scannet"), default="all")
    ap.add_argument("--eval", action="append")
    ap.add_argument("--out", type=Path, default=Path("scorer.json"))
    a = ap.parse_args()
    torch.set_num_threads(1)
    loaded = load_segmenter(a.model)
    scorer = fit(*training_set(loaded, a.train, a.scenes, a.target))
    result: dict = {"model": a.model, "train": a.train, "scenes": a.scenes, "target": a.target, "eval": {}}
    for spec in a.eval or ["array:../shared/data/real/dev", "array:../shared/data/real/scannet_scene0451_01.npy"]:
        ds = open_dataset(spec)
        rows: dict[str, list] = {"default": [], "scorer": [], "oracle_rank": []}
        kinds: dict[str, int] = {}
        corr: dict[str, list] = {"default": [], "scorer": [], "iou": []}
        for sid in ds.scene_ids:
            s = ds.load(sid)
            masks, snapped, default, f = proposals(loaded, s.coord.astype(np.float32))
            learned = scorer.score(f)
            keep = mask_nms(masks, default, 0.5)  # the shipped recipe: NMS on raw masks, then snap
            rows["default"].append(match_scene(s.instance, snapped[keep], default[keep], valid=s.valid, scene_id=sid))
            gt = s.instance if s.valid is None else np.where(s.valid, s.instance, -1)
            true_iou = best_iou(snapped, gt)  # of every proposal, once
            # the default's masks ranked by their true IoU: what ranking alone could gain
            rows["oracle_rank"].append(match_scene(s.instance, snapped[keep], true_iou[keep] + 1e-3 * default[keep],
                                                   valid=s.valid, scene_id=sid))
            for k, n in classify(snapped[keep], default[keep], gt).items():
                kinds[k] = kinds.get(k, 0) + n
            keep = mask_nms(snapped, learned, 0.5)
            rows["scorer"].append(match_scene(s.instance, snapped[keep], learned[keep], valid=s.valid, scene_id=sid))
            corr["default"].append(default)
            corr["scorer"].append(learned)
            corr["iou"].append(true_iou)
        iou = np.concatenate(corr["iou"])
        corr["oracle_rank"] = corr["iou"]
        result["eval"][spec] = {k: {m: round(float(summarize(v)[m]), 3) for m in ("AP", "AP50", "AP25")}
                                | {"spearman_iou": round(float(spearmanr(np.concatenate(corr[k]), iou)[0]), 3)}
                                for k, v in rows.items()}
        result["eval"][spec]["default_predictions"] = kinds
        print(spec, json.dumps(result["eval"][spec]), flush=True)
    write_json_atomic(a.out, result)


if __name__ == "__main__":
    main()

# Does the geometric reference's RANSAC plane removal find the real wall/floor voxels that the network
# calls object? Per model: share of true wall+floor 5 cm voxels on a RANSAC structural plane (recall),
# share of plane voxels that are annotated objects (object loss), and learned AP50 with the plane voxels
# removed from the foreground (against base and the true wall+floor removed).
#   python planefg.py MODEL.pt [MODEL.pt ...]
import sys

import numpy as np
import torch

from assist3d.data import open_dataset
from assist3d.bench.evaluation.ap import match_scene, summarize
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.cluster import instance_score, point_masks, radius_components
from assist3d.learn.segmenter.features import voxel_features, voxelize
from assist3d.learn.segmenter.geometric import GeometricConfig, remove_planes
from assist3d.learn.segmenter.infer import predict_voxels

torch.set_num_threads(1)
SPECS = ["array:../shared/data/real/dev", "array:../shared/data/real/scannet_scene0451_01.npy"]


def group(vox, fgp, keep, radius, min_vox, off):
    labels = np.full(len(vox.centres), -1, np.int64)
    rows = np.flatnonzero(keep)
    if len(rows) == 0:
        return np.zeros((0, len(vox.inverse)), bool), np.zeros(0)
    labels[rows] = radius_components(vox.centres[rows] + off[rows], radius)
    ids, sizes = np.unique(labels[rows], return_counts=True)
    ids, sizes = ids[sizes >= min_vox], sizes[sizes >= min_vox]
    scores = np.array([instance_score(fgp[labels == i].mean(), n) for i, n in zip(ids, sizes)])
    remap = np.full(labels.max() + 2, -1)
    remap[ids] = np.arange(len(ids))
    lab = np.where(labels >= 0, remap[np.maximum(labels, 0)], -1)
    return point_masks(lab, vox.inverse, len(ids)), scores


planes = {}
for spec in SPECS:
    ds = open_dataset(spec)
    for sid in ds.scene_ids:
        s = ds.load(sid)
        xyz = s.coord.astype(np.float32)
        g = GeometricConfig()
        v2 = voxelize(xyz, g.voxel_size)
        onp = remove_planes(v2.centres, g, np.random.default_rng(g.seed))[v2.inverse]
        planes[sid] = (s, onp)

for path in sys.argv[1:]:
    model = load_segmenter(path)
    cfg = model.config
    for spec in SPECS:
        ds = open_dataset(spec)
        res = {k: [] for k in ("base", "no-planes", "no-true-wall-floor")}
        rec, objloss, fgwall, fgwall_after = [], [], [], []
        for sid in ds.scene_ids:
            s, onp = planes[sid]
            inst = np.where(s.valid, s.instance, -1) if s.valid is not None else s.instance
            xyz = s.coord.astype(np.float32)
            vox = voxelize(xyz, cfg.net.voxel_size, None, inst)
            seg = voxelize(xyz, cfg.net.voxel_size, None, s.segment.astype(np.int64)).instance
            nv = len(vox.centres)
            plane_share = np.bincount(vox.inverse, onp.astype(float), nv) / np.bincount(vox.inverse, minlength=nv)
            plane = plane_share > 0.5
            struct = (seg == 0) | (seg == 1)
            obj = vox.instance >= 0
            fgp, off = predict_voxels(model.model, vox.coords, voxel_features(vox, use_color=cfg.net.use_color))
            mfg = fgp > cfg.cluster.fg_threshold
            rec.append((plane & struct).sum() / max(struct.sum(), 1))
            objloss.append((plane & obj).sum() / max(obj.sum(), 1))
            wall = seg == 0
            fgwall.append((mfg & wall).sum() / max(wall.sum(), 1))
            fgwall_after.append((mfg & wall & ~plane).sum() / max(wall.sum(), 1))
            for k, keep in {"base": mfg, "no-planes": mfg & ~plane, "no-true-wall-floor": mfg & ~struct}.items():
                m, sc = group(vox, fgp, keep, cfg.cluster.radius, cfg.cluster.min_voxels, off)
                res[k].append(match_scene(s.instance, m, sc, valid=s.valid, scene_id=sid))
        print(path.split("/")[-3:], spec.split("/")[-1],
              f"plane recall of wall+floor {np.mean(rec):.2f}, objects on planes {np.mean(objloss):.3f},",
              f"wall called fg {np.mean(fgwall):.2f} -> {np.mean(fgwall_after):.2f} after planes,",
              " ".join(f"{k} {summarize(v)['AP50']:.3f}" for k, v in res.items()), flush=True)

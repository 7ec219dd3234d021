# Where a model's learned instances lose AP50 on real scans: its foreground and offsets as they are
# ("base"), then with the ground truth substituted for parts of them: the foreground ("gt-fg"), the
# true wall and floor voxels removed from the foreground ("no-wall-floor"), the unannotated (void)
# voxels removed ("no-void"), the voxels next to a voxel of another object cut before linking and joined
# to the nearest kept voxel's instance afterwards ("gt-boundary", "gt-fg+boundary"), and the true offsets
# ("gt-fg+offsets", the ceiling of the grouping). Linking, scoring and sizes as in cluster.py.
#   python oracle.py MODEL.pt array:../shared/data/real/scannet_scene0451_01.npy array:../shared/data/real/dev
import sys

import numpy as np
import torch
from scipy.spatial import cKDTree

from assist3d.data import open_dataset
from assist3d.bench.evaluation.ap import match_scene, summarize
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.cluster import instance_score, point_masks, radius_components
from assist3d.learn.segmenter.features import voxel_features, voxelize
from assist3d.learn.segmenter.infer import predict_voxels

torch.set_num_threads(1)


def group(vox, fgp, keep, off, cut, radius=0.07, min_vox=6):
    labels = np.full(len(vox.centres), -1, np.int64)
    rows = np.flatnonzero(keep & ~cut)
    if len(rows) == 0:
        return np.zeros((0, len(vox.inverse)), bool), np.zeros(0)
    comp = radius_components(vox.centres[rows] + off[rows], radius)
    labels[rows] = comp
    rest = np.flatnonzero(keep & cut)
    if len(rest):
        d, j = cKDTree(vox.centres[rows]).query(vox.centres[rest], k=1, distance_upper_bound=0.1)
        ok = np.isfinite(d)
        labels[rest[ok]] = comp[j[ok]]
    ids = np.unique(labels[labels >= 0])
    sizes = np.array([(labels == i).sum() for i in ids])
    ids, sizes = ids[sizes >= min_vox], sizes[sizes >= min_vox]
    scores = np.array([instance_score(fgp[labels == i].mean(), n) for i, n in zip(ids, sizes)])
    remap = np.full(labels.max() + 2, -1)
    remap[ids] = np.arange(len(ids))
    lab = np.where(labels >= 0, remap[np.maximum(labels, 0)], -1)
    return point_masks(lab, vox.inverse, len(ids)), scores


def boundary(vox):
    """Object voxels with a voxel of another object in their 26-neighbourhood."""
    inst = vox.instance
    rows = np.flatnonzero(inst >= 0)
    pairs = cKDTree(vox.coords[rows].astype(float)).query_pairs(1.8, output_type="ndarray")
    a, b = rows[pairs[:, 0]], rows[pairs[:, 1]]
    diff = inst[a] != inst[b]
    out = np.zeros(len(inst), bool)
    out[a[diff]] = out[b[diff]] = True
    return out


model = load_segmenter(sys.argv[1])
size = model.config.net.voxel_size
for spec in sys.argv[2:]:
    ds = open_dataset(spec)
    res = {k: [] for k in ("base", "gt-fg", "no-wall-floor", "no-void", "gt-boundary", "gt-fg+boundary", "gt-fg+offsets")}
    for sid in ds.scene_ids:
        s = ds.load(sid)
        inst = np.where(s.valid, s.instance, -1) if s.valid is not None else s.instance
        xyz = s.coord.astype(np.float32)
        vox = voxelize(xyz, size, None, inst)
        seg = voxelize(xyz, size, None, s.segment.astype(np.int64)).instance  # ScanNet-20 index, -1 void
        fgp, off = predict_voxels(model.model, vox.coords, voxel_features(vox, use_color=model.config.net.use_color))
        mfg, gfg = fgp > model.config.cluster.fg_threshold, vox.instance >= 0
        struct = (seg == 0) | (seg == 1)  # wall, floor
        bnd, none = boundary(vox), np.zeros(len(vox.centres), bool)
        toff = np.zeros_like(off)
        _, loc = np.unique(vox.instance[gfg], return_inverse=True)
        cen = np.stack([np.bincount(loc, vox.centres[gfg, k]) / np.bincount(loc) for k in range(3)], 1)
        toff[gfg] = cen[loc] - vox.centres[gfg]
        cases = {"base": (mfg, off, none), "gt-fg": (gfg, off, none), "no-wall-floor": (mfg & ~struct, off, none),
                 "no-void": (mfg & (struct | gfg), off, none), "gt-boundary": (mfg, off, bnd),
                 "gt-fg+boundary": (gfg, off, bnd), "gt-fg+offsets": (gfg, toff, none)}
        for k, (keep, o, cut) in cases.items():
            masks, scores = group(vox, fgp, keep, o, cut, model.config.cluster.radius, model.config.cluster.min_voxels)
            res[k].append(match_scene(s.instance, masks, scores, valid=s.valid, scene_id=sid))
    print(spec.split("/")[-1], " ".join(f"{k} {summarize(v)['AP50']:.3f}" for k, v in res.items()), flush=True)

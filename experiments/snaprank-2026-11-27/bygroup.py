# After the decision (not part of the rule): hybrid AP50 with and without snap_rank, scored on two
# groups of real objects apart: flat objects in or on the walls (ScanNet-20 door, window, picture)
# and all the others. Each group is scored with the other group's points set void, so predictions on
# them are ignored as the protocol ignores predictions on void.
#   python bygroup.py MODEL.pt [MODEL.pt ...] --eval array:../shared/data/real/dev --eval array:...0451_01.npy
import argparse

import numpy as np
import torch

from assist3d.data import open_dataset
from assist3d.bench.evaluation.ap import match_scene, summarize
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.features import voxelize
from assist3d.learn.segmenter.geometric import segment_geometric, structural_points
from assist3d.learn.segmenter.hybrid import HybridConfig, combine
from assist3d.learn.segmenter.infer import instances, predict_scan
from assist3d.learn.segmenter.superpoints import superpoints

IN_WALL = (7, 8, 10)  # ScanNet-20 index (the array reader's `segment`): door, window, picture
torch.set_num_threads(1)
ap = argparse.ArgumentParser()
ap.add_argument("models", nargs="+")
ap.add_argument("--eval", action="append")
a = ap.parse_args()
scans = []
for g, spec in enumerate(a.eval):
    ds = open_dataset(spec)
    for sid in ds.scene_ids:
        s = ds.load(sid)
        on_plane = structural_points(s.coord)
        sem = np.asarray(s.segment)
        in_wall = np.isin(sem, IN_WALL)
        counted = s.instance[(s.instance >= 0) & (s.valid if s.valid is not None else True)]
        ids, sizes = np.unique(counted, return_counts=True)
        objects = set(ids[sizes >= 100].tolist())  # the protocol's objects (>= 100 points)
        n_obj = {k: len(objects & set(np.unique(s.instance[m]).tolist())) for k, m in (("in_wall", in_wall), ("other", ~in_wall))}
        scans.append((g, sid, s, segment_geometric(s.coord, on_plane=on_plane).masks, superpoints(s.coord), in_wall, n_obj))
for g in range(len(a.eval)):
    print(a.eval[g], "objects in_wall / other:", sum(x[6]["in_wall"] for x in scans if x[0] == g), "/",
          sum(x[6]["other"] for x in scans if x[0] == g))
for path in a.models:
    m = load_segmenter(path)
    res = {}
    for g, sid, s, comps, segs, in_wall, _ in scans:
        vox = voxelize(s.coord.astype(np.float32), m.config.net.voxel_size, s.color)
        fg, off = predict_scan(m.model, m.config, s.coord, s.color, vox)
        inst = instances(vox, fg, off, m.config.cluster)
        valid = s.valid if s.valid is not None else np.ones(len(s.coord), bool)
        for name, cfg in (("hybrid", HybridConfig()), ("snap_rank", HybridConfig(snap_rank=True))):
            h = combine(inst, vox, fg, off, m.config.cluster, comps, segs, hybrid=cfg)
            for group, keep in (("in_wall", in_wall), ("other", ~in_wall)):
                res.setdefault((g, name, group), []).append(
                    match_scene(s.instance, h.masks, h.scores, valid=valid & keep, scene_id=sid))
    print(path)
    for g in range(len(a.eval)):
        cells = []
        for group in ("in_wall", "other"):
            v = [summarize(res[(g, name, group)])["AP50"] for name in ("hybrid", "snap_rank")]
            cells.append(f"{group} {v[0]:.3f} -> {v[1]:.3f}")
        print(f"  {a.eval[g].split('/')[-1]}: " + ", ".join(cells))

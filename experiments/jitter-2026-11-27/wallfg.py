# Share of the real scans' voxels (5 cm) that a model calls foreground, by ground-truth kind (wall, floor,
# void = unannotated or another class, object) and, for walls and floors, by the distance to the nearest
# object voxel.
#   python wallfg.py MODEL.pt [MODEL.pt ...] --eval array:../shared/data/real/dev
import argparse
import collections

import numpy as np
import torch
from scipy.spatial import cKDTree

from assist3d.data import open_dataset
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.features import voxel_features, voxelize
from assist3d.learn.segmenter.infer import predict_voxels

torch.set_num_threads(1)
ap = argparse.ArgumentParser()
ap.add_argument("models", nargs="+")
ap.add_argument("--eval", default="array:../shared/data/real/dev")
a = ap.parse_args()
BINS = ((0, .1), (.1, .3), (.3, 1), (1, 99))
for path in a.models:
    m = load_segmenter(path)
    size = m.config.net.voxel_size
    agg = collections.defaultdict(lambda: [0, 0])
    ds = open_dataset(a.eval)
    for sid in ds.scene_ids:
        s = ds.load(sid)
        inst = np.where(s.valid, s.instance, -1) if s.valid is not None else s.instance
        xyz = s.coord.astype(np.float32)
        vox = voxelize(xyz, size, None, inst)
        seg = voxelize(xyz, size, None, s.segment.astype(np.int64)).instance
        fg, _ = predict_voxels(m.model, vox.coords, voxel_features(vox, use_color=m.config.net.use_color))
        fg = fg > m.config.cluster.fg_threshold
        obj = vox.instance >= 0
        d = cKDTree(vox.centres[obj]).query(vox.centres, k=1)[0]
        for name, k in (("wall", seg == 0), ("floor", seg == 1), ("void", (seg == -1) & ~obj), ("object", obj)):
            agg[(name, "all")][0] += int(k.sum()); agg[(name, "all")][1] += int(fg[k].sum())
            if name in ("wall", "floor"):
                for lo, hi in BINS:
                    kk = k & (d >= lo) & (d < hi)
                    agg[(name, f"{lo}-{hi} m")][0] += int(kk.sum()); agg[(name, f"{lo}-{hi} m")][1] += int(fg[kk].sum())
    print(path, "| " + " | ".join(f"{n} {b}: {f / max(c, 1):.2f}" for (n, b), (c, f) in agg.items()), flush=True)

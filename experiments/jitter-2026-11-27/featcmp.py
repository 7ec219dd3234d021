# Input features (features.py, 5 cm voxels) of augmented training examples against real scans: 10/50/90 %
# quantiles of |n_z|, planarity and scattering on wall-like background voxels (training: background with
# |n_z| < 0.3 more than 10 cm above the floor; real: voxels labelled wall) and on object voxels, for the
# default training jitter and for smaller ones.
#   python featcmp.py assist3d:DATA/assist3d array:../shared/data/real/dev
import sys

import numpy as np

from assist3d.data import open_dataset
from assist3d.learn.segmenter.config import SegmenterConfig
from assist3d.learn.segmenter.data import Scene, make_example
from assist3d.learn.segmenter.features import voxel_features, voxelize


def q(a):
    return " ".join(f"{v:.2f}" for v in np.percentile(a, [10, 50, 90]))


def show(name, wall, obj):
    print(f"{name:32s} wall |nz| {q(wall[:, 2])}  planarity {q(wall[:, 4])}  scattering {q(wall[:, 5])} || "
          f"object |nz| {q(obj[:, 2])}  planarity {q(obj[:, 4])}  scattering {q(obj[:, 5])}")


train_spec, real_spec = sys.argv[1], sys.argv[2]
ds = open_dataset(real_spec)
wall, obj = [], []
for sid in ds.scene_ids:
    s = ds.load(sid)
    vox = voxelize(s.coord.astype(np.float32), 0.05, None, s.segment.astype(np.int64))
    f = voxel_features(vox, use_color=False)
    wall.append(f[vox.instance == 0])
    obj.append(f[vox.instance >= 2])
show("real scans", np.concatenate(wall), np.concatenate(obj))
ds = open_dataset(train_spec)
scenes = [Scene.from_sample(ds.load(sid)) for sid in ds.scene_ids[:8]]
for jitter in ((0.005, 0.02), (0.0, 0.005), (0.0, 0.0)):
    cfg = SegmenterConfig.model_validate({"augment": {"jitter": jitter}})
    wall, obj = [], []
    for i, sc in enumerate(scenes):
        e = make_example(sc, cfg, np.random.default_rng(i))
        f = e.feats
        wall.append(f[(e.fg < 0.5) & (f[:, 2] < 0.3) & (f[:, 1] * 2 > 0.1)])
        obj.append(f[e.fg > 0.5])
    show(f"training, jitter sigma {jitter[0]}-{jitter[1]} m", np.concatenate(wall), np.concatenate(obj))

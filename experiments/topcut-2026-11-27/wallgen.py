# The diagnostic named in rule-topcut.md (no training): python wallgen.py MODEL.pt[,MODEL.pt] assist3d:DATA/assist3d
# Which property of real scans makes walls look like objects? A model's foreground rate on the wall-like
# background voxels of generated scenes, as rendered and after removing the ceiling, cutting everything
# above a height, or both.
import sys, numpy as np, torch
torch.set_num_threads(2)
from assist3d.data import open_dataset
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.features import voxel_features, voxelize, shape_features
from assist3d.learn.segmenter.infer import predict_voxels
ds = open_dataset(sys.argv[2])
models = [load_segmenter(p) for p in sys.argv[1].split(",")]
rng = np.random.default_rng(0)
res = {}
for sid in ds.scene_ids[-6:]:
    s = ds.load(sid)
    xyz = s.coord.astype(np.float32); inst = s.instance.astype(np.int64)
    keep = rng.random(len(xyz)) < 0.4
    xyz, inst = xyz[keep], inst[keep]
    floor = np.percentile(xyz[:, 2], 2); top = np.percentile(xyz[:, 2], 99.5)
    vox0 = voxelize(xyz, 0.05, None, inst)
    nz = shape_features(vox0.centres)[:, 0]
    pnz = nz[vox0.inverse]
    ceiling = (inst < 0) & (xyz[:, 2] > top - 0.15) & (pnz > 0.7)
    variants = {"as rendered": np.ones(len(xyz), bool), "no ceiling": ~ceiling,
                "cut at 2.0 m": xyz[:, 2] < floor + 2.0, "cut at 1.5 m": xyz[:, 2] < floor + 1.5,
                "no ceiling, walls 50 % holes": ~ceiling}
    for name, m in variants.items():
        if "holes" in name:
            # drop wall points in random 0.5 m cells
            cell = np.floor(xyz[:, :3] / 0.5).astype(np.int64)
            h = (cell[:, 0] * 73856093 ^ cell[:, 1] * 19349663 ^ cell[:, 2] * 83492791) % 2 == 0
            m = m & ~((inst < 0) & (pnz < 0.3) & h)
        v = voxelize(xyz[m], 0.05, None, inst[m])
        f = voxel_features(v, use_color=False)
        wall = (v.instance < 0) & (f[:, 2] < 0.3) & (f[:, 1] * 2 > 0.1)
        for mi, mod in enumerate(models):
            fg, _ = predict_voxels(mod.model, v.coords, f)
            r = res.setdefault((mi, name), [0, 0, 0, 0])
            r[0] += wall.sum(); r[1] += (fg[wall] > 0.5).sum(); r[2] += (v.instance >= 0).sum(); r[3] += (fg[v.instance >= 0] > 0.5).sum()
for (mi, name), (w, wf, o, of) in res.items():
    print(f"model {mi} {name:30s} wall-like voxels called object {wf / w:.2f}   object voxels called object {of / o:.2f}")

# The diagnostic named in rule-vox4.md (run on the shipped model, 3-4 scans per set):
#   NS=3 python offdiag.py MODEL.pt array:../shared/data/real/scannet_scene0451_01.npy array:../shared/data/real/dev assist3d:DATA/assist3d
# Per ground-truth object on real / generated scans: share predicted foreground, spread of its shifted
# voxels (median distance to their median), and for neighbouring object pairs the gap between their
# shifted voxel sets (min distance) -- does a 7 cm linking radius have to merge them?
import os, sys, numpy as np, torch
torch.set_num_threads(2)
from scipy.spatial import cKDTree
from assist3d.data import open_dataset
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.features import voxelize
from assist3d.learn.segmenter.infer import predict_scan
path = sys.argv[1]
specs = sys.argv[2:]
l = load_segmenter(path)
for spec in specs:
    ds = open_dataset(spec)
    for s in (ds[i] for i in range(min(len(ds), int(os.environ.get("NS", "4"))))):
        inst = np.where(s.valid, s.instance, -1) if getattr(s, "valid", None) is not None else s.instance
        vox = voxelize(np.asarray(s.coord, np.float32), l.config.net.voxel_size, None, inst)
        fg, off = predict_scan(l.model, l.config, s.coord, None, vox)
        vi = vox.instance
        gts = [g for g in np.unique(vi) if g >= 0 and (vi == g).sum() >= 10]
        spread, fgs, cents, sh, raw = [], [], [], {}, []
        for g in gts:
            m = (vi == g)
            fgs.append((fg[m] > 0.5).mean())
            p = vox.centres[m] + off[m]
            mm = m & (fg > 0.5)
            pm = vox.centres[mm] + off[mm]
            sh[g] = pm
            c = np.median(p, 0)
            spread.append(np.median(np.linalg.norm(p - c, axis=1)))
            q = vox.centres[m]
            raw.append(np.median(np.linalg.norm(q - np.median(q, 0), axis=1)))
        # neighbouring pairs: original voxel sets within 10 cm
        trees = {g: cKDTree(vox.centres[vi == g]) for g in gts}
        gaps, touching = [], 0
        for i, a in enumerate(gts):
            for b in gts[i + 1:]:
                d = trees[a].query(vox.centres[vi == b], k=1)[0].min()
                if d < 0.1:
                    touching += 1
                    if len(sh[a]) and len(sh[b]):
                        gaps.append(cKDTree(sh[a]).query(sh[b], k=1)[0].min())
        gaps = np.array(gaps)
        bg = vi < 0
        print(f"{spec.split('/')[-1][:30]:30s} {s.scene_id[:22]:22s} objs {len(gts):3d} fg-on-obj {np.median(fgs):.2f} "
              f"fg-on-bg {(fg[bg] > 0.5).mean():.2f} spread {np.median(spread):.3f} unshifted {np.median(raw):.3f} shrink {np.median(np.array(spread) / np.maximum(raw, 1e-6)):.2f} touching-pairs {touching:3d} "
              f"shifted-gap<7cm {np.mean(gaps < 0.07) if len(gaps) else float('nan'):.2f} median-gap {np.median(gaps) if len(gaps) else float('nan'):.3f}")

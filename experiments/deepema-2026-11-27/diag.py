# Learned masks of a model on scene0451_01 and scene0008_00: for each ground-truth object, the predicted mask
# that overlaps it most; medians of (share of the object it holds, share of it that is the object).
#   REAL=../shared/data/real python diag.py MODEL.pt [MODEL.pt ...]
import os, sys, numpy as np, torch
torch.set_num_threads(1)
from assist3d.data import open_dataset
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.infer import segment_points
for path in sys.argv[1:]:
    l = load_segmenter(path)
    real = os.environ.get("REAL", "../shared/data/real")
    for spec in [f"array:{real}/scannet_scene0451_01.npy", f"array:{real}/dev/scene0008_00.npy"]:
        s = open_dataset(spec)[0]
        r = segment_points(l.model, l.config, s.coord, s.color)
        masks = r.masks
        inst = np.where(s.valid, s.instance, -1) if s.valid is not None else s.instance
        gts = [g for g in np.unique(inst) if g >= 0 and (inst == g).sum() >= 1]
        best, cover = [], []
        for g in gts:
            gm = inst == g
            inter = (masks & gm).sum(1); union = (masks | gm).sum(1)
            iou = inter / np.maximum(union, 1)
            k = int(iou.argmax()) if len(iou) else -1
            best.append(iou.max() if len(iou) else 0)
            cover.append((inter[k] / gm.sum(), inter[k] / max(masks[k].sum(), 1)) if k >= 0 else (0, 0))
        best = np.array(best); cover = np.array(cover)
        print(path.split('/')[-2] if 'seed' in path else path, spec.split('/')[-1], "N", len(s.coord), "gt", len(gts), "pred", len(masks),
              "bestIoU>0.5", int((best > 0.5).sum()), ">0.25", int((best > 0.25).sum()),
              "median recall-of-gt", np.round(np.median(cover[:, 0]), 2), "median precision", np.round(np.median(cover[:, 1]), 2),
              "fg-pts", int(masks.any(0).sum()), "gt-obj-pts", int((inst >= 0).sum()))

"""Objects of each ScanNet class matched by a model's own instances (`--method learned`) on the real scans: the count
behind plan.md's "5 of the 33 doors" (IoU >= 0.5 and >= 0.25; objects of >= 100 points, classes 3-20).

    PYTHONPATH=src python experiments/openings2000/class_recall.py [MODEL.pt]     (default: the shipped model)
"""

from __future__ import annotations

import collections
import sys
from pathlib import Path

import numpy as np

from assist3d.core.taxonomy.scannet import SCANNET20_NAMES
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.predictor import Predictor
from assist3d.learn.segmenter.shipped import shipped_model_path

#: the scans' class column is the ScanNet-20 index + 1; the objects are the classes after wall and floor
CLASSES = {i + 1: name for i, name in enumerate(SCANNET20_NAMES) if name not in ("wall", "floor")}
SCANS = sorted(Path("../shared/data/real/dev").glob("*.npy")) + [Path("../shared/data/real/scannet_scene0451_01.npy")]


def main() -> None:
    model = Path(sys.argv[1]) if len(sys.argv) > 1 else shipped_model_path()
    pred = Predictor(load_segmenter(model), "learned")
    total, at50, at25 = collections.Counter(), collections.Counter(), collections.Counter()
    for path in SCANS:
        a = np.load(path)  # (N, 8): xyz, rgb, class + 1, instance + 1 (the dev README)
        masks = pred.segment(a[:, :3], a[:, 3:6].astype(np.uint8), name=path.stem, where=str(path)).masks
        for inst in np.unique(a[:, 7]):
            on = a[:, 7] == inst
            cls = int(np.bincount(a[on, 6].astype(np.int64)).argmax())
            if inst == 0 or cls not in CLASSES or on.sum() < 100:
                continue
            inter = (masks & on).sum(1)
            iou = inter / np.maximum(masks.sum(1) + on.sum() - inter, 1)
            best = float(iou.max()) if len(iou) else 0.0
            name = CLASSES[cls]
            total[name] += 1
            at50[name] += best >= 0.5
            at25[name] += best >= 0.25
    print(f"model {model}")
    for name, n in total.most_common():
        print(f"{name:15s} {n:4d} objects, matched at IoU 0.5: {at50[name]:3d}, at IoU 0.25: {at25[name]:3d}")
    print(f"{'all':15s} {sum(total.values()):4d} objects, matched at IoU 0.5: {sum(at50.values()):3d}, "
          f"at IoU 0.25: {sum(at25.values()):3d}")


if __name__ == "__main__":
    main()

"""Where hybrid inference loses real objects (experiments/fidelity-log.md, "Fallback proposals"): every ground-truth
object of the real scans, classified by the prediction that overlaps it best.

    python experiments/tools/fallback_diagnosis.py [--checkpoint MODEL.pt] [--recipe first|default|learned]
        [--eval array:../shared/data/real/dev] [--json out.json]

Per object (>= 100 points, ScanNet protocol): ``matched`` (IoU > 0.5), ``partial`` (the best mask lies
mostly on the object, precision > 0.5, but covers too little), ``merged`` (best IoU above 0.1, the
mask also holds other objects or structure), ``inside-others`` (at least half of it lies in masks
of other objects) or ``uncovered``. For the unmatched objects it also counts how many the union of
the masks lying mostly on them (precision > 0.5) would match: what joining fragments could gain.
``--recipe first`` is hybrid inference without the fallback proposals (the recipe these figures
were first taken with), ``default`` what ``assist3d segment`` does, ``learned`` the network's own
instances (what ``assist3d probe`` scores).
"""

from __future__ import annotations

import argparse
import collections
import json

import numpy as np
import torch

from assist3d.data import open_dataset
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.hybrid import HybridConfig, segment_hybrid
from assist3d.learn.segmenter.infer import segment_points
from assist3d.learn.segmenter.shipped import shipped_model_path

MIN_GT_POINTS = 100  # ScanNet's minimum instance size
SCANNET20 = ("wall floor cabinet bed chair sofa table door window bookshelf picture counter desk curtain "
             "refrigerator showercurtain toilet sink bathtub otherfurniture").split()


def classify(masks: np.ndarray, obj: np.ndarray) -> tuple[str, bool]:
    """The object's category under ``masks`` (M, N) bool, and whether the union of the masks lying
    mostly on it would match it (IoU > 0.5)."""
    if len(masks) == 0:
        return "uncovered", False
    inter = (masks & obj).sum(1)
    iou = inter / (masks | obj).sum(1)
    precision = inter / np.maximum(masks.sum(1), 1)
    best = int(iou.argmax())
    mostly_on = precision > 0.5
    union = masks[mostly_on].any(0) if mostly_on.any() else np.zeros_like(obj)
    joined = bool((union & obj).sum() / (union | obj).sum() > 0.5)
    if iou[best] > 0.5:
        return "matched", joined
    if precision[best] > 0.5:
        return "partial", joined
    if iou[best] > 0.1:
        return "merged", joined
    return ("inside-others" if masks[:, obj].any(0).mean() >= 0.5 else "uncovered"), joined


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--checkpoint", default=None)
    ap.add_argument("--recipe", choices=("first", "default", "learned"), default="first")
    ap.add_argument("--eval", default="array:../shared/data/real/dev")
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    torch.set_num_threads(1)
    loaded = load_segmenter(a.checkpoint or shipped_model_path())
    recipe = HybridConfig(fallback_radius=None) if a.recipe == "first" else HybridConfig()
    ds = open_dataset(a.eval)
    counts: collections.Counter = collections.Counter()
    by_class: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    joinable = 0
    for sid in ds.scene_ids:
        s = ds.load(sid)
        if a.recipe == "learned":
            seg = segment_points(loaded.model, loaded.config, s.coord, s.color)
        else:
            seg = segment_hybrid(loaded.model, loaded.config, s.coord, s.color, hybrid=recipe)
        inst = np.where(s.valid, s.instance, -1)
        ids, n = np.unique(inst[inst >= 0], return_counts=True)
        for i in ids[n >= MIN_GT_POINTS]:
            obj = inst == i
            kind, joined = classify(seg.masks, obj)
            counts[kind] += 1
            joinable += int(joined and kind != "matched")
            labelled = s.segment[obj][s.segment[obj] >= 0]
            cls = int(np.bincount(labelled).argmax()) if len(labelled) else -1
            by_class[SCANNET20[cls] if 0 <= cls < len(SCANNET20) else "unlabelled"][kind] += 1
    unmatched = sum(counts.values()) - counts["matched"]
    out = {"objects": sum(counts.values()), "categories": dict(counts), "unmatched": unmatched,
           "unmatched_joined_by_union_of_fragments": joinable, "by_class": {k: dict(v) for k, v in by_class.items()}}
    print(json.dumps(out, indent=1))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()

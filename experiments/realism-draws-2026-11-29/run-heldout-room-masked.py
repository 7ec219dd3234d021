"""Analysis: run-heldout-room.py with scene0451_01's ceiling (instance 39) and floor-to-ceiling element (instance 1),
both label 0, read as unlabelled (found by inspection; the array format cannot name them).

    python experiments/realism-draws-2026-11-29/run-heldout-room-masked.py D0 D1 > out.json
"""
import json
import sys

import numpy as np

from assist3d.data import open_dataset
from assist3d.bench.metrics.realism import RealismReference, matched_sample, realism_score, scene_stats, stats_of_dataset

STRUCTURE = (1, 39)
s = open_dataset("array:../shared/data/real/scannet_scene0451_01.npy?objects=annotated").load("scannet_scene0451_01")
inst = np.where(np.isin(s.instance, STRUCTURE), -1, s.instance)
real = scene_stats(s.coord, inst)
ref = RealismReference.load()
score, parts, _ = realism_score(real, ref)
out = {"scene0451_01_masked": {"layout_realism": score, "components": parts, "objects": real.objects}, "matched": {}}
for root in sys.argv[1:]:
    for preset in ("assist3d", "randomrooms", "holodeck-style"):
        spec = f"assist3d:{root}/{preset}"
        st = stats_of_dataset(spec, 50)
        rng = np.random.default_rng(0)
        vals = [realism_score(matched_sample(st, real, rng), ref)[0] for _ in range(200)]
        out["matched"][spec] = {"mean": round(float(np.mean(vals)), 2), "std": round(float(np.std(vals)), 2)}
        print(spec, out["matched"][spec], file=sys.stderr)
print(json.dumps(out, indent=2))

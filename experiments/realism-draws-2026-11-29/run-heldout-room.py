"""scene0451_01 (outside the shipped reference) against the shipped reference, and the preset sets at its size.

    python experiments/realism-draws-2026-11-29/run-heldout-room.py D0 D1 > out.json
"""
import json
import sys

import numpy as np

from assist3d.bench.metrics.realism import RealismReference, matched_sample, realism_score, stats_of_dataset

real = stats_of_dataset("array:../shared/data/real/scannet_scene0451_01.npy")  # read with objects=annotated
ref = RealismReference.load()
score, parts, _ = realism_score(real, ref)
out = {"scene0451_01": {"layout_realism": score, "components": parts, "objects": real.objects}, "matched": {}}
for root in sys.argv[1:]:
    for preset in ("assist3d", "randomrooms", "holodeck-style"):
        spec = f"assist3d:{root}/{preset}"
        st = stats_of_dataset(spec, 50)
        rng = np.random.default_rng(0)  # the same draws for every dataset
        vals = [realism_score(matched_sample(st, real, rng), ref)[0] for _ in range(200)]
        out["matched"][spec] = {"mean": round(float(np.mean(vals)), 2), "std": round(float(np.std(vals)), 2)}
        print(spec, out["matched"][spec], file=sys.stderr)
print(json.dumps(out, indent=2))

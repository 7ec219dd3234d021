"""How many sites of the submanifold convolutions have all their neighbours in one axis plane (dz = 0, dy = 0 or
dx = 0)? For those, im2col over the plane's 9 kernel offsets instead of 27 would give the same output with a third
of the multiply-adds. Counts the neighbour tables of 4 default training steps.
   .venv/bin/python experiments/speed-leads-2026-12-07/plane_sites.py DATA    (an assist3d dataset folder)"""
import collections
import sys
import tempfile

import torch

import assist3d.learn.models.sparse as S
from assist3d.learn.segmenter.config import parse_segmenter_config
from assist3d.learn.segmenter.probe import load_training_scenes
from assist3d.learn.segmenter.train import Budget, train_segmenter

scenes = load_training_scenes([f"assist3d:{sys.argv[1]}"], 0)
i = torch.arange(27)  # kernel_offsets: (dx, dy, dz), dz fastest
planes = {"dz=0": (i % 3) == 1, "dy=0": ((i // 3) % 3) == 1, "dx=0": (i // 9) == 1}
acc: dict = collections.defaultdict(lambda: collections.Counter())
seen = set()
orig = S._SubMConvIm2colFn.forward


def forward(ctx, feats, weight, table, dtype):
    if id(table) not in seen:
        seen.add(id(table))
        n = table.shape[0]
        has = table != n
        left = torch.ones(n, dtype=torch.bool)
        a = acc["sets of > 20,000 sites" if n > 20000 else "smaller sets (coarser levels)"]
        a["sites"] += n
        a["neighbours"] += int(has.sum())
        for name, m in planes.items():
            ok = left & ~has[:, ~m].any(1)
            a[name] += int(ok.sum())
            left &= ~ok
    return orig(ctx, feats, weight, table, dtype)


S._SubMConvIm2colFn.forward = staticmethod(forward)
with tempfile.TemporaryDirectory() as tmp:
    train_segmenter(parse_segmenter_config({"optim": {"precision": "bfloat16"}}, "bfloat16"), scenes, tmp,
                    seed=0, budget=Budget(steps=4))
for k, a in acc.items():
    n = a["sites"]
    share = sum(a[p] for p in planes) / n
    print(f"{k}: {n} sites, occupied neighbours {a['neighbours'] / n:.1f} of 27; in one plane: "
          + ", ".join(f"{p} {a[p] / n:.3f}" for p in planes)
          + f"; multiply-adds left with 9-offset im2col for those: {1 - share + share / 3:.3f}")

"""The rate of the bfloat16 matmuls inside the im2col convolutions' forward pass (the shapes that dominate a
step), from 4 default training steps after 2 untimed ones.
   .venv/bin/python experiments/speed-leads-2026-12-07/mm_rate.py DATA    (an assist3d dataset folder)"""
import collections
import sys
import tempfile
import time

import torch
from torch.overrides import TorchFunctionMode

from assist3d.learn.segmenter.config import parse_segmenter_config
from assist3d.learn.segmenter.probe import load_training_scenes
from assist3d.learn.segmenter.train import Budget, train_segmenter

scenes = load_training_scenes([f"assist3d:{sys.argv[1]}"], 0)
cfg = parse_segmenter_config({"optim": {"precision": "bfloat16"}}, "bfloat16")
stats: dict = collections.defaultdict(lambda: [0, 0.0, 0.0])


class Count(TorchFunctionMode):
    def __torch_function__(self, func, types, args=(), kwargs=None):
        kwargs = kwargs or {}
        if func in (torch.mm, torch.Tensor.mm, torch.matmul, torch.Tensor.matmul, torch.Tensor.__matmul__):
            a, b = args[0], args[1]
            t = time.perf_counter()
            r = func(*args, **kwargs)
            s = stats[(str(a.dtype).removeprefix("torch."), a.shape[1], b.shape[1])]
            s[0] += 1
            s[1] += time.perf_counter() - t
            s[2] += 2.0 * a.shape[0] * a.shape[1] * b.shape[1]
            return r
        return func(*args, **kwargs)


with tempfile.TemporaryDirectory() as tmp:
    train_segmenter(cfg, scenes, tmp + "/warm", seed=0, budget=Budget(steps=2))
    with Count():
        train_segmenter(cfg, scenes, tmp + "/run", seed=0, budget=Budget(steps=4))
sec = sum(s[1] for s in stats.values())
flop = sum(s[2] for s in stats.values())
print(f"forward matmuls: {sec / 4:.3f} s a step, {flop / 4 / 1e9:.1f} GFLOP a step, {flop / sec / 1e9:.0f} GFLOP/s")
for (dt, k, n), s in sorted(stats.items(), key=lambda kv: -kv[1][1])[:6]:
    print(f"  {dt} (rows, {k}) @ ({k}, {n}): {s[0]} calls, {s[1] / 4 * 1e3:.1f} ms a step, {s[2] / s[1] / 1e9:.0f} GFLOP/s")

"""torch.profiler over 10 default training steps (after 3 untimed), the operators by their own CPU time.
   .venv/bin/python experiments/speed-leads-2026-12-07/op_profile.py DATA    (an assist3d dataset folder)"""
import statistics
import sys
import tempfile
import time

from torch.profiler import ProfilerActivity, profile

from assist3d.learn.segmenter.config import parse_segmenter_config
from assist3d.learn.segmenter.probe import load_training_scenes
from assist3d.learn.segmenter.train import Budget, train_segmenter

scenes = load_training_scenes([f"assist3d:{sys.argv[1]}"], 0)
cfg = parse_segmenter_config({}, "defaults")
times: list[float] = []
last = [time.perf_counter()]


def on_step(row: dict) -> None:
    now = time.perf_counter()
    times.append(now - last[0])
    last[0] = now


with tempfile.TemporaryDirectory() as tmp:
    train_segmenter(cfg, scenes, tmp + "/warm", seed=0, budget=Budget(steps=3))
    times.clear()
    last[0] = time.perf_counter()
    with profile(activities=[ProfilerActivity.CPU]) as prof:
        train_segmenter(cfg, scenes, tmp + "/run", seed=0, budget=Budget(steps=10), on_step=on_step)
print(f"seconds a step under the profiler: median {statistics.median(times[1:]):.3f} (steps 2-10)")
print(prof.key_averages().table(sort_by="self_cpu_time_total", row_limit=12))

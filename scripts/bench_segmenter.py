"""Time the CPU segmenter's training step (forward, backward, optimiser) on real batches of a dataset.

    python scripts/bench_segmenter.py --train assist3d:DATA [--steps 4] [--threads 2] [--scenes 6] [--json]

The batches are the probe's own (``build_batch``: crop, augmentation, voxelisation with the default
recipe and seed 0), built before the clock starts, so the figure is the network's share of a step; the
example building runs in the loader's workers during training (``--loader-workers``) or adds about
0.65 s per step without them (experiments/fidelity-log.md, "Cost"). One warm-up step, then the median of ``--steps``
timed steps. Compare two code versions by running it under each (for example with ``PYTHONPATH``
pointing at another checkout's ``src``) with a whole-process timer.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import torch

from assist3d.data import open_dataset
from assist3d.learn.segmenter.config import parse_segmenter_config
from assist3d.learn.segmenter.data import Scene
from assist3d.learn.segmenter.loader import build_batch
from assist3d.learn.segmenter.model import Segmenter
from assist3d.learn.segmenter.train import example_loss


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--train", required=True, help="a training set FORMAT:PATH")
    ap.add_argument("--steps", type=int, default=4, help="timed steps after one warm-up step")
    ap.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    ap.add_argument("--scenes", type=int, default=6, help="the first N scenes of the set")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    if a.steps < 1 or a.scenes < 1:
        raise SystemExit("--steps and --scenes must be at least 1")
    torch.set_num_threads(a.threads)
    scenes = []
    for sample in open_dataset(a.train):
        scenes.append(Scene.from_sample(sample))
        if len(scenes) == a.scenes:
            break
    cfg = parse_segmenter_config({}, "defaults")
    batches = [build_batch(scenes, cfg, 0, k) for k in range(a.steps + 1)]
    torch.manual_seed(0)
    model = Segmenter(cfg.net)
    opt = torch.optim.Adam(model.parameters(), lr=cfg.optim.lr)
    model.train()
    seconds, losses = [], []
    for examples in batches:
        t0 = time.perf_counter()
        opt.zero_grad(set_to_none=True)
        loss, parts = example_loss(model, examples, cfg, "cpu")
        loss.backward()
        opt.step()
        seconds.append(time.perf_counter() - t0)
        losses.append(round(parts["loss"], 6))
    voxels = [sum(len(e.coords) for e in b) for b in batches]
    out = {"train": a.train, "threads": a.threads, "steps_timed": a.steps,
           "seconds_per_step_median": round(statistics.median(seconds[1:]), 3),
           "seconds_per_step": [round(s, 3) for s in seconds[1:]], "warmup_seconds": round(seconds[0], 3),
           "voxels_per_step": voxels[1:], "losses": losses, "torch": torch.__version__}
    if a.json:
        print(json.dumps(out))
    else:
        print(f"{out['seconds_per_step_median']:.3f} s per training step (median of {a.steps}, {a.threads} "
              f"threads, {statistics.mean(voxels[1:]):,.0f} voxels per step); losses {losses}")


if __name__ == "__main__":
    main()

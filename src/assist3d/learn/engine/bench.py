"""Model benchmark: forward and forward+backward time and peak memory on one synthetic scene.

The scene is a toy room (:func:`assist3d.learn.engine.toy.make_toy_scene`) subsampled to exactly
``points`` points and voxelised at the config's voxel size. Forward runs in eval mode under
``no_grad``; forward+backward runs in train mode with the full matched loss. Peak memory: CUDA's
``max_memory_allocated`` on a GPU; on the CPU the growth of the process's peak resident set size
(``ru_maxrss``) during the run, an upper bound that includes allocator slack.
"""

from __future__ import annotations

import resource
import statistics
import sys
import time
from dataclasses import asdict, dataclass

import numpy as np
import torch

from .config import TrainConfig
from .losses import scene_loss
from .toy import make_toy_scene
from .train import build_model, resolve_device
from .voxelize import collate, instance_masks, voxelize


@dataclass(frozen=True)
class BenchResult:
    points: int
    voxels: int
    backend: str
    device: str
    threads: int
    parameters: int
    forward_s: float
    forward_backward_s: float | None
    forward_peak_mib: float
    forward_backward_peak_mib: float | None
    repeats: int
    note: str = ""

    def as_dict(self) -> dict:
        return asdict(self)


def _rss_mib() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r / (1024 * 1024) if sys.platform == "darwin" else r / 1024


def _sync(device: str) -> None:
    if device.startswith("cuda"):
        torch.cuda.synchronize()


def run_model_bench(cfg: TrainConfig, *, points: int = 100_000, backend: str = "torch", device: str = "cpu",
                    repeats: int = 3, seed: int = 0) -> BenchResult:
    dev = resolve_device(device)
    cfg = cfg.model_copy(update={"model": cfg.model.model_copy(update={"backend": backend})})
    if cfg.threads > 0:
        torch.set_num_threads(cfg.threads)
    rng = np.random.default_rng(seed)
    room = 6.0
    density = 1.3 * points / (room * room + 2 * room * 2.6 + 24.0)  # floor, two walls, ~12 boxes
    sample = make_toy_scene("bench", rng=rng, num_objects=12, room_m=room, density_per_m2=density)
    while len(sample) < points:
        density *= 1.5 * points / len(sample)
        sample = make_toy_scene("bench", rng=np.random.default_rng(seed), num_objects=12, room_m=room,
                                density_per_m2=density)
    rows = np.sort(rng.choice(len(sample), points, replace=False))
    vox = voxelize(sample.coord[rows], sample.color[rows], sample.instance[rows], cfg.data.voxel_size)
    masks, _ = instance_masks(vox.instance)
    coords, feats = collate([vox], dev)
    targets = torch.from_numpy(np.ascontiguousarray(masks.T)).to(dev, torch.float32)
    torch.manual_seed(seed)
    model = build_model(cfg.model).to(dev)
    n_params = sum(p.numel() for p in model.parameters())

    def forward() -> None:
        model.eval()
        with torch.no_grad():
            model(coords, feats, 1)

    def forward_backward() -> None:
        model.train()
        model.zero_grad(set_to_none=True)
        preds = model(coords, feats, 1)
        scene_loss(preds[0], targets, cfg.loss).total.backward()

    rss_base = _rss_mib()

    def measure(fn) -> tuple[float, float]:
        if dev.startswith("cuda"):
            torch.cuda.reset_peak_memory_stats()
            base = torch.cuda.memory_allocated()
        else:
            base = rss_base  # the peak RSS only grows: measure from before the first run
        fn()  # warm-up (allocator, kernel maps, lazy init)
        _sync(dev)
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            fn()
            _sync(dev)
            times.append(time.perf_counter() - t)
        if dev.startswith("cuda"):
            peak = (torch.cuda.max_memory_allocated() - base) / 2 ** 20
        else:
            peak = _rss_mib() - base
        return statistics.median(times), peak

    fwd_s, fwd_mem = measure(forward)
    fb_s: float | None = None
    fb_mem: float | None = None
    note = ""
    if backend == "spconv" and not dev.startswith("cuda"):
        note = "spconv's CPU package has no backward pass (it asks for a CUDA stream): forward only"
    else:
        fb_s, fb_mem = measure(forward_backward)
    return BenchResult(points=points, voxels=len(vox.coords), backend=backend, device=dev,
                       threads=torch.get_num_threads(), parameters=n_params, forward_s=fwd_s,
                       forward_backward_s=fb_s, forward_peak_mib=fwd_mem, forward_backward_peak_mib=fb_mem,
                       repeats=repeats, note=note)

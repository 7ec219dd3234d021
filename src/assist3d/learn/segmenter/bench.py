"""Training throughput of the segmenter: seconds per step of the real training loop.

:func:`bench_training` runs :func:`assist3d.learn.segmenter.train.train_segmenter` itself (example
building, forward, backward, optimiser, weight averaging) for ``warmup + steps`` steps into a
temporary folder and reads each step's training time from the loop's own clock, so the figure is what
a probe or a training run spends per step, loader included. The first ``warmup`` steps (kernel
selection, allocator growth) are left out of the statistics.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from dataclasses import asdict, dataclass
from typing import Sequence

import torch

from ...core.errors import ConfigError
from ...core.machine import describe_machine
from ..models.sparse import native_bfloat16, resolve_precision
from .config import SegmenterConfig
from .data import Scene
from .train import Budget, train_segmenter

MAX_BENCH_STEPS = 10_000


@dataclass(frozen=True)
class TrainBench:
    """Seconds per training step (median, min, max over the timed steps) and the derived rates."""

    device: str
    precision: str
    threads: int
    loader_workers: int
    batch_size: int
    scenes: int
    steps: int
    warmup: int
    step_s_median: float
    step_s_min: float
    step_s_max: float
    steps_per_s: float
    examples_per_s: float
    wall_s: float
    machine: dict  # describe_machine() + torch, native_bfloat16 and the GPU's name on CUDA

    def as_dict(self) -> dict:
        return asdict(self)


def machine_of(device: str) -> dict:
    """:func:`assist3d.core.machine.describe_machine` with what decides a training step's speed here: the
    torch version, whether the CPU multiplies bfloat16 natively (``optim.precision: auto`` uses it) and,
    on CUDA, the GPU's name."""
    gpu = torch.cuda.get_device_name(torch.device(device)) if torch.device(device).type == "cuda" else None
    return {**describe_machine(), "torch": torch.__version__, "native_bfloat16": native_bfloat16("cpu"), "gpu": gpu}


def bench_training(scenes: Sequence[Scene], cfg: SegmenterConfig, *, steps: int = 10, warmup: int = 3,
                   device: str = "cpu", loader_workers: int = 0, seed: int = 0) -> TrainBench:
    """Time ``steps`` training steps after ``warmup`` untimed ones (see the module docstring)."""
    if not (1 <= steps <= MAX_BENCH_STEPS) or not (0 <= warmup <= MAX_BENCH_STEPS):
        raise ConfigError(f"bench steps {steps} / warmup {warmup}: expected 1 to {MAX_BENCH_STEPS:,} timed steps "
                          "and 0 or more warm-up steps")
    if not scenes:
        raise ConfigError("no training scenes to time")
    times: list[float] = []
    last = [0.0]

    def on_step(row: dict) -> None:
        times.append(row["train_seconds"] - last[0])
        last[0] = row["train_seconds"]

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="assist3d-bench-train-") as tmp:
        train_segmenter(cfg, scenes, tmp, seed=seed, budget=Budget(steps=warmup + steps), device=device,
                        loader_workers=loader_workers, on_step=on_step)
    wall = time.perf_counter() - t0
    timed = times[warmup:]
    med = statistics.median(timed)
    return TrainBench(device=device, precision=resolve_precision(cfg.optim.precision, device),
                      threads=torch.get_num_threads(), loader_workers=loader_workers,
                      batch_size=cfg.optim.batch_size, scenes=len(scenes), steps=steps, warmup=warmup,
                      step_s_median=round(med, 4), step_s_min=round(min(timed), 4), step_s_max=round(max(timed), 4),
                      steps_per_s=round(1.0 / med, 4), examples_per_s=round(cfg.optim.batch_size / med, 4),
                      wall_s=round(wall, 2), machine=machine_of(device))

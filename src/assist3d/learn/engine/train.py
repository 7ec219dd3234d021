"""The trainer: mixed real/synthetic batches, Hungarian-matched losses, AdamW + one-cycle, AMP, DDP.

Output folder: ``config.yaml`` (resolved copy), ``metrics.csv`` (one row per step), ``last.pt``
(every epoch), ``epoch_NNNN.pt`` (every ``checkpoint_every`` epochs and the final one) and TensorBoard
events under ``tb/`` when the ``tensorboard`` package is installed. Only rank 0 writes.
"""

from __future__ import annotations

import io
import logging
import math
import time
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import torch
from torch.utils.data import DistributedSampler

from ...core.contracts import PointSample
from ...core import reading
from ...core.errors import ConfigError, DataError
from ...core.fileio import write_bytes_atomic, write_text_atomic
from ..models import mask3d as _mask3d  # noqa: F401  registers "mask3d"
from ..models.registry import build_model as build_registered
from .config import ModelConfig, TrainConfig, dump_train_config, parse_train_config
from .dist import DistInfo, all_reduce_mean, init_distributed, shutdown
from .loader import PreparedBatch, Source, epoch_batches, prepare_batch
from .loggers import CsvLog, TensorBoardLog, TrainLogger, close_all, log_all
from .losses import scene_loss
from .scenes import SceneSource
from .voxelize import collate

log = logging.getLogger(__name__)


class MemorySource:
    """Scenes held in memory (tests, notebooks): ``samples`` with a synthetic flag each."""

    def __init__(self, samples: list[PointSample], synthetic: list[bool] | None = None):
        self.samples = list(samples)
        self.synthetic = list(synthetic) if synthetic is not None else [False] * len(self.samples)

    def __len__(self) -> int:
        return len(self.samples)

    def sample(self, i: int) -> PointSample:
        return self.samples[i]

    def is_synthetic(self, i: int) -> bool:
        return self.synthetic[i]


class _SpecSource(SceneSource):
    def is_synthetic(self, i: int) -> bool:
        return self.refs[i].synthetic


def resolve_device(name: str) -> str:
    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if name.startswith("cuda") and not torch.cuda.is_available():
        raise ConfigError(f"device {name!r} asked for but CUDA is not available; use --device cpu")
    if name != "cpu" and not name.startswith("cuda"):
        raise ConfigError(f"device {name!r}: expected auto, cpu or cuda[:N]")
    return name


def build_model(cfg: ModelConfig) -> torch.nn.Module:
    """The Mask3D-style model of a training config (the ``mask3d`` entry of the model registry)."""
    return build_registered("mask3d", cfg)


def save_checkpoint(path: Path, model: torch.nn.Module, optimizer: Any, scheduler: Any, epoch: int, step: int,
                    cfg: TrainConfig, scaler: Any = None) -> None:
    """Write ``path`` atomically with model, optimiser, scheduler, epoch, step and config."""
    state = {
        "model": _unwrap(model).state_dict(),
        "optimizer": optimizer.state_dict() if optimizer is not None else None,
        "scheduler": scheduler.state_dict() if scheduler is not None else None,
        "scaler": scaler.state_dict() if scaler is not None else None,
        "epoch": epoch,
        "step": step,
        "config": cfg.model_dump(mode="json"),
    }
    buf = io.BytesIO()
    torch.save(state, buf)
    write_bytes_atomic(path, buf.getvalue())


def load_checkpoint(path: str | Path, map_location: str = "cpu") -> dict:
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: checkpoint not found")
    state = reading.read_checkpoint(path, map_location=map_location)
    if not isinstance(state, dict) or "model" not in state or "config" not in state:
        raise DataError(f"{path}: not an assist3d checkpoint (expected keys model, config)")
    return state


def _unwrap(model: torch.nn.Module) -> torch.nn.Module:
    return model.module if hasattr(model, "module") else model


@dataclass
class StepStats:
    loss: float
    objectness: float
    mask_bce: float
    dice: float
    scenes: int


class Trainer:
    """Owns the model, optimiser and schedule; :meth:`step` trains on one batch of scene indices."""

    def __init__(self, cfg: TrainConfig, source: Source, *, steps_total: int, device: str = "cpu",
                 dist_info: DistInfo | None = None):
        self.cfg = cfg
        self.source = source
        self.device = device
        self.dist = dist_info or DistInfo(0, 1, 0)
        if cfg.threads > 0:
            torch.set_num_threads(cfg.threads)
        torch.manual_seed(cfg.seed)
        model = build_model(cfg.model).to(device)
        if self.dist.world_size > 1:
            ids = [self.dist.local_rank] if device.startswith("cuda") else None
            model = torch.nn.parallel.DistributedDataParallel(model, device_ids=ids)
        self.model = model
        self.optimizer = torch.optim.AdamW(model.parameters(), lr=cfg.optim.lr, weight_decay=cfg.optim.weight_decay)
        # OneCycleLR needs a warm-up and an annealing phase of at least one step each
        total = max(steps_total, 4)
        pct = min(max(cfg.optim.pct_start, 1.5 / total), 1 - 1.5 / total)
        self.scheduler = torch.optim.lr_scheduler.OneCycleLR(self.optimizer, max_lr=cfg.optim.lr, total_steps=total,
                                                             pct_start=pct)
        self.use_amp = cfg.optim.amp and device.startswith("cuda")
        self.amp_dtype = torch.bfloat16 if self.use_amp and torch.cuda.is_bf16_supported() else torch.float16
        self.scaler = torch.amp.GradScaler("cuda") if self.use_amp and self.amp_dtype == torch.float16 else None

    def batch_loss(self, indices: list[int], *, rng: np.random.Generator, augment: bool = True) -> tuple[torch.Tensor, StepStats]:
        """Prepare the scenes ``indices`` with ``rng`` and return their weighted loss (:meth:`prepared_loss`)."""
        return self.prepared_loss(prepare_batch(self.source, self.cfg, indices, rng=rng, augment=augment), rng=rng)

    def prepared_loss(self, batch: PreparedBatch, *, rng: np.random.Generator) -> tuple[torch.Tensor, StepStats]:
        """Forward one prepared batch and return the weighted loss (synthetic scenes x ``synthetic_alpha``);
        ``rng`` draws the points the losses are computed on when ``loss.num_points`` is set."""
        dcfg = self.cfg.data
        indices, prepared = batch.indices, batch.scenes
        coords, feats = collate([v for v, _ in prepared], self.device)
        ctx = torch.autocast("cuda", dtype=self.amp_dtype) if self.use_amp else nullcontext()
        with ctx:
            preds = self.model(coords, feats, len(indices))
        total = torch.zeros((), device=self.device)
        stats = np.zeros(3)
        for b, (i, (vox, masks)) in enumerate(zip(indices, prepared)):
            targets = torch.from_numpy(np.ascontiguousarray(masks.T)).to(self.device, torch.float32)
            sample = None
            n_pts = self.cfg.loss.num_points
            if n_pts > 0 and len(vox.coords) > n_pts:
                sample = torch.from_numpy(rng.choice(len(vox.coords), n_pts, replace=False)).to(self.device)
            parts = scene_loss(preds[b], targets, self.cfg.loss, sample)
            weight = dcfg.synthetic_alpha if self.source.is_synthetic(i) else 1.0
            total = total + weight * parts.total
            stats += [float(parts.objectness), float(parts.mask_bce), float(parts.dice)]
        loss = total / len(indices)
        stats /= len(indices)
        return loss, StepStats(float(loss.detach()), *stats.tolist(), scenes=len(indices))

    def step(self, indices: list[int], *, rng: np.random.Generator) -> StepStats:
        """One optimisation step on the scenes ``indices``, prepared here with ``rng``."""
        return self.step_prepared(prepare_batch(self.source, self.cfg, indices, rng=rng), rng=rng)

    def step_prepared(self, batch: PreparedBatch, *, rng: np.random.Generator) -> StepStats:
        """One optimisation step on a batch the loader prepared (:mod:`.loader`)."""
        self.model.train()
        self.optimizer.zero_grad(set_to_none=True)
        loss, stats = self.prepared_loss(batch, rng=rng)
        if self.scaler is not None:
            self.scaler.scale(loss).backward()
            self.scaler.unscale_(self.optimizer)
        else:
            loss.backward()
        if self.cfg.optim.grad_clip > 0:
            torch.nn.utils.clip_grad_norm_(self.model.parameters(), self.cfg.optim.grad_clip)
        if self.scaler is not None:
            self.scaler.step(self.optimizer)
            self.scaler.update()
        else:
            self.optimizer.step()
        self.scheduler.step()
        return stats

    def state(self) -> dict:
        return {"model": _unwrap(self.model).state_dict(), "optimizer": self.optimizer.state_dict(),
                "scheduler": self.scheduler.state_dict()}

    def restore(self, state: dict) -> None:
        _unwrap(self.model).load_state_dict(state["model"])
        if state.get("optimizer") is not None:
            self.optimizer.load_state_dict(state["optimizer"])
        if state.get("scheduler") is not None:
            fresh = self.scheduler.state_dict()
            saved = dict(state["scheduler"])
            if saved.get("total_steps") != fresh["total_steps"]:
                # the run was extended (or shortened): keep the position, use the new schedule's length
                log.warning("schedule length changed from %s to %s steps on resume", saved.get("total_steps"),
                            fresh["total_steps"])
                saved["total_steps"] = fresh["total_steps"]
                saved["_schedule_phases"] = fresh["_schedule_phases"]
            self.scheduler.load_state_dict(saved)
        if self.scaler is not None and state.get("scaler") is not None:
            self.scaler.load_state_dict(state["scaler"])


@dataclass
class TrainResult:
    out_dir: Path
    epochs: int
    steps: int
    last_loss: float
    checkpoint: Path
    seconds: float


_CSV_FIELDS = ["epoch", "step", "lr", "loss", "objectness", "mask_bce", "dice", "scenes", "seconds"]


def train(cfg: TrainConfig, out_dir: str | Path, *, resume: bool = False, source: Source | None = None,
          on_step: Callable[[dict], None] | None = None, loggers: Sequence[TrainLogger] | None = None) -> TrainResult:
    """Train ``cfg`` into ``out_dir`` (resuming from ``out_dir/last.pt`` when ``resume``).

    Every step's row (``epoch, step, lr, loss, objectness, mask_bce, dice, scenes, seconds``) goes to
    ``loggers`` on the main process: by default ``out_dir/metrics.csv`` and, when tensorboard is
    installed, ``out_dir/tb`` (:mod:`.loggers`); ``on_step`` also gets it, for progress display."""
    out = Path(out_dir)
    device = resolve_device(cfg.device)
    info = init_distributed(device)
    if device == "cuda" and info.world_size > 1:
        device = f"cuda:{info.local_rank}"
    src: Source = source if source is not None else _SpecSource(cfg.data.train, cache=cfg.data.cache_scenes)
    sampler = DistributedSampler(range(len(src)), num_replicas=info.world_size, rank=info.rank, shuffle=True,
                                 seed=cfg.seed)
    bs = cfg.optim.batch_size
    steps_per_epoch = math.ceil(len(sampler) / bs)
    trainer = Trainer(cfg, src, steps_total=steps_per_epoch * cfg.optim.epochs, device=device, dist_info=info)
    start_epoch, step = 0, 0
    last = out / "last.pt"
    if resume:
        if not last.is_file():
            raise ConfigError(f"--resume: {last} not found (train into this folder first, or drop --resume)")
        state = load_checkpoint(last, device)
        trainer.restore(state)
        start_epoch, step = int(state["epoch"]), int(state["step"])
        log.info("resumed from %s at epoch %d, step %d", last, start_epoch, step)
    sinks: list[TrainLogger] = []
    if info.is_main:
        out.mkdir(parents=True, exist_ok=True)
        write_text_atomic(out / "config.yaml", dump_train_config(cfg))
        if loggers is None:
            tb = TensorBoardLog.open(out / "tb", ("loss", "objectness", "mask_bce", "dice", "lr"))
            sinks = [CsvLog(out / "metrics.csv", _CSV_FIELDS)] + ([tb] if tb is not None else [])
        else:
            sinks = list(loggers)
    t0 = time.perf_counter()
    last_loss = float("nan")
    ckpt = last
    try:
        for epoch in range(start_epoch, cfg.optim.epochs):
            sampler.set_epoch(epoch)
            order = list(sampler)
            torch.manual_seed(cfg.seed * 1_000_003 + epoch * 101 + info.rank)
            batches = epoch_batches(src, cfg, order, epoch=epoch, rank=info.rank, workers=cfg.data.workers)
            for b in range(steps_per_epoch):
                ts = time.perf_counter()
                batch = next(batches)
                lr = trainer.optimizer.param_groups[0]["lr"]  # the rate this step uses
                # the loss-point draw has its own stream, so it does not depend on where the batch was built
                stats = trainer.step_prepared(batch, rng=np.random.default_rng([cfg.seed, epoch, info.rank, b, 1]))
                step += 1
                loss_t = all_reduce_mean(torch.tensor(stats.loss, device=device), info)
                last_loss = float(loss_t)
                row = {"epoch": epoch + 1, "step": step, "lr": lr, "loss": last_loss,
                       "objectness": stats.objectness, "mask_bce": stats.mask_bce, "dice": stats.dice,
                       "scenes": stats.scenes * info.world_size, "seconds": time.perf_counter() - ts}
                if info.is_main:
                    log_all(sinks, [row])
                    if on_step is not None:
                        on_step({**row, "epochs": cfg.optim.epochs, "steps_per_epoch": steps_per_epoch})
            batches.close()  # stops the loader's workers
            if info.is_main:
                save_checkpoint(last, trainer.model, trainer.optimizer, trainer.scheduler, epoch + 1, step, cfg,
                                trainer.scaler)
                if (epoch + 1) % max(cfg.checkpoint_every, 1) == 0 or epoch + 1 == cfg.optim.epochs:
                    ckpt = out / f"epoch_{epoch + 1:04d}.pt"
                    save_checkpoint(ckpt, trainer.model, trainer.optimizer, trainer.scheduler, epoch + 1, step, cfg,
                                    trainer.scaler)
    finally:
        close_all(sinks)
        shutdown(info)
    return TrainResult(out_dir=out, epochs=cfg.optim.epochs, steps=step, last_loss=last_loss, checkpoint=ckpt,
                       seconds=time.perf_counter() - t0)


def config_from_checkpoint(state: dict) -> TrainConfig:
    return parse_train_config(state["config"], "checkpoint config")

"""Training the segmenter on a budget of minutes or steps, resumable, deterministic per seed.

Each step draws its scenes and augmentations from ``numpy.random.default_rng([seed, step])``, so a
run resumed from ``last.pt`` sees exactly the batches an uninterrupted run would. With a step budget
the learning rate follows a cosine from ``lr`` to 1 % over the steps; with a minute budget it follows
the same cosine over the elapsed training time (the run then depends on the machine's speed, and the
number of steps it reached is recorded).
"""

from __future__ import annotations

import copy
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import torch
import torch.nn.functional as F

from ..engine.loggers import CsvLog, TrainLogger, close_all, log_all
from ..models.sparse import resolve_precision, use_precision
from ..models.registry import build_model
from ...core.errors import ConfigError
from .checkpoint import load_segmenter, save_segmenter
from .config import SegmenterConfig
from .data import Example, Scene
from .infer import batch_coords
from .loader import BatchLoader
from .model import Segmenter

log = logging.getLogger(__name__)

CHECKPOINT_EVERY_S = 120.0


@dataclass(frozen=True)
class Budget:
    """Stop after ``steps`` steps, or after ``minutes`` of training time, whichever is given."""

    steps: int | None = None
    minutes: float | None = None

    def __post_init__(self) -> None:
        if (self.steps is None) == (self.minutes is None):
            raise ConfigError("give exactly one training budget: --steps S or --minutes M")
        if self.steps is not None and not (1 <= self.steps <= 10_000_000):
            raise ConfigError(f"--steps {self.steps}: expected 1 to 10,000,000")
        if self.minutes is not None and not (0 < self.minutes <= 60 * 24 * 7):
            raise ConfigError(f"--minutes {self.minutes}: expected more than 0 and at most a week (10080)")

    def progress(self, step: int, seconds: float) -> float:
        if self.steps is not None:
            return step / self.steps
        return seconds / (self.minutes * 60.0)

    def as_dict(self) -> dict:
        return {"steps": self.steps, "minutes": self.minutes}


@dataclass
class TrainRecord:
    steps: int
    train_seconds: float
    last_loss: float
    checkpoint: Path


def example_loss(model: Segmenter, examples: Sequence[Example], cfg: SegmenterConfig,
                 device: str = "cpu") -> tuple[torch.Tensor, dict[str, float]]:
    """Foreground BCE + offset L1 + direction loss (minus cosine) over a batch of examples."""
    coords = np.concatenate([batch_coords(e.coords, b) for b, e in enumerate(examples)])
    feats = np.concatenate([e.feats for e in examples])
    fg = torch.from_numpy(np.concatenate([e.fg for e in examples])).to(device)
    off_t = torch.from_numpy(np.concatenate([e.offset for e in examples])).to(device)
    logit, off = model(torch.from_numpy(coords).to(device), torch.from_numpy(feats).to(device))
    bce = F.binary_cross_entropy_with_logits(logit, fg)
    m = fg > 0.5
    if bool(m.any()):
        l1 = (off[m] - off_t[m]).abs().sum(1).mean()
        cos = F.cosine_similarity(off[m], off_t[m], dim=1, eps=1e-6)
        direction = -cos.mean()
    else:
        l1 = direction = off.sum() * 0.0
    loss = bce + cfg.optim.offset_weight * l1 + cfg.optim.direction_weight * direction
    return loss, {"loss": float(loss.detach()), "bce": float(bce.detach()), "offset": float(l1.detach()),
                  "direction": float(direction.detach())}


LOG_FIELDS = ("step", "train_seconds", "lr", "loss", "bce", "offset", "direction")


def _lr(cfg: SegmenterConfig, progress: float) -> float:
    p = min(max(progress, 0.0), 1.0)
    return cfg.optim.lr * (0.01 + 0.99 * 0.5 * (1 + math.cos(math.pi * p)))


@torch.no_grad()
def update_ema(ema: Segmenter, model: Segmenter, decay: float, step: int) -> None:
    """``ema <- d * ema + (1 - d) * model`` with ``d = min(decay, (1 + step) / (10 + step))``: the
    usual warm-up, so the first steps' random weights do not linger in the average. Buffers are copied."""
    d = min(decay, (1 + step) / (10 + step))
    for pe, p in zip(ema.parameters(), model.parameters()):
        pe.mul_(d).add_(p.detach(), alpha=1.0 - d)
    for be, b in zip(ema.buffers(), model.buffers()):
        be.copy_(b)


def train_segmenter(cfg: SegmenterConfig, scenes: Sequence[Scene], out_dir: str | Path, *, seed: int,
                    budget: Budget, meta: dict | None = None, device: str = "cpu", loader_workers: int = 0,
                    on_step: Callable[[dict], None] | None = None,
                    loggers: Sequence[TrainLogger] = (), probs: np.ndarray | None = None) -> TrainRecord:
    """Train on ``scenes`` into ``out_dir/last.pt`` (resumed when it exists); returns the record.

    Each step's row (``step, train_seconds, lr, loss, bce, offset, direction``) goes to
    ``out_dir/train_log.csv`` and to ``loggers`` (:mod:`assist3d.learn.engine.loggers`), only when the
    checkpoint that covers it is written, so a resumed run logs no step twice.

    ``loader_workers`` processes build the coming steps' examples while the network trains
    (:mod:`.loader`); the batches, and so the result, are the same for any number of workers.
    ``probs`` (per scene, :func:`.loader.mix_probabilities`) weights the draws; None draws uniformly.
    """
    if not scenes:
        raise ConfigError("no training scenes")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    last = out / "last.pt"
    torch.manual_seed(seed)
    model = build_model("segmenter", cfg.net).to(device)
    precision = resolve_precision(cfg.optim.precision, device)
    use_precision(model, precision)
    opt = torch.optim.Adam(model.parameters(), lr=cfg.optim.lr, weight_decay=cfg.optim.weight_decay)
    ema = copy.deepcopy(model).requires_grad_(False) if cfg.optim.ema_decay > 0 else None
    step, seconds, last_loss = 0, 0.0, float("nan")
    if last.is_file():
        loaded = load_segmenter(last, device, weights="live")
        if loaded.config != cfg:
            raise ConfigError(f"{last}: was trained with another configuration; use a new output folder")
        model.load_state_dict(loaded.model.state_dict())
        if loaded.optimizer is not None:
            opt.load_state_dict(loaded.optimizer)
        if ema is not None:
            if loaded.ema_state is None:
                raise ConfigError(f"{last}: holds no averaged weights although optim.ema_decay is set")
            ema.load_state_dict(loaded.ema_state)
        step = int(loaded.progress.get("step", 0))
        seconds = float(loaded.progress.get("train_seconds", 0.0))
        last_loss = float(loaded.progress.get("loss", float("nan")))
        log.info("resumed %s at step %d (%.0f s trained)", last, step, seconds)
    meta = dict(meta or {})
    csv_log = CsvLog(out / "train_log.csv", LOG_FIELDS)
    csv_log.truncate(step)
    sinks: list[TrainLogger] = [csv_log, *loggers]
    pending: list[dict] = []

    def save() -> None:
        progress = {"step": step, "train_seconds": seconds, "loss": last_loss, "seed": seed, "budget": budget.as_dict(),
                    "precision": precision}
        save_segmenter(last, model, cfg, meta={**meta, **progress}, optimizer=opt, progress=progress, ema=ema)
        log_all(sinks, pending)  # rows reach the logs only with the checkpoint that covers them
        pending.clear()

    try:
        last_save = time.perf_counter()
        model.train()
        with BatchLoader(scenes, cfg, seed, step, workers=loader_workers, probs=probs) as loader:
            while budget.progress(step, seconds) < 1.0:
                t0 = time.perf_counter()
                _, examples = loader.next()
                for g in opt.param_groups:
                    g["lr"] = _lr(cfg, budget.progress(step, seconds))
                opt.zero_grad(set_to_none=True)
                loss, parts = example_loss(model, examples, cfg, device)
                if not math.isfinite(parts["loss"]):
                    raise FloatingPointError(f"training diverged at step {step} (loss {parts['loss']}); lower optim.lr")
                loss.backward()
                torch.nn.utils.clip_grad_norm_(model.parameters(), 5.0)
                opt.step()
                if ema is not None:
                    update_ema(ema, model, cfg.optim.ema_decay, step)
                step += 1
                seconds += time.perf_counter() - t0
                last_loss = parts["loss"]
                pending.append({"step": step, "train_seconds": round(seconds, 3), "lr": opt.param_groups[0]["lr"],
                                **{k: round(v, 6) for k, v in parts.items()}})
                if on_step is not None:
                    on_step({"step": step, "train_seconds": seconds, "progress": budget.progress(step, seconds),
                             "lr": opt.param_groups[0]["lr"], **parts})
                if time.perf_counter() - last_save > CHECKPOINT_EVERY_S:
                    save()
                    last_save = time.perf_counter()
        save()
    finally:
        close_all(sinks)

    return TrainRecord(steps=step, train_seconds=seconds, last_loss=last_loss, checkpoint=last)

"""Training the segmenter on a budget of minutes or steps, resumable, deterministic per seed.

Each step draws its scenes and augmentations from ``numpy.random.default_rng([seed, step])``, so a
run resumed from ``last.pt`` sees exactly the batches an uninterrupted run would. With a step budget
the learning rate follows a cosine from ``lr`` to 1 % over the steps; with a minute budget it follows
the same cosine over the elapsed training time (the run then depends on the machine's speed, and the
number of steps it reached is recorded).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import torch
import torch.nn.functional as F

from ..engine.loggers import CsvLog, TrainLogger, close_all, log_all
from ..models.sparse import resolve_precision, use_precision
from ..models.registry import build_model
from ..trainer import CallbackHook, CheckpointHook, EMAHook, Hook, Trainer, update_ema  # noqa: F401  update_ema: the API
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
    ema_hook = EMAHook(model, cfg.optim.ema_decay) if cfg.optim.ema_decay > 0 else None
    trainer = Trainer(model, opt, lambda m, examples: example_loss(m, examples, cfg, device),
                      lr_at=lambda t: _lr(cfg, budget.progress(t.steps, t.seconds)), grad_clip=5.0, check_finite=True)
    precisions = [precision]  # every precision the run's steps were taken in (a resume may change machines)
    if last.is_file():
        loaded = load_segmenter(last, device, weights="live")
        if loaded.config != cfg:
            raise ConfigError(f"{last}: was trained with another configuration; use a new output folder")
        model.load_state_dict(loaded.model.state_dict())
        if loaded.optimizer is not None:
            opt.load_state_dict(loaded.optimizer)
        if ema_hook is not None:
            if loaded.ema_state is None:
                raise ConfigError(f"{last}: holds no averaged weights although optim.ema_decay is set")
            ema_hook.ema.load_state_dict(loaded.ema_state)
        trainer.steps = int(loaded.progress.get("step", 0))
        trainer.seconds = float(loaded.progress.get("train_seconds", 0.0))
        trainer.last_loss = float(loaded.progress.get("loss", float("nan")))
        before = precisions_of(loaded.progress)
        if before and precision not in before:
            log.warning("%s: trained so far in %s, continues in %s (optim.precision %s follows this machine's "
                        "CPU); its record names both", last, "+".join(before), precision, cfg.optim.precision)
        precisions = sorted({*before, precision})
        log.info("resumed %s at step %d (%.0f s trained)", last, trainer.steps, trainer.seconds)
    meta = dict(meta or {})
    csv_log = CsvLog(out / "train_log.csv", LOG_FIELDS)
    csv_log.truncate(trainer.steps)
    sinks: list[TrainLogger] = [csv_log, *loggers]
    rows = _PendingRows()

    def save(t: Trainer) -> None:
        progress = {"step": t.steps, "train_seconds": t.seconds, "loss": t.last_loss, "seed": seed,
                    "budget": budget.as_dict(), "precision": precision, "precisions": precisions}
        save_segmenter(last, model, cfg, meta={**meta, **progress}, optimizer=opt, progress=progress,
                       ema=ema_hook.ema if ema_hook is not None else None)
        log_all(sinks, rows.pending)  # rows reach the logs only with the checkpoint that covers them
        rows.pending.clear()

    trainer.hooks = [*([ema_hook] if ema_hook is not None else []), rows]
    if on_step is not None:
        trainer.hooks.append(CallbackHook(on_step, lambda t: {"progress": budget.progress(t.steps, t.seconds)}))
    trainer.hooks.append(CheckpointHook(save, every_s=CHECKPOINT_EVERY_S))
    try:
        with BatchLoader(scenes, cfg, seed, trainer.steps, workers=loader_workers, probs=probs) as loader:
            trainer.fit(iter(lambda: loader.next()[1], None), until=lambda t: budget.progress(t.steps, t.seconds) >= 1.0)
    finally:
        close_all(sinks)

    return TrainRecord(steps=trainer.steps, train_seconds=trainer.seconds, last_loss=trainer.last_loss, checkpoint=last)


def precisions_of(progress: dict) -> list[str]:
    """The precisions a checkpoint's steps were taken in (its ``progress`` or meta): ``precisions``, else
    (checkpoints from before that key) its one ``precision``, else (from before precision existed) none known."""
    got = progress.get("precisions")
    if isinstance(got, list):
        return sorted(str(p) for p in got)
    return [str(progress["precision"])] if progress.get("precision") else []


class _PendingRows(Hook):
    """Collects each step's log row (rounded) until the checkpoint that covers it is written."""

    def __init__(self) -> None:
        self.pending: list[dict] = []

    def after_step(self, trainer: Trainer, record: dict[str, float]) -> None:
        self.pending.append({"step": trainer.steps, "train_seconds": round(trainer.seconds, 3), "lr": record["lr"],
                             **{k: round(v, 6) for k, v in record.items() if k in LOG_FIELDS[3:]}})

"""The one training loop of the learning side: a model, an optimiser, a loss and hooks.

Every model of the registry (:mod:`assist3d.learn.models.registry`) trains through :class:`Trainer`.
What differs between them lives outside the loop:

- the **loss** (``loss_fn(model, batch) -> (loss, parts)``, ``parts`` the floats to log);
- the **batches** (any iterator; each stack has its loader, deterministic per seed and step);
- the **learning rate**: ``lr_at(trainer)`` sets it before each step (a schedule over a budget of steps or
  minutes) and/or a ``torch.optim.lr_scheduler`` is stepped after it;
- the **hooks** (:class:`Hook`), called around each step in the order given: weight averaging
  (:class:`EMAHook`), logging, checkpointing (:class:`CheckpointHook`), progress display.

One step is: set the rate, zero the gradients, forward the loss, (refuse a non-finite loss), backward
(through a ``GradScaler`` when one is given), clip the gradient norm, step the optimiser and the scheduler.
:meth:`Trainer.fit` runs steps until the batches end or ``until(trainer)`` says stop, and keeps the
counters (``step``, ``seconds`` of training time including fetching each batch) that checkpoints save and
a resumed run restores.

Adding a model therefore means a loss function and a loader, not a new loop; see docs/architecture.md.
"""

from __future__ import annotations

import copy
import math
import time
from typing import Any, Callable, Iterable, Iterator, Sequence

import torch

LossFn = Callable[[torch.nn.Module, Any], tuple[torch.Tensor, dict[str, float]]]


class Hook:
    """A piece of a run's behaviour around the step; override what is needed.

    ``after_step`` gets the step's record: ``step`` (steps done, this one included), ``train_seconds``
    (training time so far), ``step_seconds``, ``lr`` (the rate this step used) and the loss parts."""

    def before_fit(self, trainer: Trainer) -> None:
        pass

    def after_step(self, trainer: Trainer, record: dict[str, float]) -> None:
        pass

    def after_fit(self, trainer: Trainer) -> None:
        pass


class Trainer:
    """Owns the optimisation step and the step / time counters; see the module docstring."""

    def __init__(self, model: torch.nn.Module, optimizer: torch.optim.Optimizer, loss_fn: LossFn, *,
                 lr_at: Callable[[Trainer], float] | None = None, scheduler: Any = None, grad_clip: float = 0.0,
                 scaler: Any = None, check_finite: bool = False, hooks: Sequence[Hook] = ()) -> None:
        self.model = model
        self.optimizer = optimizer
        self.loss_fn = loss_fn
        self.lr_at = lr_at
        self.scheduler = scheduler
        self.grad_clip = grad_clip
        self.scaler = scaler
        self.check_finite = check_finite
        self.hooks = list(hooks)
        self.steps = 0
        self.seconds = 0.0
        self.last_loss = float("nan")
        self.step_lr = float("nan")  # the rate the last step used

    @property
    def lr(self) -> float:
        return float(self.optimizer.param_groups[0]["lr"])

    def train_step(self, batch: Any) -> dict[str, float]:
        """One optimisation step on ``batch``; returns the loss parts. The counters are :meth:`fit`'s."""
        if self.lr_at is not None:
            lr = self.lr_at(self)
            for g in self.optimizer.param_groups:
                g["lr"] = lr
        self.step_lr = self.lr
        self.model.train()
        self.optimizer.zero_grad(set_to_none=True)
        loss, parts = self.loss_fn(self.model, batch)
        if self.check_finite and not math.isfinite(parts["loss"]):
            raise FloatingPointError(f"training diverged at step {self.steps} (loss {parts['loss']}); lower optim.lr")
        if self.scaler is not None:
            self.scaler.scale(loss).backward()
            self.scaler.unscale_(self.optimizer)
        else:
            loss.backward()
        if self.grad_clip > 0:
            torch.nn.utils.clip_grad_norm_(self.model.parameters(), self.grad_clip)
        if self.scaler is not None:
            self.scaler.step(self.optimizer)
            self.scaler.update()
        else:
            self.optimizer.step()
        if self.scheduler is not None:
            self.scheduler.step()
        return parts

    def fit(self, batches: Iterable[Any], until: Callable[[Trainer], bool] | None = None) -> None:
        """Train on ``batches`` until they end or ``until(self)`` is true (checked before each step)."""
        it: Iterator[Any] = iter(batches)
        for h in self.hooks:
            h.before_fit(self)
        while until is None or not until(self):
            t0 = time.perf_counter()
            try:
                batch = next(it)
            except StopIteration:
                break
            parts = self.train_step(batch)
            self.steps += 1
            dt = time.perf_counter() - t0
            self.seconds += dt
            self.last_loss = float(parts["loss"])
            record = {"step": self.steps, "train_seconds": self.seconds, "step_seconds": dt, "lr": self.step_lr,
                      **parts}
            for h in self.hooks:
                h.after_step(self, record)
        for h in self.hooks:
            h.after_fit(self)


class EMAHook(Hook):
    """Keeps ``ema``, an exponential moving average of the model's weights (buffers copied), updated after
    every step as ``ema <- d * ema + (1 - d) * model`` with ``d = min(decay, (1 + k) / (10 + k))`` for the
    ``k``-th step (0-based): the usual warm-up, so the first steps' random weights do not linger."""

    def __init__(self, model: torch.nn.Module, decay: float) -> None:
        self.decay = decay
        self.ema = copy.deepcopy(model).requires_grad_(False)

    def after_step(self, trainer: Trainer, record: dict[str, float]) -> None:
        update_ema(self.ema, trainer.model, self.decay, trainer.steps - 1)


@torch.no_grad()
def update_ema(ema: torch.nn.Module, model: torch.nn.Module, decay: float, step: int) -> None:
    """One averaging update of ``ema`` towards ``model`` at 0-based ``step`` (see :class:`EMAHook`)."""
    d = min(decay, (1 + step) / (10 + step))
    for pe, p in zip(ema.parameters(), model.parameters()):
        pe.mul_(d).add_(p.detach(), alpha=1.0 - d)
    for be, b in zip(ema.buffers(), model.buffers()):
        be.copy_(b)


class CheckpointHook(Hook):
    """Calls ``save(trainer)`` every ``every_s`` seconds of wall time and/or every ``every_steps`` steps,
    and once when a fit ends (``at_end``)."""

    def __init__(self, save: Callable[[Trainer], None], *, every_s: float | None = None,
                 every_steps: int | None = None, at_end: bool = True) -> None:
        self.save = save
        self.every_s = every_s
        self.every_steps = every_steps
        self.at_end = at_end
        self._last = time.perf_counter()

    def before_fit(self, trainer: Trainer) -> None:
        self._last = time.perf_counter()

    def after_step(self, trainer: Trainer, record: dict[str, float]) -> None:
        due = self.every_s is not None and time.perf_counter() - self._last > self.every_s
        due |= self.every_steps is not None and trainer.steps % self.every_steps == 0
        if due:
            self.save(trainer)
            self._last = time.perf_counter()

    def after_fit(self, trainer: Trainer) -> None:
        if self.at_end:
            self.save(trainer)


class CallbackHook(Hook):
    """Passes every step's record, with ``extra(trainer)`` merged in, to ``fn`` (progress display)."""

    def __init__(self, fn: Callable[[dict], None], extra: Callable[[Trainer], dict] | None = None) -> None:
        self.fn = fn
        self.extra = extra

    def after_step(self, trainer: Trainer, record: dict[str, float]) -> None:
        self.fn({**record, **(self.extra(trainer) if self.extra is not None else {})})

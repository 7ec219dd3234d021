"""The one batch loader of the learning side: batch ``k`` is ``build(k)``, a pure function of ``k``, built
in the training process or, ahead of the step, by worker processes.

Every model's data pipeline is such a function: the CPU segmenter's step ``k`` (its scenes drawn, cropped,
augmented and voxelised from ``numpy.random.default_rng([seed, k])``, :func:`.segmenter.loader.build_batch`)
and the Mask3D-style model's step ``b`` of an epoch (:func:`.engine.loader.epoch_batches`). Workers therefore
change when a batch is built, never what it holds: any number of workers gives the same batches, and a run
resumed at step ``k`` sees the batches an uninterrupted run would. ``build`` must be picklable when
``workers > 0`` (a module-level function or a ``functools.partial`` of one).
"""

from __future__ import annotations

import itertools
from typing import Callable, Generic, Iterator, TypeVar

from torch.utils.data import DataLoader, Dataset, Sampler

from ..core.errors import ConfigError

T = TypeVar("T")
MAX_WORKERS = 64  # loader processes


class _Built(Dataset):
    def __init__(self, build: Callable[[int], T]) -> None:
        self.build = build

    def __getitem__(self, k: int) -> T:
        return self.build(k)


class _Range(Sampler):
    """Keys ``start, start + 1, ...``, up to ``stop`` (exclusive) or without end."""

    def __init__(self, start: int, stop: int | None) -> None:
        self.start, self.stop = start, stop

    def __iter__(self) -> Iterator[int]:
        return iter(range(self.start, self.stop)) if self.stop is not None else itertools.count(self.start)


def _as_is(batch):
    return batch  # keep what build returns (the default collate would turn numpy arrays into tensors)


class StepLoader(Generic[T]):
    """Batches ``build(start)``, ``build(start + 1)``, ... (up to ``stop``, exclusive, or without end), in
    order; iterate it, or call :meth:`next`, inside a ``with`` block (which stops the workers at its end).

    ``workers=0`` builds each batch when it is asked for; ``workers=N`` has ``N`` processes build up to
    ``prefetch`` batches each ahead of the training step."""

    def __init__(self, build: Callable[[int], T], start: int = 0, stop: int | None = None, *, workers: int = 0,
                 prefetch: int = 2) -> None:
        if not (0 <= workers <= MAX_WORKERS):
            raise ConfigError(f"loader workers {workers}: expected 0 to {MAX_WORKERS}")
        self.build, self.next_step, self.stop, self.workers = build, start, stop, workers
        self._loader = (DataLoader(_Built(build), batch_size=None, sampler=_Range(start, stop), num_workers=workers,
                                   collate_fn=_as_is, prefetch_factor=max(1, prefetch)) if workers else None)
        self._it: Iterator[T] | None = None

    def __enter__(self) -> StepLoader[T]:
        self._it = iter(self._loader) if self._loader is not None else None
        self._open = True
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self._open = False
        it, self._it = self._it, None
        shutdown = getattr(it, "_shutdown_workers", None)  # stop worker processes now, not at garbage collection
        if shutdown is not None:
            shutdown()

    def next(self) -> tuple[int, T]:
        """The next step's index and its batch; StopIteration after ``stop``."""
        if not getattr(self, "_open", False):
            raise RuntimeError("the loader was used outside its 'with' block")
        step = self.next_step
        if self.stop is not None and step >= self.stop:
            raise StopIteration
        batch = next(self._it) if self._it is not None else self.build(step)
        self.next_step += 1
        return step, batch

    def __iter__(self) -> Iterator[T]:
        while True:
            try:
                yield self.next()[1]
            except StopIteration:
                return

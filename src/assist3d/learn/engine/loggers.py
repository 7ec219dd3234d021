"""Training loggers, shared by the GPU model's trainer (:func:`assist3d.learn.engine.train.train`) and the
CPU segmenter (:func:`assist3d.learn.segmenter.train.train_segmenter`).

A logger receives the rows of finished steps, in order (one mapping per step), and is closed when
training ends. The trainers write a CSV log by default (``metrics.csv`` / ``train_log.csv``) and,
for the GPU model, TensorBoard scalars when ``tensorboard`` is installed; pass ``loggers=[...]`` to
add your own (anything with ``log(rows)`` and ``close()``: Weights & Biases, MLflow, a queue).
"""

from __future__ import annotations

import csv
import logging
from pathlib import Path
from typing import Any, Mapping, Protocol, Sequence

from ...core import reading
from ...core.errors import DataError, shown

log = logging.getLogger(__name__)

Row = Mapping[str, Any]


class TrainLogger(Protocol):
    """Where the rows of finished training steps go."""

    def log(self, rows: Sequence[Row]) -> None:
        """Record ``rows`` (finished steps, oldest first)."""
        ...

    def close(self) -> None:
        """Flush and release whatever the logger holds; called once when training ends."""
        ...


class CsvLog:
    """Rows appended to a CSV file with fixed columns (a header when the file is new or empty).

    :meth:`truncate` keeps the rows up to a step, so a run resumed from a checkpoint does not log
    the steps after it twice."""

    def __init__(self, path: str | Path, fields: Sequence[str], *, step_key: str = "step") -> None:
        self.path = Path(path)
        self.fields = tuple(fields)
        self.step_key = step_key

    def truncate(self, step: int) -> None:
        """Drop the rows of steps after ``step``."""
        if not self.path.is_file():
            return
        lines = reading.read_text(self.path, what="metrics log").splitlines()
        col = self.fields.index(self.step_key)
        try:
            kept = lines[:1] + [ln for ln in lines[1:] if ln and int(ln.split(",")[col]) <= step]
        except (ValueError, IndexError):
            raise DataError(f"{shown(self.path, 400)}: a row has no integer {self.step_key!r} in column {col + 1}; "
                            "repair or remove the log to resume") from None
        self.path.write_text("\n".join(kept) + "\n" if kept else "")

    def log(self, rows: Sequence[Row]) -> None:
        if not rows:
            return
        new = not self.path.is_file() or self.path.stat().st_size == 0
        with open(self.path, "a", newline="") as f:
            w = csv.DictWriter(f, fieldnames=self.fields)
            if new:
                w.writeheader()
            w.writerows(rows)

    def close(self) -> None:
        pass


class TensorBoardLog:
    """Scalars ``train/<key>`` at each row's step, through ``torch.utils.tensorboard``."""

    def __init__(self, log_dir: str | Path, keys: Sequence[str], *, step_key: str = "step") -> None:
        from torch.utils.tensorboard import SummaryWriter  # optional: needs the tensorboard package

        self.writer = SummaryWriter(str(log_dir))
        self.keys = tuple(keys)
        self.step_key = step_key

    @classmethod
    def open(cls, log_dir: str | Path, keys: Sequence[str], *, step_key: str = "step") -> TensorBoardLog | None:
        """A logger, or None when tensorboard is not installed (the CSV log still has every row)."""
        try:
            return cls(log_dir, keys, step_key=step_key)
        except ImportError:
            log.debug("tensorboard is not installed: no TensorBoard log")
            return None

    def log(self, rows: Sequence[Row]) -> None:
        for row in rows:
            for k in self.keys:
                self.writer.add_scalar(f"train/{k}", row[k], row[self.step_key])

    def close(self) -> None:
        self.writer.close()


def log_all(loggers: Sequence[TrainLogger], rows: Sequence[Row]) -> None:
    for lg in loggers:
        lg.log(rows)


def close_all(loggers: Sequence[TrainLogger]) -> None:
    for lg in loggers:
        lg.close()

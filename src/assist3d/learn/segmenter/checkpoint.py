"""Segmenter checkpoints: the CPU segmenter's files in the one checkpoint format of
:mod:`assist3d.learn.checkpoint` (tag ``assist3d-segmenter``; tensors, strings and numbers only, read
with ``weights_only``, so a crafted file cannot run code). The configuration is validated by pydantic
(:class:`SegmenterConfig`, older files through ``legacy_config``) before a model is built.

Training files of a run with ``optim.ema_decay`` also hold the averaged weights: they are the trained
model, so :func:`load_segmenter` builds the model from them (``weights="live"``, for resuming, gives the
optimiser's weights; both are kept in ``LoadedSegmenter``). ``save_segmenter(precision=...)``: float32
(training files), float16 or int8 (the format's blockwise codes), for a smaller file to ship.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar, Literal

import torch

from ...core.errors import DataError
from ..checkpoint import (INT8_BLOCK, INT8_MIN_NUMEL, VERSION, VERSION_INT8, Checkpoint, Precision,  # noqa: F401
                          dequantize_int8, quantize_int8, read_checkpoint, write_checkpoint)
from ..models.registry import build_model
from .config import SegmenterConfig, legacy_config, parse_segmenter_config
from .model import Network, Segmenter, SegmenterEnsemble

FORMAT = "assist3d-segmenter"
Weights = Literal["trained", "live"]


@dataclass
class LoadedSegmenter:
    """``model`` is in eval mode; ``ema_state`` holds a training file's averaged weights, if any."""

    name: ClassVar[str] = "segmenter"  # the model's registry name

    model: Network
    config: SegmenterConfig
    meta: dict[str, Any]
    optimizer: dict | None
    progress: dict[str, Any]
    ema_state: dict[str, torch.Tensor] | None = None


def save_segmenter(path: str | Path, model: Segmenter, cfg: SegmenterConfig, *, meta: dict | None = None,
                   optimizer: torch.optim.Optimizer | None = None, progress: dict | None = None,
                   precision: Precision = "float32", ema: Segmenter | None = None) -> Path:
    """Write ``path`` atomically. ``precision`` float16 or int8 gives a smaller file to ship."""
    return write_checkpoint(path, Checkpoint(
        model="segmenter", config=cfg.model_dump(mode="json"), state_dict=model.state_dict(), meta=meta or {},
        optimizer=optimizer.state_dict() if optimizer is not None else None, progress=progress,
        ema_state=ema.state_dict() if ema is not None else None), precision=precision)


def load_segmenter(path: str | Path, device: str = "cpu", weights: Weights = "trained") -> LoadedSegmenter:
    """Read a checkpoint safely and build its model in eval mode; one-line :class:`DataError` otherwise.

    ``weights="trained"`` builds the model a run produced: the averaged weights when the file holds
    them (a training file of a run with ``optim.ema_decay``), else its weights; ``"live"`` builds the
    optimiser's weights (resuming a run)."""
    path = Path(path)
    return segmenter_from_checkpoint(read_checkpoint(path, device, model="segmenter"), path, device, weights)


def segmenter_from_checkpoint(ckpt: Checkpoint, path: Path, device: str = "cpu",
                              weights: Weights = "trained") -> LoadedSegmenter:
    """The segmenter of a checkpoint already read (:func:`assist3d.learn.checkpoint.read_checkpoint`)."""
    cfg = parse_segmenter_config(legacy_config(ckpt.config, str(path)), f"{path} config")
    model = build_model("segmenter", cfg.net)
    state = ckpt.ema_state if ckpt.ema_state is not None and weights == "trained" else ckpt.state_dict
    try:
        model.load_state_dict({k: v.float() if v.is_floating_point() else v for k, v in ckpt.state_dict.items()})
        if state is not ckpt.state_dict:
            model.load_state_dict({k: v.float() if v.is_floating_point() else v for k, v in state.items()})
    except RuntimeError as e:
        first = str(e).strip().splitlines()[0][:200]
        raise DataError(f"{path}: the weights do not fit the model its config describes ({first})") from None
    model.to(device).eval()
    return LoadedSegmenter(model=model, config=cfg, meta=ckpt.meta, optimizer=ckpt.optimizer,
                           progress=ckpt.progress or {}, ema_state=ckpt.ema_state)


def load_segmenters(paths: list[str | Path], device: str = "cpu") -> LoadedSegmenter:
    """One checkpoint, or several read as a :class:`SegmenterEnsemble` (outputs averaged). The first
    file's configuration (voxel size, clustering) is used; every member must read the same input
    features, otherwise a :class:`DataError` names the file that differs. ``meta["ensemble"]`` lists
    the members' files and metadata."""
    if not paths:
        raise DataError("no checkpoint given")
    loaded = [load_segmenter(p, device) for p in paths]
    if len(loaded) == 1:
        return loaded[0]
    first = loaded[0].config.net
    for path, one in zip(paths[1:], loaded[1:]):
        net = one.config.net
        if (net.voxel_size, net.use_color) != (first.voxel_size, first.use_color):
            raise DataError(f"{path}: cannot join the ensemble of {paths[0]}: voxel size {net.voxel_size} m and "
                            f"colour {net.use_color} against {first.voxel_size} m and {first.use_color}")
    ensemble = SegmenterEnsemble([one.model for one in loaded]).to(device).eval()
    meta = {"ensemble": [{"file": str(p), **one.meta} for p, one in zip(paths, loaded)]}
    return LoadedSegmenter(model=ensemble, config=loaded[0].config, meta=meta, optimizer=None, progress={})

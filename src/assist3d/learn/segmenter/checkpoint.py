"""Segmenter checkpoints that can never run code.

A checkpoint is a ``torch.save`` file holding only tensors, strings and numbers, read back with
``torch.load(..., weights_only=True)``: PyTorch's restricted unpickler refuses any other object, so
a crafted file cannot import or call anything. The configuration travels as a JSON string and is
validated by pydantic before a model is built.

Keys: ``format`` (``"assist3d-segmenter"``), ``version``, ``config`` (JSON of
:class:`SegmenterConfig`), ``meta`` (JSON: training sets, steps, seconds, ...), ``state_dict`` and,
for resumable training files only, ``optimizer`` and ``progress`` (JSON).

Training files of a run with ``optim.ema_decay`` also hold ``ema_state_dict``, the averaged weights
(float32 tensors): they are the trained model, so :func:`load_segmenter` builds the model from them
(``weights="live"``, for resuming, gives the optimiser's weights; both are kept in ``LoadedSegmenter``).

Precision (``save_segmenter(precision=...)``): float32 (training files), float16, or int8. int8
files (version 2) store every weight matrix or convolution kernel of at least ``INT8_MIN_NUMEL``
values as int8 codes in blocks of ``INT8_BLOCK`` consecutive values, each block with its own
float32 scale (its largest magnitude / 127) in ``int8_scales``; the small tensors (biases,
normalisation) stay float16. A larger network then fits the 5 MB cap of the shipped model
(~1.03 bytes per weight instead of 2). Symmetric blockwise codes are what GGML's Q8_0 and
bitsandbytes' blockwise quantisation use; written here because either library would be a heavy
dependency for ~20 lines, and loading stays ``weights_only`` (int8 and float tensors only).
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import torch
import torch.nn.functional as F

from ...core import reading
from ...core.errors import DataError, shown
from ...core.fileio import write_bytes_atomic
from .config import SegmenterConfig, legacy_config, parse_segmenter_config
from ..models.registry import build_model
from .model import Network, Segmenter, SegmenterEnsemble

FORMAT = "assist3d-segmenter"
VERSION = 1  # float32 / float16 files
VERSION_INT8 = 2  # files with int8 weights (``int8_scales``)
INT8_BLOCK = 64
INT8_MIN_NUMEL = 1024

Precision = Literal["float32", "float16", "int8"]
Weights = Literal["trained", "live"]


@dataclass
class LoadedSegmenter:
    """``model`` is in eval mode; ``ema_state`` holds a training file's averaged weights, if any."""

    model: Network
    config: SegmenterConfig
    meta: dict[str, Any]
    optimizer: dict | None
    progress: dict[str, Any]
    ema_state: dict[str, torch.Tensor] | None = None


def quantize_int8(t: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Blockwise symmetric int8 codes of ``t`` (same shape) and the float32 scale of each block of
    ``INT8_BLOCK`` consecutive values (row-major order; the last block may be shorter)."""
    flat = t.detach().float().reshape(-1)
    blocks = F.pad(flat, (0, (-flat.numel()) % INT8_BLOCK)).view(-1, INT8_BLOCK)
    scale = blocks.abs().amax(1) / 127.0
    scale = torch.where(scale > 0, scale, torch.ones_like(scale))
    codes = torch.round(blocks / scale[:, None]).clamp(-127, 127).to(torch.int8)
    return codes.reshape(-1)[: flat.numel()].view(t.shape).contiguous(), scale


def dequantize_int8(codes: torch.Tensor, scale: torch.Tensor) -> torch.Tensor:
    """The float32 tensor that :func:`quantize_int8` encoded."""
    flat = codes.reshape(-1).float()
    flat = F.pad(flat, (0, (-flat.numel()) % INT8_BLOCK)).view(-1, INT8_BLOCK) * scale.float()[:, None]
    return flat.reshape(-1)[: codes.numel()].view(codes.shape)


def _int8_candidate(v: torch.Tensor) -> bool:
    return v.is_floating_point() and v.dim() >= 2 and v.numel() >= INT8_MIN_NUMEL


def save_segmenter(path: str | Path, model: Segmenter, cfg: SegmenterConfig, *, meta: dict | None = None,
                   optimizer: torch.optim.Optimizer | None = None, progress: dict | None = None,
                   precision: Precision = "float32", ema: Segmenter | None = None) -> Path:
    """Write ``path`` atomically. ``precision`` float16 or int8 gives a smaller file to ship (module docstring)."""
    if precision not in ("float32", "float16", "int8"):
        raise ValueError(f"precision must be float32, float16 or int8, not {precision!r}")
    state: dict[str, torch.Tensor] = {}
    scales: dict[str, torch.Tensor] = {}
    for k, v in model.state_dict().items():
        if precision == "int8" and _int8_candidate(v):
            state[k], scales[k] = quantize_int8(v)
        elif precision != "float32" and v.is_floating_point():
            state[k] = v.detach().half().contiguous()
        else:
            state[k] = v.detach().contiguous()
    payload: dict[str, Any] = {
        "format": FORMAT, "version": VERSION_INT8 if scales else VERSION,
        "config": json.dumps(cfg.model_dump(mode="json")),
        "meta": json.dumps(meta or {}),
        "state_dict": state,
    }
    if scales:
        payload["int8_scales"] = scales
    if optimizer is not None:
        payload["optimizer"] = optimizer.state_dict()
    if ema is not None:
        payload["ema_state_dict"] = {k: v.detach().contiguous() for k, v in ema.state_dict().items()}
    if progress is not None:
        payload["progress"] = json.dumps(progress)
    buf = io.BytesIO()
    torch.save(payload, buf)
    path = Path(path)
    write_bytes_atomic(path, buf.getvalue())
    return path


def _json(path: Path, payload: dict, key: str) -> dict:
    raw = payload.get(key, "{}")
    if not isinstance(raw, str):
        raise DataError(f"{path}: not an assist3d segmenter checkpoint ({key!r} is not a JSON string)")
    try:
        value = reading.parse_json(raw, path)
    except DataError as e:
        raise DataError(f"{shown(path, 400)}: not an assist3d segmenter checkpoint ({key!r}: "
                        f"{reading.problem(e, path)})") from None
    if not isinstance(value, dict):
        raise DataError(f"{path}: not an assist3d segmenter checkpoint ({key!r} is not a JSON object)")
    return value


def _dequantized(path: Path, state: dict[str, torch.Tensor], scales: Any) -> dict[str, torch.Tensor]:
    """``state`` with its int8 entries decoded by their ``scales``; DataError if they do not match."""
    if not isinstance(scales, dict) or not all(isinstance(v, torch.Tensor) for v in scales.values()):
        raise DataError(f"{path}: not an assist3d segmenter checkpoint (int8_scales is not a dict of tensors)")
    out = dict(state)
    for k, scale in scales.items():
        codes = state.get(k)
        blocks = -(-codes.numel() // INT8_BLOCK) if codes is not None else -1
        if codes is None or codes.dtype != torch.int8 or scale.dim() != 1 or scale.numel() != blocks:
            raise DataError(f"{path}: int8 weights {k!r} do not match their scales")
        out[k] = dequantize_int8(codes, scale)
    return out


def load_segmenter(path: str | Path, device: str = "cpu", weights: Weights = "trained") -> LoadedSegmenter:
    """Read a checkpoint safely and build its model in eval mode; one-line :class:`DataError` otherwise.

    ``weights="trained"`` builds the model a run produced: the averaged weights when the file holds
    them (a training file of a run with ``optim.ema_decay``), else its weights; ``"live"`` builds the
    optimiser's weights (resuming a run)."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: checkpoint not found" + (" (it is a folder)" if path.is_dir() else ""))
    payload = reading.read_checkpoint(path, map_location=device)
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise DataError(f"{path}: not an assist3d segmenter checkpoint (no format tag {FORMAT!r})")
    if payload.get("version") not in (VERSION, VERSION_INT8):
        raise DataError(f"{path}: segmenter checkpoint version {payload.get('version')!r}; "
                        f"this assist3d reads {VERSION} and {VERSION_INT8}")
    cfg = parse_segmenter_config(legacy_config(_json(path, payload, "config"), str(path)), f"{path} config")
    meta = _json(path, payload, "meta")
    state = payload.get("state_dict")
    if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
        raise DataError(f"{path}: not an assist3d segmenter checkpoint (state_dict is not a dict of tensors)")
    state = _dequantized(path, state, payload.get("int8_scales", {}) if payload["version"] == VERSION_INT8 else {})
    model = build_model("segmenter", cfg.net)
    try:
        model.load_state_dict({k: v.float() if v.is_floating_point() else v for k, v in state.items()})
    except RuntimeError as e:
        first = str(e).strip().splitlines()[0][:200]
        raise DataError(f"{path}: the weights do not fit the model its config describes ({first})") from None
    model.to(device).eval()
    progress = _json(path, payload, "progress") if "progress" in payload else {}
    ema = payload.get("ema_state_dict")
    if ema is not None and (not isinstance(ema, dict) or set(ema) != set(state)
                            or not all(isinstance(v, torch.Tensor) and v.shape == state[k].shape for k, v in ema.items())):
        raise DataError(f"{path}: its averaged weights (ema_state_dict) do not match its model's")
    if ema is not None and weights == "trained":
        model.load_state_dict({k: v.float() if v.is_floating_point() else v for k, v in ema.items()})
    return LoadedSegmenter(model=model, config=cfg, meta=meta, optimizer=payload.get("optimizer"), progress=progress,
                           ema_state=ema)


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

"""One checkpoint format for every model of the registry, and one way to read it that can never run code.

A checkpoint is a ``torch.save`` file holding only tensors, strings and numbers, read back with
``torch.load(..., weights_only=True)``: PyTorch's restricted unpickler refuses any other object, so a
crafted file cannot import or call anything. Keys, in this order:

- ``format``: ``"assist3d-<model>"``, the registry name of the model (``assist3d-segmenter``,
  ``assist3d-mask3d``); ``version``: 1, or 2 for files with int8 weights;
- ``config`` (a JSON string: the model's configuration, validated by its owner before a model is built),
  ``meta`` (JSON: training sets, steps, seconds, ...), ``state_dict``, ``int8_scales`` (version 2 only);
- training files only: ``optimizer``, ``ema_state_dict`` (averaged weights, float32), ``progress`` (JSON:
  step, seconds, ...), ``states`` (other training states by name: a learning-rate scheduler, a gradient
  scaler).

Weight precision (:func:`write_checkpoint` ``precision``): float32 (training files), float16, or int8.
int8 stores every weight matrix or convolution kernel of at least ``INT8_MIN_NUMEL`` values as int8 codes
in blocks of ``INT8_BLOCK`` consecutive values, each block with its own float32 scale (its largest
magnitude / 127) in ``int8_scales``; the small tensors (biases, normalisation) stay float16 (~1.03 bytes
per weight instead of 2). Symmetric blockwise codes are what GGML's Q8_0 and bitsandbytes' blockwise
quantisation use; written here because either library would be a heavy dependency for ~20 lines, and
loading stays ``weights_only`` (int8 and float tensors only).

Files of the Mask3D-style model written before this format (a plain dict with ``model`` and ``config``)
are read too (:func:`read_checkpoint` with ``model="mask3d"``).
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import torch
import torch.nn.functional as F

from ..core import reading
from ..core.errors import DataError, shown
from ..core.fileio import write_bytes_atomic

FORMAT_PREFIX = "assist3d-"
VERSION = 1  # float32 / float16 files
VERSION_INT8 = 2  # files with int8 weights (``int8_scales``)
INT8_BLOCK = 64
INT8_MIN_NUMEL = 1024

Precision = Literal["float32", "float16", "int8"]


@dataclass
class Checkpoint:
    """The contents of a checkpoint file; ``state_dict`` decoded (int8 weights as float32)."""

    model: str
    config: dict[str, Any]
    state_dict: dict[str, torch.Tensor]
    meta: dict[str, Any] = field(default_factory=dict)
    optimizer: dict | None = None
    progress: dict[str, Any] | None = None
    ema_state: dict[str, torch.Tensor] | None = None
    states: dict[str, Any] = field(default_factory=dict)
    version: int = VERSION


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


def write_checkpoint(path: str | Path, ckpt: Checkpoint, *, precision: Precision = "float32") -> Path:
    """Write ``ckpt`` to ``path`` atomically; ``precision`` float16 or int8 gives a smaller file to ship."""
    if precision not in ("float32", "float16", "int8"):
        raise ValueError(f"precision must be float32, float16 or int8, not {precision!r}")
    state: dict[str, torch.Tensor] = {}
    scales: dict[str, torch.Tensor] = {}
    for k, v in ckpt.state_dict.items():
        if precision == "int8" and _int8_candidate(v):
            state[k], scales[k] = quantize_int8(v)
        elif precision != "float32" and v.is_floating_point():
            state[k] = v.detach().half().contiguous()
        else:
            state[k] = v.detach().contiguous()
    payload: dict[str, Any] = {
        "format": FORMAT_PREFIX + ckpt.model, "version": VERSION_INT8 if scales else VERSION,
        "config": json.dumps(ckpt.config),
        "meta": json.dumps(ckpt.meta),
        "state_dict": state,
    }
    if scales:
        payload["int8_scales"] = scales
    if ckpt.optimizer is not None:
        payload["optimizer"] = ckpt.optimizer
    if ckpt.ema_state is not None:
        payload["ema_state_dict"] = {k: v.detach().contiguous() for k, v in ckpt.ema_state.items()}
    if ckpt.progress is not None:
        payload["progress"] = json.dumps(ckpt.progress)
    if ckpt.states:
        payload["states"] = dict(ckpt.states)
    buf = io.BytesIO()
    torch.save(payload, buf)
    path = Path(path)
    write_bytes_atomic(path, buf.getvalue())
    return path


def load_payload(path: str | Path, device: str = "cpu") -> Any:
    """``torch.load`` of ``path`` with ``weights_only`` through the reading layer
    (:func:`assist3d.core.reading.read_checkpoint`): one-line :class:`DataError` for a missing, unreadable
    or code-carrying file."""
    path = Path(path)
    if path.is_dir():
        raise DataError(f"{path}: checkpoint not found (it is a folder)")
    return reading.read_checkpoint(path, map_location=device)


def _json(path: Path, payload: dict, key: str, what: str) -> dict:
    raw = payload.get(key, "{}")
    if not isinstance(raw, str):
        raise DataError(f"{path}: not an {what} ({key!r} is not a JSON string)")
    try:
        value = reading.parse_json(raw, path)
    except DataError as e:
        raise DataError(f"{shown(path, 400)}: not an {what} ({key!r}: {reading.problem(e, path)})") from None
    if not isinstance(value, dict):
        raise DataError(f"{path}: not an {what} ({key!r} is not a JSON object)")
    return value


def _tensors(path: Path, value: Any, key: str, what: str) -> dict[str, torch.Tensor]:
    if not isinstance(value, dict) or not all(isinstance(v, torch.Tensor) for v in value.values()):
        raise DataError(f"{path}: not an {what} ({key} is not a dict of tensors)")
    return value


def _dequantized(path: Path, state: dict[str, torch.Tensor], scales: Any, what: str) -> dict[str, torch.Tensor]:
    """``state`` with its int8 entries decoded by their ``scales``; DataError if they do not match."""
    scales = _tensors(path, scales, "int8_scales", what)
    out = dict(state)
    for k, scale in scales.items():
        codes = state.get(k)
        blocks = -(-codes.numel() // INT8_BLOCK) if codes is not None else -1
        if codes is None or codes.dtype != torch.int8 or scale.dim() != 1 or scale.numel() != blocks:
            raise DataError(f"{path}: int8 weights {k!r} do not match their scales")
        out[k] = dequantize_int8(codes, scale)
    return out


def _legacy_mask3d(path: Path, payload: dict) -> Checkpoint:
    """A Mask3D-style file written before this format: ``model``, ``config`` (a dict), optimiser, scheduler,
    scaler, epoch, step."""
    if not isinstance(payload.get("config"), dict):
        raise DataError(f"{path}: not an assist3d checkpoint (expected keys model, config)")
    state = _tensors(path, payload["model"], "model", "assist3d checkpoint")
    states = {k: payload[k] for k in ("scheduler", "scaler") if payload.get(k) is not None}
    progress = {k: payload[k] for k in ("epoch", "step") if k in payload}
    return Checkpoint(model="mask3d", config=payload["config"], state_dict=state, optimizer=payload.get("optimizer"),
                      progress=progress, states=states)


def read_checkpoint(path: str | Path, device: str = "cpu", *, model: str | None = None) -> Checkpoint:
    """Read a checkpoint safely (:func:`load_payload`); ``model`` (a registry name) refuses a file of
    another model. One-line :class:`DataError` for anything that is not a well-formed checkpoint."""
    path = Path(path)
    payload = load_payload(path, device)
    what = f"assist3d {model} checkpoint" if model else "assist3d checkpoint"
    if not isinstance(payload, dict):
        raise DataError(f"{path}: not an {what} (no format tag)")
    tag = payload.get("format")
    if tag is None and model in (None, "mask3d") and "model" in payload and "config" in payload:
        return _legacy_mask3d(path, payload)
    if not isinstance(tag, str) or not tag.startswith(FORMAT_PREFIX) or (model and tag != FORMAT_PREFIX + model):
        expected = f"{FORMAT_PREFIX}{model}" if model else f"{FORMAT_PREFIX}<model>"
        raise DataError(f"{path}: not an {what} (no format tag {expected!r})")
    version = payload.get("version")
    if version not in (VERSION, VERSION_INT8):
        raise DataError(f"{path}: {tag} checkpoint version {version!r}; this assist3d reads {VERSION} and "
                        f"{VERSION_INT8}")
    state = _tensors(path, payload.get("state_dict"), "state_dict", what)
    if version == VERSION_INT8:
        state = _dequantized(path, state, payload.get("int8_scales", {}), what)
    ema = payload.get("ema_state_dict")
    if ema is not None and (not isinstance(ema, dict) or set(ema) != set(state) or not all(
            isinstance(v, torch.Tensor) and v.shape == state[k].shape for k, v in ema.items())):
        raise DataError(f"{path}: its averaged weights (ema_state_dict) do not match its model's")
    states = payload.get("states", {})
    if not isinstance(states, dict):
        raise DataError(f"{path}: not an {what} ('states' is not a dict)")
    return Checkpoint(model=tag[len(FORMAT_PREFIX):], config=_json(path, payload, "config", what),
                      state_dict=state, meta=_json(path, payload, "meta", what), optimizer=payload.get("optimizer"),
                      progress=_json(path, payload, "progress", what) if "progress" in payload else None,
                      ema_state=ema, states=states, version=version)

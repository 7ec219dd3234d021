"""Segmenter checkpoints that can never run code.

A checkpoint is a ``torch.save`` file holding only tensors, strings and numbers, read back with
``torch.load(..., weights_only=True)``: PyTorch's restricted unpickler refuses any other object, so
a crafted file cannot import or call anything. The configuration travels as a JSON string and is
validated by pydantic before a model is built.

Keys: ``format`` (``"assist3d-segmenter"``), ``version``, ``config`` (JSON of
:class:`SegmenterConfig`), ``meta`` (JSON: training sets, steps, seconds, ...), ``state_dict`` and,
for resumable training files only, ``optimizer`` and ``progress`` (JSON).
"""

from __future__ import annotations

import io
import json
import pickle
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from ...core.errors import DataError
from ...core.fileio import write_bytes_atomic
from .config import SegmenterConfig, parse_segmenter_config
from .model import Segmenter

FORMAT = "assist3d-segmenter"
VERSION = 1


@dataclass
class LoadedSegmenter:
    model: Segmenter
    config: SegmenterConfig
    meta: dict[str, Any]
    optimizer: dict | None
    progress: dict[str, Any]


def save_segmenter(path: str | Path, model: Segmenter, cfg: SegmenterConfig, *, meta: dict | None = None,
                   optimizer: torch.optim.Optimizer | None = None, progress: dict | None = None,
                   half: bool = False) -> Path:
    """Write ``path`` atomically. ``half`` stores float tensors as float16 (a smaller file to ship)."""
    state = {k: (v.half() if half and v.is_floating_point() else v).contiguous() for k, v in model.state_dict().items()}
    payload: dict[str, Any] = {
        "format": FORMAT, "version": VERSION,
        "config": json.dumps(cfg.model_dump(mode="json")),
        "meta": json.dumps(meta or {}),
        "state_dict": state,
    }
    if optimizer is not None:
        payload["optimizer"] = optimizer.state_dict()
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
        value = json.loads(raw)
    except json.JSONDecodeError as e:
        raise DataError(f"{path}: not an assist3d segmenter checkpoint ({key!r} is not valid JSON: {e})") from None
    if not isinstance(value, dict):
        raise DataError(f"{path}: not an assist3d segmenter checkpoint ({key!r} is not a JSON object)")
    return value


def load_segmenter(path: str | Path, device: str = "cpu") -> LoadedSegmenter:
    """Read a checkpoint safely and build its model in eval mode; one-line :class:`DataError` otherwise."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: checkpoint not found" + (" (it is a folder)" if path.is_dir() else ""))
    if not zipfile.is_zipfile(path):
        raise DataError(f"{path}: not a readable checkpoint (not a PyTorch archive)")
    try:
        payload = torch.load(path, map_location=device, weights_only=True)
    except pickle.UnpicklingError as e:
        found = re.search(r"Unsupported global: GLOBAL ([\w.]+)", str(e))
        what = f": {found.group(1)}" if found else ""
        raise DataError(f"{path}: refused: the file holds objects other than tensors and numbers{what}; "
                        "loading it could run code") from None
    except (RuntimeError, EOFError, OSError, ValueError, zipfile.BadZipFile, KeyError, AttributeError) as e:
        raise DataError(f"{path}: not a readable checkpoint ({type(e).__name__})") from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise DataError(f"{path}: not an assist3d segmenter checkpoint (no format tag {FORMAT!r})")
    if payload.get("version") != VERSION:
        raise DataError(f"{path}: segmenter checkpoint version {payload.get('version')!r}; this assist3d reads {VERSION}")
    cfg = parse_segmenter_config(_json(path, payload, "config"), f"{path} config")
    meta = _json(path, payload, "meta")
    state = payload.get("state_dict")
    if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
        raise DataError(f"{path}: not an assist3d segmenter checkpoint (state_dict is not a dict of tensors)")
    model = Segmenter(cfg.net)
    try:
        model.load_state_dict({k: v.float() if v.is_floating_point() else v for k, v in state.items()})
    except RuntimeError as e:
        first = str(e).strip().splitlines()[0][:200]
        raise DataError(f"{path}: the weights do not fit the model its config describes ({first})") from None
    model.to(device).eval()
    progress = _json(path, payload, "progress") if "progress" in payload else {}
    return LoadedSegmenter(model=model, config=cfg, meta=meta, optimizer=payload.get("optimizer"), progress=progress)

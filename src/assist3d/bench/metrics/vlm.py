"""Layout reasonability scored by a vision-language model (the paper's GPT-4o metric).

``score_layout(images, cfg)`` sends a few rendered views (PNG bytes, as ``image_url`` data URIs)
with the ``vlm_score.txt`` prompt and returns ``(score 0-100 | None, details)``; the answer must
be JSON ``{"score": <0-100>, "reason": "..."}``; a bad answer gets one repair round. The same
client gives time-outs, retries, the size cap, the concurrency limit and the on-disk cache (the
key covers the images, so re-scoring an unchanged scene is free).

``vlm_layout_score(scene_dir, cfg)`` renders a dataset scene folder (``coord.npy`` +
``color.npy``, the Pointcept layout every generated scene has) and scores it; it returns None
when no endpoint is configured or the endpoint fails.
"""

from __future__ import annotations

import base64
import logging
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from ...config import LLMConfig
from ...core.contracts import Room
from ...core import reading
from ...core.errors import ConfigError, DataError, LLMError, inert, shown
from ...llm.cache import ResponseCache
from ...llm.client import ChatClient, Usage
from ...llm.prompts import describe_room, load_template, render_repair_message
from ...llm.schema import parse_json_text
from .views import render_point_views

log = logging.getLogger(__name__)

def vlm_model(cfg: LLMConfig) -> str | None:
    return cfg.vlm_model or cfg.model


def check_score(data: Any) -> tuple[float | None, str, str | None]:
    """``(score, reason, problem)`` for a decoded answer; ``problem`` is None when it is good."""
    if not isinstance(data, dict) or "score" not in data:
        return None, "", 'the answer must be a JSON object {"score": <0-100>, "reason": "..."}'
    s = data["score"]
    if isinstance(s, str):
        try:
            s = float(s.strip().rstrip("%"))
        except ValueError:
            return None, "", f"score {data['score']!r} is not a number"
    if isinstance(s, bool) or not isinstance(s, (int, float)) or not math.isfinite(s):
        return None, "", f"score {data['score']!r} is not a number"
    if not 0 <= s <= 100:
        return None, "", f"score {s} is outside 0-100"
    reason = data.get("reason", "")
    return float(s), reason if isinstance(reason, str) else str(reason), None


def _client(cfg: LLMConfig, cache: ResponseCache | None) -> ChatClient:
    model = vlm_model(cfg)
    if not cfg.base_url or not model:
        raise ConfigError("the VLM layout score needs llm.base_url and llm.vlm_model (or llm.model)")
    return ChatClient(cfg, model=model, cache=cache)  # the circuit breaker is shared across clients


def score_layout(images: list[bytes], cfg: LLMConfig, *, room: str = "",
                 cache: ResponseCache | None = None) -> tuple[float | None, dict[str, Any]]:
    """Ask the VLM for a 0-100 layout score of the scene shown in ``images`` (PNG bytes).

    Returns ``(score, details)``; ``score`` is None when the endpoint failed or never gave a
    usable answer (``details["error"]`` says why). ``details`` also holds model, reason,
    cached, llm_calls, cache_hits, repairs, prompt_tokens, completion_tokens, seconds.
    """
    if not images:
        raise ValueError("score_layout: no images")
    client = _client(cfg, cache)
    usage = Usage()
    t0 = time.monotonic()
    tpl = load_template("vlm", cfg.prompt_dir)
    system, text = tpl.render({"views": str(len(images)), "room": room})
    parts: list[dict[str, Any]] = [{"type": "text", "text": text}]
    for png in images:
        parts.append({"type": "image_url", "image_url": {
            "url": "data:image/png;base64," + base64.b64encode(png).decode("ascii")}})
    messages: list[dict[str, Any]] = ([{"role": "system", "content": system}] if system else [])
    messages.append({"role": "user", "content": parts})
    details: dict[str, Any] = {"model": client.model, "reason": "", "cached": False, "repairs": 0}
    score: float | None = None
    try:
        answer = client.complete(messages, usage=usage)
        details["cached"] = answer.cached
        data, problem = parse_json_text(answer.content)
        if problem is None:
            score, details["reason"], problem = check_score(data)
        if problem is not None:
            details["repairs"] = 1
            messages = messages + [{"role": "assistant", "content": answer.content},
                                   {"role": "user", "content": render_repair_message([problem], cfg.prompt_dir)}]
            answer = client.complete(messages, usage=usage)
            data, problem = parse_json_text(answer.content)
            if problem is None:
                score, details["reason"], problem = check_score(data)
            if problem is not None:
                raise LLMError(f"no usable score after one repair round: {problem}")
    except LLMError as e:
        log.warning("VLM layout score failed: %s", inert(e))
        details["error"] = str(e)
        score = None
    details.update(usage.as_dict())
    details["seconds"] = round(time.monotonic() - t0, 4)
    return score, details


def load_scene_points(scene_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    """coord (N, 3) float32 and color (N, 3) uint8 of a Pointcept-layout scene folder."""
    arrays = []
    for name in ("coord.npy", "color.npy"):
        p = Path(scene_dir) / name
        if not p.is_file():
            raise DataError(f"{p}: missing (a scene folder needs coord.npy and color.npy)")
        a = reading.read_npy(p)
        if a.ndim != 2 or a.shape[1] < 3:
            raise DataError(f"{p}: expected an (N, 3) array, got shape {a.shape}")
        arrays.append(a[:, :3])
    coord, color = arrays
    if len(coord) != len(color):
        raise DataError(f"{scene_dir}: coord.npy has {len(coord)} rows but color.npy has {len(color)}")
    if color.dtype != np.uint8:
        color = np.clip(color * (255.0 if color.max(initial=0) <= 1.0 else 1.0), 0, 255).astype(np.uint8)
    return coord.astype(np.float32), color


def vlm_layout_score(scene_dir: Path, cfg: LLMConfig, *, n_views: int = 4, size: int = 512) -> float | None:
    """The VLM layout score (0-100) of one scene folder, or None when no endpoint is configured
    or it failed. Views are rendered from the scene's points (``coord.npy`` / ``color.npy``)."""
    if not cfg.base_url or not vlm_model(cfg):
        return None
    coord, color = load_scene_points(Path(scene_dir))
    images = render_point_views(coord, color, n=n_views, size=size)
    score, details = score_layout(images, cfg, room=_room_text(Path(scene_dir) / "layout.json"))
    log.info("%s: VLM layout score %s (%s)", shown(scene_dir, 400), score,
             shown(details.get("reason") or details.get("error", "")))
    return score


def _room_text(layout_json: Path) -> str:
    """A one-line room description from a scene's layout.json, or "" when there is none."""
    if not layout_json.is_file():
        return ""
    try:
        room = Room.from_json(reading.read_json(layout_json)["room"])
    except (DataError, ValueError, KeyError, TypeError) as e:
        log.debug("%s: no room description (%s)", layout_json, e)
        return ""
    return f"It is a {describe_room(room)}."

"""On-disk cache of chat-completion answers.

The key is a hash of the model name, the full request messages and the temperature: the base
URL is not part of it (the same model behind another server answers from the same cache) and
neither is the API key, which never reaches this module. Each entry is one small JSON file
written atomically, so concurrent workers never see half-written answers; a hit returns exactly
the stored text, which makes re-running a dataset free and reproducible.
"""

from __future__ import annotations

import hashlib
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..core import reading
from ..core.errors import DataError
from ..core.fileio import write_json_atomic
from ..core.paths import cache_root

log = logging.getLogger(__name__)

CACHE_VERSION = 1


def cache_key(model: str, messages: list[dict[str, Any]], temperature: float) -> str:
    """sha256 hex digest of the canonical JSON of (model, messages, temperature)."""
    payload = json.dumps({"v": CACHE_VERSION, "model": model, "messages": messages,
                          "temperature": round(float(temperature), 6)},
                         sort_keys=True, ensure_ascii=False, separators=(",", ":"))
    return hashlib.sha256(payload.encode("utf-8")).hexdigest()


@dataclass(frozen=True)
class CachedAnswer:
    """A stored answer: the assistant text and the token usage of the call that produced it."""

    content: str
    prompt_tokens: int
    completion_tokens: int
    finish_reason: str = ""  # "stop", "length" (cut off at max_tokens), ... or "" when unknown


def default_cache_dir() -> Path:
    return cache_root() / "llm"


class ResponseCache:
    """``<folder>/<key[:2]>/<key>.json`` files holding ``{"key", "model", "content", "usage"}``."""

    def __init__(self, folder: str | Path | None = None) -> None:
        self.folder = Path(folder).expanduser() if folder else default_cache_dir()

    def path(self, key: str) -> Path:
        return self.folder / key[:2] / f"{key}.json"

    def get(self, key: str) -> CachedAnswer | None:
        """The stored answer for ``key`` or None. A corrupt entry is ignored (and logged)."""
        p = self.path(key)
        if not p.exists():
            return None
        try:
            d = reading.read_json(p)
            if d.get("key") != key or not isinstance(d.get("content"), str):
                raise ValueError("key or content missing")
            usage = d.get("usage") or {}
            return CachedAnswer(d["content"], int(usage.get("prompt_tokens", 0)),
                                int(usage.get("completion_tokens", 0)), str(d.get("finish_reason", "")))
        except (DataError, ValueError, TypeError, AttributeError) as e:
            log.warning("%s: corrupt cache entry (%s); ignoring it", p, e)
            return None

    def put(self, key: str, model: str, answer: CachedAnswer) -> None:
        write_json_atomic(self.path(key), {
            "key": key,
            "model": model,
            "content": answer.content,
            "usage": {"prompt_tokens": answer.prompt_tokens, "completion_tokens": answer.completion_tokens},
            "finish_reason": answer.finish_reason,
        })

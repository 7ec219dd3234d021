"""OpenAI-compatible endpoints: the chat client, its on-disk cache, prompt templates and answer parsing.

Public facade: :class:`ChatClient`, :class:`ResponseCache` — the hardened client and its cache.

What is built on it lives with its role: the LLM relation planner in
:mod:`assist3d.planning.llm_planner`, the room-type object proposals the planner asks
for in :mod:`assist3d.planning.llm_rooms`, and the VLM layout score with the other metrics in
:mod:`assist3d.bench.metrics.vlm` (views: :mod:`assist3d.bench.metrics.views`). They import ``llm``,
never the reverse. See ``docs/llm.md``.
"""

from __future__ import annotations

from .cache import ResponseCache, cache_key
from .client import ChatAnswer, ChatClient, Usage

__all__ = ["ChatAnswer", "ChatClient", "ResponseCache", "Usage", "cache_key"]

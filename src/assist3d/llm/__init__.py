"""LLM-guided relation planning and VLM layout scoring through OpenAI-compatible endpoints.

Public facade:

* :class:`LLMPlanner` — ``LLMPlanner(cfg.llm, fallback=planner).plan(request, rng=rng)``.
* :func:`score_layout`, :func:`vlm_layout_score` — the paper's layout reasonability score.
* :func:`render_views`, :func:`render_point_views` — PNG views of a scene mesh or point cloud.
* :class:`ChatClient`, :class:`ResponseCache` — the hardened client and its on-disk cache.

See ``docs/llm.md``.
"""

from __future__ import annotations

from .cache import ResponseCache, cache_key
from .client import ChatAnswer, ChatClient, Usage
from .planner import LLMPlanner
from .views import render_point_views, render_views
from .vlm import score_layout, vlm_layout_score

__all__ = ["ChatAnswer", "ChatClient", "LLMPlanner", "ResponseCache", "Usage", "cache_key", "render_point_views",
           "render_views", "score_layout", "vlm_layout_score"]

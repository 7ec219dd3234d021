"""OpenAI-compatible endpoints: the chat client, its cache, prompt templates and VLM layout scoring.

Public facade:

* :func:`score_layout`, :func:`vlm_layout_score` — the paper's layout reasonability score.
* :func:`render_views`, :func:`render_point_views` — PNG views of a scene mesh or point cloud.
* :class:`ChatClient`, :class:`ResponseCache` — the hardened client and its on-disk cache.

The LLM relation planner built on this client is :class:`assist3d.planning.llm_planner.LLMPlanner`
(``planning`` imports ``llm``, never the reverse). See ``docs/llm.md``.
"""

from __future__ import annotations

from .cache import ResponseCache, cache_key
from .client import ChatAnswer, ChatClient, Usage
from .views import render_point_views, render_views
from .vlm import score_layout, vlm_layout_score

__all__ = ["ChatAnswer", "ChatClient", "ResponseCache", "Usage", "cache_key", "render_point_views", "render_views",
           "score_layout", "vlm_layout_score"]

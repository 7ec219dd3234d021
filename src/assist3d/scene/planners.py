"""Choosing the relation planner from the configuration."""

from __future__ import annotations

import logging
import threading

from ..config import GenerateConfig
from .relations import Planner
from .rules import RulePlanner

log = logging.getLogger(__name__)

_said_rules = False
_said_lock = threading.Lock()


def _say_rules_once() -> None:
    global _said_rules
    with _said_lock:
        if _said_rules:
            return
        _said_rules = True
    log.info("layout: rule-based planner (no LLM endpoint configured)")


def make_planner(cfg: GenerateConfig) -> Planner:
    """The planner a run uses.

    An :class:`assist3d.llm.planner.LLMPlanner` (with a :class:`RulePlanner` fallback) when
    ``layout.planner == "llm"`` or both ``llm.base_url`` and ``llm.model`` are set; otherwise the
    :class:`RulePlanner`, saying so once per process. ``layout.planner == "none"`` (the RandomRooms
    baseline) still gets a rule planner for the groups that are planned at all.
    """
    wants_llm = cfg.layout.planner == "llm" or (
        cfg.layout.planner != "none" and bool(cfg.llm.base_url) and bool(cfg.llm.model))
    rules = RulePlanner()
    if not wants_llm:
        if cfg.layout.planner == "rules":
            _say_rules_once()
        return rules
    from ..llm.planner import LLMPlanner  # loaded only when an LLM endpoint is configured (docs/architecture.md)

    return LLMPlanner(cfg.llm, fallback=rules)

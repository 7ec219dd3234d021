"""Choosing the relation planner from the configuration."""

from __future__ import annotations

import logging
import threading
from typing import Callable

from ..config import GenerateConfig
from ..core.registry import Registry
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


#: relation planners by name: a factory ``(cfg) -> Planner`` (chosen by :func:`planner_name`)
PLANNERS: Registry[Callable[[GenerateConfig], Planner]] = Registry("relation planner")


@PLANNERS.register("rules")
def _rules(cfg: GenerateConfig) -> Planner:
    return RulePlanner()


@PLANNERS.register("llm")
def _llm(cfg: GenerateConfig) -> Planner:
    from .llm_planner import LLMPlanner  # loaded only when an LLM endpoint is configured (docs/architecture.md)

    return LLMPlanner(cfg.llm, fallback=RulePlanner())


def planner_name(cfg: GenerateConfig) -> str:
    """The name in :data:`PLANNERS` of the planner a run uses.

    ``"llm"`` when ``layout.planner == "llm"``, or when both ``llm.base_url`` and ``llm.model`` are
    set and ``layout.planner`` is not ``"none"``; otherwise ``layout.planner``, except that ``"none"``
    (the RandomRooms baseline) gets the rule planner for the groups that are planned at all.
    """
    if cfg.layout.planner == "llm" or (
            cfg.layout.planner != "none" and bool(cfg.llm.base_url) and bool(cfg.llm.model)):
        return "llm"
    return "rules" if cfg.layout.planner == "none" else cfg.layout.planner


def make_planner(cfg: GenerateConfig) -> Planner:
    """The planner a run uses (:func:`planner_name`), saying once per process when it is the rule planner."""
    name = planner_name(cfg)
    if name == "rules" and cfg.layout.planner == "rules":
        _say_rules_once()
    return PLANNERS.get(name)(cfg)

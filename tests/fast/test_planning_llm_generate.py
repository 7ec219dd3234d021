"""generate with an LLM endpoint (the local fake server): the manifest records the models, calls
and cache hits; a re-run into a new folder is answered from the cache; no secret is written."""

from __future__ import annotations

import json
import os

import pytest

from assist3d.config import parse_config
from assist3d.export.manifest import llm_summary
from assist3d.pipeline import generate_dataset
from llm_fakeserver import SENTINEL, FakeServer, Step, files_containing
from test_planning_llm_layout import _answer

MODEL = "fake-gen"


def _cfg(url: str, cache: str) -> dict:
    return {
        "seed": 5,
        "assets": {"procedural_count": 60},
        "selection": {"floor_count": 4, "wall_count": 2, "on_top_count": 1},
        "room": {"area_min": 10.0, "area_max": 14.0},
        "layout": {"group_budget_s": 120.0},
        "render": {"width": 64, "height": 48, "fx": 57.8, "fy": 57.8, "vantage_points": 1, "views_per_point": 4},
        "llm": {"base_url": url, "model": MODEL, "timeout_s": 2.0, "retries": 0, "cache_dir": cache},
    }


def test_manifest_accounts_llm_calls_and_cache_hits(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    cache = str(tmp_path / "llm-cache")
    with FakeServer([], responder=_answer) as srv:
        generate_dataset(parse_config(_cfg(srv.url, cache)), tmp_path / "a", range(2))
        calls = len(srv.requests)
    man = json.loads((tmp_path / "a" / "manifest.json").read_text())
    summary = man["llm"]
    assert summary["models"] == [MODEL]
    assert summary["llm_calls"] == calls > 0 and summary.get("cache_hits", 0) == 0
    assert summary["groups_by_planner"]["rules"] >= 2  # the fake server fails every wall group
    assert all("llm" in e for e in man["scenes"])
    # the same dataset into another folder: every group the server answered comes from the cache
    with FakeServer([Step(status=500)] * 50) as srv2:
        generate_dataset(parse_config(_cfg(srv2.url, cache)), tmp_path / "b", range(2))
    man2 = json.loads((tmp_path / "b" / "manifest.json").read_text())
    assert man2["llm"]["cache_hits"] == calls - summary["groups_by_planner"]["rules"]
    for name in ("coord.npy", "instance.npy"):
        for sid in ("scene_000000", "scene_000001"):
            assert (tmp_path / "a" / sid / name).read_bytes() == (tmp_path / "b" / sid / name).read_bytes()
    assert not files_containing(SENTINEL, tmp_path, os.environ["ASSIST3D_CACHE"])


def test_llm_summary_of_rule_only_scenes():
    s = llm_summary([{"planner": {"floor": "rules", "wall": "rules"}, "llm": {}}])
    assert s == {"models": [], "groups_by_planner": {"rules": 2}}

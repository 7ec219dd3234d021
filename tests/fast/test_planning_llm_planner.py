"""LLM planner against a real local chat-completions server replaying scripted answers."""

from __future__ import annotations

import json
import logging
import os
import time

import numpy as np
import pytest

from assist3d.config import LLMConfig
from assist3d.core.contracts import AssetRecord, Opening, PlacedInstance, Relation, Room
from assist3d.planning.llm_planner import LLMPlanner
from assist3d.planning.relations import GroupPlan, PlannedObject, PlanRequest, group_kind, validate_plan
from llm_fakeserver import SENTINEL, FakeServer, Step, files_containing

MODEL = "fake-model"
TIMEOUT = 1.0


class ReversePlanner:
    """A deterministic stand-in for the rule planner: objects in reverse order."""

    name = "rules"

    def plan(self, request: PlanRequest, *, rng: np.random.Generator) -> GroupPlan:
        kind = group_kind(request.group)
        order = []
        for pos, src in enumerate(reversed(range(len(request.objects)))):
            if kind == "floor":
                rels = (Relation("edge", hard=True),) + ((Relation("near", pos - 1),) if pos else ())
            elif kind == "wall":
                rels = (Relation("height", None, (1.0, 1.5), True),)
            else:
                rels = (Relation("on", request.support.id, hard=True),)
            order.append(PlannedObject(src, rels))
        return GroupPlan(request.group, tuple(order), "rules", ("reverse order",), {"rule_seconds": 0.0})


def _asset(i: int, name: str, cls: str, size=(1.0, 0.5, 0.8), groups=("floor",)) -> AssetRecord:
    return AssetRecord(id=f"proc:{cls}/{i}", source="procedural", name=name, class_name=cls, groups=groups,
                       size=size)


ROOM = Room(((0.0, 0.0), (5.0, 0.0), (5.0, 4.0), (0.0, 4.0)), 2.8,
            (Opening("door", 0, 1.0, 0.9, 0.0, 2.1),), False)
FLOOR = PlanRequest("floor", (_asset(0, "Oak dining table", "table", (1.6, 0.9, 0.75)),
                              _asset(1, "Wooden chair", "chair", (0.45, 0.5, 0.9)),
                              _asset(2, "Bookcase", "bookshelf", (0.8, 0.35, 1.9))), ROOM)


def _pose(x: float, y: float, z: float = 0.0) -> np.ndarray:
    p = np.eye(4)
    p[:3, 3] = (x, y, z)
    return p


SOFA = PlacedInstance(4, "proc:sofa/0", "sofa", "floor", _pose(2.0, 3.5))
WALL = PlanRequest("wall", (_asset(5, "Painting", "picture", (0.9, 0.04, 0.6), ("wall",)),
                            _asset(6, "Clock", "clock", (0.3, 0.05, 0.3), ("wall",))), ROOM, placed=(SOFA,))
TABLE = PlacedInstance(9, "proc:table/0", "table", "floor", _pose(2.5, 2.0))
ONTOP = PlanRequest("on:9", (_asset(7, "Lamp", "lamp", (0.2, 0.2, 0.4), ("obj",)),
                             _asset(8, "Mug", "cup", (0.08, 0.08, 0.1), ("obj",))), ROOM, placed=(SOFA, TABLE),
                    support=TABLE)

GOOD_FLOOR = json.dumps({"objects": [
    {"index": 2, "relations": [{"relation": "edge"}]},
    {"index": 0, "relations": [{"relation": "middle"}, {"relation": "far", "target": 2}]},
    {"index": 1, "relations": [{"relation": "around", "target": 0}, {"relation": "near", "target": 0, "hard": True}]},
]})


@pytest.fixture
def secret_env(monkeypatch, tmp_path, caplog):
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    caplog.set_level(logging.DEBUG)
    yield
    assert SENTINEL not in caplog.text
    assert not files_containing(SENTINEL, tmp_path, os.environ["ASSIST3D_CACHE"])


def _cfg(server: FakeServer, tmp_path, **kw) -> LLMConfig:
    base = dict(base_url=server.url, model=MODEL, timeout_s=TIMEOUT, retries=1, backoff_s=0.05,
                max_response_bytes=4000, cache_dir=str(tmp_path / "llm"))
    base.update(kw)
    return LLMConfig(**base)


def _plan(cfg: LLMConfig, request: PlanRequest = FLOOR) -> tuple[GroupPlan, float]:
    t0 = time.monotonic()
    plan = LLMPlanner(cfg, fallback=ReversePlanner()).plan(request, rng=np.random.default_rng(0))
    elapsed = time.monotonic() - t0
    assert validate_plan(plan, request) == []
    return plan, elapsed


def test_good_answer(secret_env, tmp_path):
    with FakeServer([Step(GOOD_FLOOR)]) as srv:
        plan, elapsed = _plan(_cfg(srv, tmp_path))
    assert plan.planner == f"llm:{MODEL}"
    assert [p.source for p in plan.order] == [2, 0, 1]
    # targets given as object indices become positions in the plan: table (index 0) is position 1
    chair = plan.order[2]
    assert Relation("around", 1) in chair.relations and Relation("near", 1, (), True) in chair.relations
    assert plan.order[0].relations == (Relation("edge"),)  # soft unless the answer says "hard": true
    assert plan.stats["llm_calls"] == 1 and plan.stats["cache_hits"] == 0 and plan.stats["repairs"] == 0
    assert plan.stats["prompt_tokens"] == 11 and plan.stats["completion_tokens"] == 7
    assert plan.stats["llm_seconds"] <= plan.stats["seconds"] < TIMEOUT
    req = srv.requests[0]
    assert req["path"] == "/v1/chat/completions"
    assert req["headers"]["Authorization"] == f"Bearer {SENTINEL}"
    body = req["json"]
    assert body["model"] == MODEL and body["response_format"] == {"type": "json_object"}
    user = body["messages"][-1]["content"]
    assert '0: "Oak dining table" (class: table), 1.60 x 0.90 x 0.75 m' in user
    assert "- around (" in user and "- height" not in user and "- on (" not in user  # floor vocabulary only


def test_malformed_json_then_good_repair(secret_env, tmp_path):
    with FakeServer([Step('{"objects": [ {"index": 2,, }'), Step(GOOD_FLOOR)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path))
    assert plan.planner == f"llm:{MODEL}" and plan.stats["repairs"] == 1 and plan.stats["llm_calls"] == 2
    repair = srv.requests[1]["json"]["messages"]
    assert repair[-2] == {"role": "assistant", "content": '{"objects": [ {"index": 2,, }'}
    assert "not valid JSON" in repair[-1]["content"]
    assert not plan.notes


def test_code_is_never_evaluated(secret_env, tmp_path):
    marker = tmp_path / "pwned"
    evil = f"__import__('pathlib').Path({str(marker)!r}).write_text('x')"
    with FakeServer([Step(evil)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path))
    assert not marker.exists()
    assert plan.planner == "rules" and plan.stats["repairs"] == 1 and len(srv.requests) == 2


def test_unknown_relations_are_reported_not_remapped(secret_env, tmp_path):
    bad = json.dumps({"objects": [
        {"index": 2, "relations": [{"relation": "edge"}]},
        {"index": 0, "relations": [{"relation": "next_to", "target": 2}, {"relation": "far", "target": 2}]},
        {"index": 1, "relations": [{"relation": "around", "target": 0}]},
    ]})
    with FakeServer([Step(bad)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path))
    assert plan.planner == f"llm:{MODEL}" and plan.stats["repairs"] == 1
    assert "unknown relation 'next_to'" in srv.requests[1]["json"]["messages"][-1]["content"]
    assert plan.order[1].relations == (Relation("far", 0),)  # nothing "near"-like was invented
    assert any("next_to" in n and n.startswith("dropped:") for n in plan.notes)


def test_later_and_unknown_targets_are_dropped(secret_env, tmp_path):
    bad = json.dumps({"objects": [
        {"index": 0, "relations": [{"relation": "middle"}, {"relation": "near", "target": 1}]},
        {"index": 1, "relations": [{"relation": "near", "target": 0}, {"relation": "far", "target": 17},
                                   {"relation": "near", "target": 1}]},
        {"index": 2, "relations": [{"relation": "edge"}, {"relation": "height", "value": [1, 2]}]},
    ]})
    with FakeServer([Step(bad)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path))
    assert plan.planner == f"llm:{MODEL}"
    text = srv.requests[1]["json"]["messages"][-1]["content"]
    assert "target 1 is listed later" in text and "target 17 is not one of the objects" in text
    assert "refers to the object itself" in text and "'height' is not allowed for floor" in text
    assert plan.order[0].relations == (Relation("middle"),)
    assert plan.order[1].relations == (Relation("near", 0),)
    assert len([n for n in plan.notes if n.startswith("dropped:")]) == 4


def test_duplicates_and_missing_objects(secret_env, tmp_path):
    bad = json.dumps({"objects": [
        {"index": 1, "relations": [{"relation": "middle"}]},
        {"index": 1, "relations": [{"relation": "edge"}]},
        {"index": 9, "relations": []},
    ]})
    with FakeServer([Step(bad)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path))
    assert plan.planner == f"llm:{MODEL}"
    text = srv.requests[1]["json"]["messages"][-1]["content"]
    assert "listed more than once" in text and "index 9 does not exist" in text and "never listed: [0, 2]" in text
    # missing objects follow the fallback's order (2 before 0) with its relations re-targeted
    assert [p.source for p in plan.order] == [1, 2, 0]
    assert plan.order[1].relations == (Relation("edge", None, (), True),)  # first in the fallback: no target
    # object 0 was "near" the fallback's object 1, which sits at position 0 of the merged order
    assert plan.order[2].relations == (Relation("edge", None, (), True), Relation("near", 0))
    assert any("missing from the answer" in n for n in plan.notes)


def test_wall_and_on_top_groups(secret_env, tmp_path):
    wall = json.dumps({"objects": [
        {"index": 0, "relations": [{"relation": "above", "target": 4}, {"relation": "height", "value": [1.2, 1.6]}]},
        {"index": 1, "relations": [{"relation": "above", "target": 99}, {"relation": "height", "value": [2, 5]},
                                   {"relation": "right_of", "target": 0}]},
    ]})
    ontop = json.dumps({"objects": [
        {"index": 1, "relations": [{"relation": "on", "target": 9}]},
        {"index": 0, "relations": [{"relation": "on", "target": 9}, {"relation": "left_of", "target": 1}]},
    ]})
    with FakeServer([Step(wall)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path), WALL)
        assert "id 4: sofa at x=2.00, y=3.50" in srv.requests[0]["json"]["messages"][-1]["content"]
    assert plan.planner == f"llm:{MODEL}"
    assert plan.order[0].relations == (Relation("above", 4), Relation("height", None, (1.2, 1.6)))
    assert plan.order[1].relations == (Relation("right_of", 0),)
    with FakeServer([Step(ontop)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path), ONTOP)
    assert plan.planner == f"llm:{MODEL}" and plan.stats["repairs"] == 0
    assert plan.order[1].relations == (Relation("on", 9, (), True), Relation("left_of", 0))
    # "on" must name the support, even though the sofa (id 4) is a placed instance too
    wrong = ontop.replace('"target": 9}]}', '"target": 4}]}', 1)
    with FakeServer([Step(wrong)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path / "b"), ONTOP)
    assert "'on' target 4 is not the support's id (valid: 9)" in srv.requests[1]["json"]["messages"][-1]["content"]
    assert plan.order[0].relations == () and plan.planner == f"llm:{MODEL}"


@pytest.mark.parametrize("step", [Step(GOOD_FLOOR + " " * 5000), Step(endless=True)], ids=["length", "streamed"])
def test_oversized_answer_falls_back(secret_env, tmp_path, step):
    with FakeServer([step]) as srv:
        plan, elapsed = _plan(_cfg(srv, tmp_path))
    assert plan.planner == "rules" and len(srv.requests) == 1  # not retried
    assert elapsed < TIMEOUT  # rejected while reading, not after the whole body
    assert any("max_response_bytes" in n for n in plan.notes)
    assert plan.stats["llm_calls"] == 1 and plan.stats["rule_seconds"] == 0.0  # fallback stats kept


@pytest.mark.slow
def test_stall_returns_within_timeout(secret_env, tmp_path):
    with FakeServer([Step(GOOD_FLOOR, sleep=30)]) as srv:
        plan, elapsed = _plan(_cfg(srv, tmp_path, retries=2))
    assert plan.planner == "rules"
    assert elapsed < TIMEOUT + 0.5
    assert any("timeout_s" in n for n in plan.notes)


@pytest.mark.slow
def test_trickling_answer_returns_within_timeout(secret_env, tmp_path):
    with FakeServer([Step(GOOD_FLOOR, trickle=True)]) as srv:
        plan, elapsed = _plan(_cfg(srv, tmp_path, retries=2))
    assert plan.planner == "rules" and elapsed < TIMEOUT + 0.5 and len(srv.requests) == 1


def test_cut_off_answer_is_salvaged(secret_env, tmp_path):
    cut = GOOD_FLOOR[:GOOD_FLOOR.index('{"index": 1')]  # the chair's entry was cut off
    with FakeServer([Step(cut, finish_reason="length")]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path))
    assert plan.planner == f"llm:{MODEL}" and plan.stats["repairs"] == 1
    assert "cut off at the token limit" in srv.requests[1]["json"]["messages"][-1]["content"]
    assert [p.source for p in plan.order] == [2, 0, 1]  # two salvaged entries, the chair appended
    assert plan.order[1].relations == (Relation("middle"), Relation("far", 0))
    assert any("missing from the answer" in n for n in plan.notes)


def test_http_500_then_success(secret_env, tmp_path):
    with FakeServer([Step(status=500), Step(status=503, headers={"Retry-After": "0"}), Step(GOOD_FLOOR)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path, retries=2))
    assert plan.planner == f"llm:{MODEL}" and plan.stats["llm_calls"] == 3


def test_http_500_forever_falls_back_after_retries(secret_env, tmp_path):
    with FakeServer([Step(status=500)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path, retries=2))
    assert plan.planner == "rules" and len(srv.requests) == 3
    assert any("after 3 attempt(s)" in n for n in plan.notes)


def test_client_error_is_not_retried(secret_env, tmp_path):
    with FakeServer([Step(status=401)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path, retries=3))
    assert plan.planner == "rules" and len(srv.requests) == 1 and any("HTTP 401" in n for n in plan.notes)


def test_json_mode_rejected_is_dropped_silently(secret_env, tmp_path):
    with FakeServer([Step(GOOD_FLOOR, reject_json_mode=True)]) as srv:
        planner = LLMPlanner(_cfg(srv, tmp_path), fallback=ReversePlanner())
        plan = planner.plan(FLOOR, rng=np.random.default_rng(0))
        plan2 = planner.plan(WALL, rng=np.random.default_rng(0))
    assert plan.planner == f"llm:{MODEL}"
    assert "response_format" in srv.requests[0]["json"] and "response_format" not in srv.requests[1]["json"]
    assert "response_format" not in srv.requests[2]["json"]  # remembered for later requests
    assert plan2.planner in ("rules", f"llm:{MODEL}")


def test_circuit_breaker_spans_planners_and_probes_after_cooldown(secret_env, tmp_path, monkeypatch):
    from assist3d.llm import client as client_mod

    with FakeServer([Step(status=500), Step(status=500), Step(GOOD_FLOOR)]) as srv:
        cfg = _cfg(srv, tmp_path, retries=0, max_failures=2)
        planner = LLMPlanner(cfg, fallback=ReversePlanner())
        plans = [planner.plan(r, rng=np.random.default_rng(0)) for r in (FLOOR, WALL)]
        # a new planner (as build_layout makes for the next scene) sees the open breaker too
        plans.append(LLMPlanner(cfg, fallback=ReversePlanner()).plan(ONTOP, rng=np.random.default_rng(0)))
        assert [p.planner for p in plans] == ["rules"] * 3
        assert len(srv.requests) == 2  # the third group never called the failing endpoint
        assert plans[2].stats["llm_calls"] == 0 and "skipped" in plans[2].notes[0]
        monkeypatch.setattr(client_mod, "BREAKER_COOLDOWN_S", 0.0)  # cool-down over: one probe goes through
        probe = LLMPlanner(cfg, fallback=ReversePlanner()).plan(FLOOR, rng=np.random.default_rng(0))
    assert probe.planner == f"llm:{MODEL}" and len(srv.requests) == 3


def test_cache_makes_rerun_free_and_identical(secret_env, tmp_path, monkeypatch):
    with FakeServer([Step('{"objects": [}'), Step(GOOD_FLOOR)]) as srv:
        first, _ = _plan(_cfg(srv, tmp_path))
    assert first.stats["llm_calls"] == 2
    # another server (so another base URL) and another key: the cache still answers, no request
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL + "-other")
    with FakeServer([Step(status=500)]) as srv2:
        second, _ = _plan(_cfg(srv2, tmp_path))
    assert len(srv2.requests) == 0
    assert second.order == first.order and second.planner == first.planner
    assert second.stats["llm_calls"] == 0 and second.stats["cache_hits"] == 2 and second.stats["repairs"] == 1
    assert second.stats["prompt_tokens"] == 0  # a cache hit costs nothing
    # a different temperature is a different question
    with FakeServer([Step(GOOD_FLOOR)]) as srv3:
        _plan(_cfg(srv3, tmp_path, temperature=0.7))
    assert len(srv3.requests) == 1
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)


def test_empty_group_uses_fallback_without_calls(secret_env, tmp_path):
    with FakeServer([Step(GOOD_FLOOR)]) as srv:
        plan, _ = _plan(_cfg(srv, tmp_path), PlanRequest("floor", (), ROOM))
    assert plan.order == () and len(srv.requests) == 0

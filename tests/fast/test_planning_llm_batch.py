"""Several on-top groups in one prompt (``llm.on_top_batch``): each group's answer is checked,
repaired and, failing that, planned by the rules on its own; a batched scene gives the layout of
the one-prompt-per-group scene when the answers agree, from fewer requests."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from assist3d.config import LLMConfig
from assist3d.core.contracts import PlacedInstance, Relation
from assist3d.planning.llm_planner import LLMPlanner
from assist3d.planning.llm_prompts import render_batch_messages
from assist3d.planning.llm_schema import split_batch_answer
from assist3d.planning.relations import PlanRequest, validate_plan
from llm_fakeserver import SENTINEL, FakeServer, Step
from test_planning_llm_layout import MODEL as LAYOUT_MODEL, _catalog, _llm_cfg
from test_planning_llm_planner import FLOOR, ONTOP, ROOM, ReversePlanner, _asset

MODEL = "fake-model"
layout_mod = pytest.importorskip("assist3d.scene.layout")

SHELF = PlacedInstance(12, "proc:shelf/0", "shelf", "floor", np.eye(4))
ONSHELF = PlanRequest("on:12", (_asset(20, "Vase", "vase", (0.15, 0.15, 0.3), ("obj",)),
                                _asset(21, "Book", "book", (0.2, 0.15, 0.04), ("obj",)),
                                _asset(22, "Clock", "clock", (0.2, 0.1, 0.2), ("obj",))), ROOM,
                      placed=(SHELF,), support=SHELF)
TABLE_ANSWER = {"group": "on:9", "objects": [
    {"index": 1, "relations": [{"relation": "on", "target": 9}]},
    {"index": 0, "relations": [{"relation": "on", "target": 9}, {"relation": "left_of", "target": 1}]}]}
SHELF_ANSWER = {"group": "on:12", "objects": [
    {"index": 2, "relations": [{"relation": "on", "target": 12}]},
    {"index": 0, "relations": [{"relation": "on", "target": 12}, {"relation": "near", "target": 2}]},
    {"index": 1, "relations": [{"relation": "on", "target": 12}]}]}


@pytest.fixture
def key(monkeypatch):
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)


def _planner(srv: FakeServer, tmp_path) -> LLMPlanner:
    cfg = LLMConfig(base_url=srv.url, model=MODEL, timeout_s=1.0, retries=0, backoff_s=0.01,
                    cache_dir=str(tmp_path / "llm"))
    return LLMPlanner(cfg, fallback=ReversePlanner())


def _batch(planner: LLMPlanner, requests=(ONTOP, ONSHELF)):
    plans = planner.plan_batch(list(requests), rngs=[np.random.default_rng(i) for i in range(len(requests))])
    for plan, request in zip(plans, requests):
        assert plan.group == request.group and validate_plan(plan, request) == []
    return plans


def test_one_prompt_plans_every_group_and_counts_the_call_once(key, tmp_path):
    with FakeServer([Step(json.dumps({"groups": [TABLE_ANSWER, SHELF_ANSWER]}))]) as srv:
        table, shelf = _batch(_planner(srv, tmp_path))
    assert len(srv.requests) == 1
    user = srv.requests[0]["json"]["messages"][-1]["content"]
    assert 'Group "on:9", support id 9: table' in user and 'Group "on:12", support id 12: shelf' in user
    assert '0: "Vase" (class: vase)' in user and "Groups to dress (2)" in user
    assert table.planner == shelf.planner == f"llm:{MODEL}"
    assert [p.source for p in table.order] == [1, 0] and [p.source for p in shelf.order] == [2, 0, 1]
    assert table.order[1].relations == (Relation("on", 9, (), True), Relation("left_of", 0))
    assert shelf.order[1].relations == (Relation("on", 12, (), True), Relation("near", 0))
    # the batch's counters sit on the first plan only, so a layout's sums count one call
    assert (table.stats["llm_calls"], shelf.stats["llm_calls"]) == (1, 0)
    assert (table.stats["prompt_tokens"], shelf.stats["prompt_tokens"]) == (11, 0)


def test_a_bad_group_is_repaired_and_a_good_group_keeps_its_first_answer(key, tmp_path):
    bad_shelf = {"group": "on:12", "objects": [
        {"index": 2, "relations": [{"relation": "on", "target": 12}, {"relation": "next_to", "target": 0}]},
        {"index": 0, "relations": [{"relation": "on", "target": 12}]}]}  # object 1 never listed
    other_table = {"group": "on:9", "objects": [  # the repair answers the good group differently: ignored
        {"index": 0, "relations": [{"relation": "on", "target": 9}]},
        {"index": 1, "relations": [{"relation": "on", "target": 9}]}]}
    with FakeServer([Step(json.dumps({"groups": [TABLE_ANSWER, bad_shelf]})),
                     Step(json.dumps({"groups": [other_table, SHELF_ANSWER]}))]) as srv:
        table, shelf = _batch(_planner(srv, tmp_path))
    assert len(srv.requests) == 2
    repair = srv.requests[1]["json"]["messages"][-1]["content"]
    assert "group on:12: object 2: unknown relation 'next_to'" in repair
    assert "group on:12: objects never listed: [1]" in repair and "group on:9" not in repair
    assert [p.source for p in table.order] == [1, 0]  # the first answer, not the repair's
    assert [p.source for p in shelf.order] == [2, 0, 1]  # the repaired answer
    assert table.stats["repairs"] == 1 and table.stats["llm_calls"] == 2 and shelf.stats["llm_calls"] == 0


def test_a_group_missing_twice_falls_back_alone(key, tmp_path):
    only_table = json.dumps({"groups": [TABLE_ANSWER, {"group": "on:99", "objects": []}]})
    with FakeServer([Step(only_table), Step(only_table)]) as srv:
        table, shelf = _batch(_planner(srv, tmp_path))
    repair = srv.requests[1]["json"]["messages"][-1]["content"]
    assert "group on:12: group on:12 is missing from the answer" in repair
    assert "group 'on:99' was not asked for" in repair
    assert table.planner == f"llm:{MODEL}" and [p.source for p in table.order] == [1, 0]
    assert shelf.planner == "rules" and [p.source for p in shelf.order] == [2, 1, 0]  # ReversePlanner
    assert any("LLM failed for group on:12" in n and "missing from the answer" in n for n in shelf.notes)


def test_a_failed_request_hands_every_group_to_the_rules(key, tmp_path):
    with FakeServer([Step(status=500)]) as srv:
        plans = _batch(_planner(srv, tmp_path))
    assert [p.planner for p in plans] == ["rules", "rules"]
    assert all(any("LLM failed for group" in n for n in p.notes) for p in plans)


def test_a_cut_off_answer_keeps_its_complete_groups(key, tmp_path):
    cut = '{"groups": [' + json.dumps(TABLE_ANSWER) + ', {"group": "on:12", "objects": [{"index": 2, "rel'
    with FakeServer([Step(cut, finish_reason="length"), Step("not json either")]) as srv:
        table, shelf = _batch(_planner(srv, tmp_path))
    repair = srv.requests[1]["json"]["messages"][-1]["content"]
    assert "cut off at the token limit" in repair and "only the first 1 complete groups could be read" in repair
    assert table.planner == f"llm:{MODEL}" and shelf.planner == "rules"


def test_batch_answers_are_read_in_either_shape_and_never_evaluated():
    found, problems = split_batch_answer({"groups": {"on:9": {"objects": []}, "on:12": []}}, ["on:9", "on:12"])
    assert set(found) == {"on:9", "on:12"} and not problems
    found, problems = split_batch_answer({"groups": [TABLE_ANSWER, TABLE_ANSWER, 7]}, ["on:9"])
    assert list(found) == ["on:9"] and any("more than once" in p for p in problems)
    assert any('entry 2 of "groups"' in p for p in problems)
    assert split_batch_answer("__import__('os')", ["on:9"])[0] == {}


def test_only_on_top_groups_can_be_batched():
    with pytest.raises(ValueError):
        render_batch_messages([ONTOP, FLOOR])
    assert "Groups to dress (1)" in render_batch_messages([ONTOP])[-1]["content"]


# --------------------------------------------------------------------------------------------
# build_layout end to end
# --------------------------------------------------------------------------------------------

GROUP = re.compile(r'Group "(on:\d+)", support id (\d+):')
COUNT = re.compile(r"Objects of on:\d+ \((\d+)\)")


def _responder(body: dict) -> Step:
    """Well-formed answers, the same plan for a group whether it is asked alone or in a batch."""
    text = body["messages"][-1]["content"]
    def objects(sid: int, n: int) -> list[dict]:
        return [{"index": i, "relations": [{"relation": "on", "target": sid}]} for i in range(n)]
    if "Groups to dress" in text:
        groups = [{"group": g, "objects": objects(int(s), int(n))}
                  for (g, s), n in zip(GROUP.findall(text), COUNT.findall(text))]
        return Step(json.dumps({"groups": groups}))
    m = re.search(r"Support \(the objects rest on it\): id (\d+)", text)
    n = int(re.search(r"to (?:arrange|put on it|hang) \((\d+)\)", text).group(1))
    if m:
        return Step(json.dumps({"objects": objects(int(m.group(1)), n)}))
    if "Wall objects to hang" in text:
        return Step(json.dumps({"objects": [{"index": i, "relations": [{"relation": "height", "value": [1.2, 1.6]}]}
                                            for i in range(n)]}))
    return Step(json.dumps({"objects": [{"index": i, "relations": [{"relation": "edge"}]} for i in range(n)]}))


@pytest.mark.parametrize("concurrently", [False, True], ids=["serial", "concurrent"])
@pytest.mark.slow
def test_batched_layout_equals_the_per_group_layout_with_fewer_requests(key, tmp_path, concurrently):
    cat = _catalog(tmp_path / "cat")
    layouts, requests = {}, {}
    for batch in (1, 2):
        with FakeServer([], responder=_responder) as srv:
            cfg = _llm_cfg(srv.url, tmp_path / f"b{batch}", on_top_batch=batch, plan_concurrently=concurrently)
            layouts[batch] = layout_mod.build_layout(cat, cfg, 5)
            requests[batch] = len(srv.requests)
    one, two = layouts[1], layouts[2]
    on_top = [g for g in one.planner if g.startswith("on:")]
    assert len(on_top) >= 3 and all(two.planner[g] == f"llm:{LAYOUT_MODEL}" for g in on_top)
    assert requests[2] == 2 + (len(on_top) + 1) // 2 < requests[1] == 2 + len(on_top)
    assert two.stats["llm_calls"] == requests[2] and one.stats["llm_calls"] == requests[1]
    assert [i.to_json() for i in one.instances] == [i.to_json() for i in two.instances]
    assert [d.to_json() for d in one.dropped] == [d.to_json() for d in two.dropped]
    # and the same cache gives the same batched layout with the endpoint gone
    with FakeServer([Step(status=500)]) as dead:
        cfg = _llm_cfg(dead.url, tmp_path / "b2", on_top_batch=2, plan_concurrently=concurrently)
        again = layout_mod.build_layout(cat, cfg, 5)
    assert [i.to_json() for i in again.instances] == [i.to_json() for i in two.instances]
    assert again.stats["cache_hits"] == requests[2] and len(dead.requests) == 0


def test_a_batch_that_starts_after_the_scene_budget_goes_to_the_rules(key, tmp_path):
    cat = _catalog(tmp_path / "cat")

    def slow(body: dict) -> Step:
        step = _responder(body)
        return Step(step.content, sleep=0.4)

    with FakeServer([], responder=slow) as srv:
        cfg = _llm_cfg(srv.url, tmp_path, on_top_batch=3, scene_budget_s=0.2)
        lay = layout_mod.build_layout(cat, cfg, 5)
    on_top = [g for g in lay.planner if g.startswith("on:")]
    assert lay.planner["floor"] == f"llm:{LAYOUT_MODEL}" and lay.planner["wall"] == "rules"
    assert on_top and all(lay.planner[g] == "rules" for g in on_top) and len(srv.requests) == 1
    assert lay.stats["llm_budget_groups"] == 1 + len(on_top)

"""The compact answer form (``llm.answer_format: compact``): the same plan as the full form from
about a third of the answer, read entry by entry in any answer, with problems phrased for it."""

from __future__ import annotations

import json

import numpy as np
import pytest
from pydantic import ValidationError

from assist3d.config import LLMConfig
from assist3d.llm.schema import salvage_objects
from assist3d.planning.llm_planner import LLMPlanner
from assist3d.planning.llm_prompts import render_batch_messages, render_plan_messages
from assist3d.planning.llm_schema import check_answer, expand_compact_entry
from assist3d.planning.relations import validate_plan
from llm_fakeserver import SENTINEL, FakeServer, Step
from test_planning_llm_batch import ONSHELF
from test_planning_llm_planner import FLOOR, ONTOP, WALL, ReversePlanner

FULL = {
    "floor": {"objects": [
        {"index": 0, "relations": [{"relation": "middle"}]},
        {"index": 1, "relations": [{"relation": "around", "target": 0, "hard": True},
                                   {"relation": "face_to", "target": 0}]},
        {"index": 2, "relations": [{"relation": "edge"}, {"relation": "far", "target": 0, "hard": False}]}]},
    "wall": {"objects": [
        {"index": 0, "relations": [{"relation": "above", "target": 4}, {"relation": "height", "value": [1.2, 1.6]}]},
        {"index": 1, "relations": [{"relation": "height", "value": [1.8, 2.1]}, {"relation": "far", "target": 0}]}]},
    "on:9": {"objects": [
        {"index": 1, "relations": [{"relation": "on", "target": 9}]},
        {"index": 0, "relations": [{"relation": "on", "target": 9}, {"relation": "left_of", "target": 1}]}]},
}
COMPACT = {
    "floor": {"objects": [[0, "middle"], [1, ["around", 0, "hard"], ["face_to", 0]], [2, "edge", ["far", 0, False]]]},
    "wall": {"objects": [[0, ["above", 4], ["height", 1.2, 1.6]], [1, ["height", 1.8, 2.1], ["far", 0]]]},
    "on:9": {"objects": [[1, ["on", 9]], [0, ["on", 9], ["left_of", 1]]]},
}
REQUESTS = {"floor": FLOOR, "wall": WALL, "on:9": ONTOP}


@pytest.mark.parametrize("group", sorted(REQUESTS))
def test_compact_answer_checks_to_the_full_answers_plan(group):
    request = REQUESTS[group]
    full, compact = check_answer(FULL[group], request), check_answer(COMPACT[group], request)
    assert full.problems == () and compact.problems == ()
    assert compact.order == full.order and len(compact.order) == len(request.objects)
    # and the compact form is the shorter answer
    assert len(json.dumps(COMPACT[group])) < 0.6 * len(json.dumps(FULL[group]))


def test_compact_entries_mix_with_full_ones_and_bad_parts_are_reported_not_guessed():
    mixed = {"objects": [[0, "middle"], FULL["floor"]["objects"][1], [2, "edge", ["far", 0, 1], 7, ["next_to", 0]]]}
    checked = check_answer(mixed, FLOOR)
    assert [p.source for p in checked.order] == [0, 1, 2]
    assert [r.kind for r in checked.order[2].relations] == ["edge"]  # the three bad relations left out
    text = " | ".join(checked.problems)
    assert "relation 'far' takes one target, got [0, 1]" in text
    assert 'a relation must be "name", ["name", target] or ["height", min, max], got 7' in text
    assert "unknown relation 'next_to'" in text
    entry, problems = expand_compact_entry(["zero", "edge"], 4)
    assert entry is None and problems[0].startswith("entry 4: expected [<index>, <relation>, ...]")
    # a relation that needs a target, written bare, is judged like a full one without its target
    assert "relation 'near' needs an integer 'target'" in " ".join(check_answer({"objects": [[0, "near"]]}, FLOOR).problems)


def test_a_cut_off_compact_answer_keeps_its_complete_entries():
    text = '{"objects": [[0, "middle"], [1, ["around", 0], ["face_to", 0]], [2, "edge", ["fa'
    assert salvage_objects(text) == [[0, "middle"], [1, ["around", 0], ["face_to", 0]]]


def test_compact_prompts_ask_for_the_compact_form():
    for request in (FLOOR, WALL, ONTOP):
        full = render_plan_messages(request)[-1]["content"]
        compact = render_plan_messages(request, answer_format="compact")[-1]["content"]
        assert "as one list" in compact and "as one list" not in full
        assert request_lines(full) == request_lines(compact)  # the same room and objects
        # the same vocabulary, each relation written as the compact answer writes it
        names = [ln.split()[1] for ln in full.splitlines() if ln.startswith("- ")]
        listed = [ln for ln in compact.splitlines() if ln.startswith("- ")]
        assert len(listed) == len(names) and '"target"' not in compact and '"value"' not in compact
        assert all(ln.startswith((f'- ["{n}", ', f'- "{n}":')) for ln, n in zip(listed, names))
    batch = render_batch_messages([ONTOP, ONSHELF], answer_format="compact")[-1]["content"]
    assert "as one list" in batch and 'Group "on:12"' in batch
    with pytest.raises(ValidationError):
        LLMConfig(answer_format="short")


def request_lines(prompt: str) -> list[str]:
    """The lines of a prompt that describe the request (room, numbered objects, placed ids)."""
    return [ln for ln in prompt.splitlines() if ln.lstrip().startswith(("Room:", "0:", "1:", "2:", "id "))]


def test_the_planner_asks_in_the_configured_form_and_plans_the_same(monkeypatch, tmp_path):
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    plans, prompts = {}, {}
    for form, answer in (("full", FULL["floor"]), ("compact", COMPACT["floor"])):
        with FakeServer([Step(json.dumps(answer))]) as srv:
            cfg = LLMConfig(base_url=srv.url, model="fake", timeout_s=1.0, retries=0, backoff_s=0.01,
                            cache_dir=str(tmp_path / "llm"), answer_format=form)
            plans[form] = LLMPlanner(cfg, fallback=ReversePlanner()).plan(FLOOR, rng=np.random.default_rng(0))
        prompts[form] = srv.requests[0]["json"]["messages"][-1]["content"]
        assert len(srv.requests) == 1  # the other form's cached answer is not this prompt's
    assert plans["compact"].order == plans["full"].order and plans["compact"].planner == "llm:fake"
    assert plans["compact"].notes == () and validate_plan(plans["compact"], FLOOR) == []
    assert "as one list" in prompts["compact"] and "as one list" not in prompts["full"]


def test_a_compact_answer_with_problems_is_repaired_in_the_compact_form(monkeypatch, tmp_path):
    """The repair round quotes the compact answer's problems (an invented relation, an object never
    listed) and the compact repair answer is used; the repair prompt asks for the corrected answer
    without forcing the full form."""
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    bad = {"objects": [[0, "middle"], [1, ["next_to", 0], ["face_to", 0]]]}  # object 2 missing
    with FakeServer([Step(json.dumps(bad)), Step(json.dumps(COMPACT["floor"]))]) as srv:
        cfg = LLMConfig(base_url=srv.url, model="fake", timeout_s=1.0, retries=0, backoff_s=0.01,
                        cache_dir=str(tmp_path / "llm"), answer_format="compact")
        plan = LLMPlanner(cfg, fallback=ReversePlanner()).plan(FLOOR, rng=np.random.default_rng(0))
    assert len(srv.requests) == 2 and plan.stats["repairs"] == 1 and plan.planner == "llm:fake"
    repair = srv.requests[1]["json"]["messages"][-1]["content"]
    assert "unknown relation 'next_to'" in repair and "objects never listed: [2]" in repair
    assert '"relation"' not in repair  # nothing in it asks for the full form
    assert plan.order == check_answer(COMPACT["floor"], FLOOR).order and plan.notes == ()

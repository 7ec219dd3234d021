"""The LLM's object plan for the Holodeck-style baseline (selection.strategy: room-type): answer
checking, and build_layout against the local fake chat server (answer used, cached, or the
built-in template when the call fails)."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from assist3d.assets.catalog import Catalog
from assist3d.core.contracts import AssetRecord, MeshData, SupportSurface
from assist3d.planning.llm_rooms import NO_HOLD, check_room_answer
from assist3d.config.presets import apply_preset
from assist3d.scene.layout import build_layout
from assist3d.core.taxonomy.roomtypes import ROOM_TEMPLATES
from llm_fakeserver import SENTINEL, FakeServer, Step, files_containing

MODEL = "fake-rooms"
VOCAB = {"floor": ("bed", "chair", "dining table", "nightstand", "wardrobe"), "wall": ("clock", "picture"),
         "obj": ("book", "cup", "vase")}


def test_good_answer_becomes_a_template():
    data = {"floor": [{"class": "Bed", "quantity": 1}, {"class": "nightstand", "quantity": 2, "same": True},
                      {"class": "chair", "quantity": 3, "same": False}],
            "wall": [{"class": "picture", "quantity": 2, "same": False}], "small": ["book", "vase", "book"]}
    t, problems = check_room_answer(data, "bedroom", VOCAB)
    assert problems == []
    assert [(i.cls, i.count, i.same, i.prob) for i in t.floor] == [
        ("bed", (1, 1), True, 1.0), ("nightstand", (2, 2), True, 1.0), ("chair", (3, 3), False, 1.0)]
    assert [i.holds for i in t.floor] == ["bed" not in NO_HOLD, True, "chair" not in NO_HOLD] == [False, True, False]
    assert [(i.cls, i.count, i.same) for i in t.wall] == [("picture", (2, 2), False)]
    assert t.small == ("book", "vase")


def test_bad_entries_are_dropped_with_reasons_never_remapped():
    data = {"floor": [{"class": "bedd"}, {"class": "bed", "quantity": 40}, {"class": "wardrobe", "quantity": "two"},
                      "nightstand", {"class": "nightstand", "quantity": 0}],
            "wall": {"class": "clock"}, "small": ["spaceship"]}
    t, problems = check_room_answer(data, "bedroom", VOCAB)
    assert [(i.cls, i.count) for i in t.floor] == [("bed", (8, 8)), ("wardrobe", (1, 1)), ("nightstand", (1, 1))]
    text = "\n".join(problems)
    assert "unknown class 'bedd'" in text and "clamped to 8" in text and "is not a number" in text
    assert "not an object" in text and '"wall" is not a list' in text and "'spaceship'" in text
    assert t.wall == () and t.small == ROOM_TEMPLATES["bedroom"].small  # small objects fall back to the template
    assert check_room_answer({"floor": [{"class": "spaceship"}]}, "bedroom", VOCAB)[0] is None
    assert check_room_answer(["bed"], "bedroom", VOCAB) == (None, ["the answer is not a JSON object"])


def _box(size) -> MeshData:
    import trimesh

    m = trimesh.creation.box(extents=size)
    m.apply_translation((0, 0, size[2] / 2))
    return MeshData(np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.int32),
                    np.full((len(m.faces), 3), 180, np.uint8))


def _catalog(root) -> Catalog:
    specs = [("bed", "floor", (1.4, 2.0, 0.5), False), ("nightstand", "floor", (0.45, 0.4, 0.55), True),
             ("wardrobe", "floor", (1.0, 0.6, 2.0), False), ("dining table", "floor", (1.6, 0.9, 0.75), True),
             ("chair", "floor", (0.45, 0.5, 0.9), False), ("picture", "wall", (0.6, 0.03, 0.4), False),
             ("clock", "wall", (0.3, 0.05, 0.3), False), ("book", "obj", (0.2, 0.15, 0.04), False),
             ("cup", "obj", (0.08, 0.08, 0.1), False), ("vase", "obj", (0.12, 0.12, 0.25), False)]
    cat = Catalog(root)
    for cls, group, size, sup in specs:
        for i in range(3):
            hw, hd = size[0] * 0.45, size[1] * 0.45
            sups = (SupportSurface(size[2], ((-hw, -hd), (hw, -hd), (hw, hd), (-hw, hd))),) if sup else ()
            cat.add(AssetRecord(id=f"toy:{cls}/{i}", source="toy", name=cls, class_name=cls, groups=(group,),
                                size=size, supports=sups), _box(size))
    cat.save()
    return cat


ROOM_ANSWER = {"floor": [{"class": "bed", "quantity": 1}, {"class": "nightstand", "quantity": 2, "same": True},
                         {"class": "spaceship", "quantity": 1}],
               "wall": [{"class": "picture", "quantity": 2, "same": False}], "small": ["book"]}


def _cfg(url: str, cache: str):
    return apply_preset({"selection": {"room_types": ["bedroom"]},
                         "layout": {"group_budget_s": 30.0, "max_backtracks": 200},
                         "llm": {"base_url": url, "model": MODEL, "timeout_s": 2.0, "retries": 0, "max_failures": 50,
                                 "cache_dir": cache}}, "holodeck-style")


def test_build_layout_uses_the_llm_object_plan_and_caches_it(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    cat = _catalog(tmp_path / "cat")
    room_prompts = []

    def answer(body: dict) -> Step:
        text = body["messages"][-1]["content"]
        if text.startswith("Furnish this room"):
            room_prompts.append(text)
            return Step(json.dumps(ROOM_ANSWER))
        return Step(status=500)  # relation planning: the rule planner takes over

    with FakeServer([], responder=answer) as srv:
        lay = build_layout(cat, _cfg(srv.url, str(tmp_path / "llm")), 5)
    sel = lay.stats["selection"]
    assert sel["room_type"] == "bedroom" and sel["room_objects"] == "llm"
    assert len(room_prompts) == 1
    assert "Room type: bedroom." in room_prompts[0] and "dining table" in room_prompts[0]  # the vocabulary is listed
    assert lay.stats["selected"]["floor"] == 3 and lay.stats["selected"]["wall"] == 2
    assert any("unknown class 'spaceship'" in n for n in lay.stats["notes"])
    stands = {i.asset for i in lay.instances if i.class_name == "nightstand"}
    assert len(stands) == 1  # "same": one model repeated
    assert {i.class_name for i in lay.instances if i.group.startswith("on:") or i.group == "obj"} <= {"book"}
    assert lay.stats["llm_calls"] >= 1
    assert not files_containing(SENTINEL, tmp_path, os.environ["ASSIST3D_CACHE"])
    # a re-run is served from the cache: the same object plan without asking again
    with FakeServer([Step(status=500)]) as srv2:
        again = build_layout(cat, _cfg(srv2.url, str(tmp_path / "llm")), 5)
        asked = [r for r in srv2.requests if r["json"]["messages"][-1]["content"].startswith("Furnish this room")]
    assert asked == [] and again.stats["selection"]["room_objects"] == "llm"
    assert again.stats["cache_hits"] >= 1
    assert [i.to_json() for i in again.instances] == [i.to_json() for i in lay.instances]


def test_failed_call_falls_back_to_the_template(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    cat = _catalog(tmp_path / "cat")
    with FakeServer([Step(status=500)]) as srv:
        lay = build_layout(cat, _cfg(srv.url, str(tmp_path / "llm")), 5)
    assert lay.stats["selection"]["room_objects"] == "template"
    assert any("LLM room objects failed for a bedroom" in n for n in lay.stats["notes"])
    assert "bed" in {i.class_name for i in lay.instances}  # the bedroom template's anchor

"""Typed run records (assist3d.core.records): the one place that names the keys of a scene's marker."""

from __future__ import annotations

from assist3d.export.manifest import scene_entry
from assist3d.core.records import (MANIFEST_ENTRY_KEYS, PLAN_COUNTERS, STAGES, LLMUsage, SceneRecord, StageTimings,
                              stage_timings)


def _record(**kw) -> SceneRecord:
    base = dict(id="scene_000003", index=3, seed=11, dataset_seed=0, instances=5, instances_with_points=4,
                dropped=1, planner={"floor": "rules"}, vantage_points=[[1.0, 2.0, 1.5]], render={"views": 2},
                triangles=100, llm=LLMUsage(llm_calls=0, cache_hits=0, repairs=0),
                seconds=StageTimings(select=0.1, layout=0.2, assemble=0.3, render=0.4, fuse=0.5),
                cpu_seconds={"select+layout": 0.3})
    base.update(kw)
    return SceneRecord(**base)


def test_marker_keys_keep_their_order_and_check_sits_before_the_timings():
    """The marker's JSON is a file format: key order is part of the bytes users hash."""
    keys = list(_record().to_json())
    assert keys == ["id", "index", "seed", "dataset_seed", "instances", "instances_with_points", "dropped",
                    "planner", "vantage_points", "render", "triangles", "llm", "seconds", "cpu_seconds"]
    checked = list(_record(check={"ok": True}).to_json())
    assert checked.index("check") == checked.index("llm") + 1
    assert list(_record().to_json()["seconds"]) == list(STAGES[:-1])  # "write" comes from the writer


def test_stage_timings_round_trip_and_total_with_a_missing_stage():
    t = StageTimings.from_json({"select": 1, "layout": 2.5, "write": 0.5, "unknown": 9})
    assert t.get("render") == 0.0 and t.total == 4.0
    assert StageTimings.from_json(t.to_json()) == t
    assert stage_timings({"seconds": None}).total == 0.0  # an old or damaged entry reads as zeros


def test_llm_usage_reads_counters_at_the_top_and_seconds_with_the_timings():
    stats = {"llm_calls": 3, "cache_hits": 1, "repairs": 0, "prompt_tokens": 120,
             "timing": {"select": 0.1, "floor": 2.0, "llm_seconds": 1.75}, "notes": ["x"]}
    u = LLMUsage.from_layout_stats(stats)
    assert u.to_json() == {"llm_calls": 3, "cache_hits": 1, "repairs": 0, "prompt_tokens": 120, "llm_seconds": 1.75}
    assert list(u.to_json()) == [k for k in PLAN_COUNTERS if k in u.to_json()]
    assert LLMUsage.from_json({"llm_calls": 2, "bogus": 1, "repairs": "3"}).to_json() == {"llm_calls": 2}


def test_manifest_entry_is_the_listed_subset_in_order():
    marker = {"format": "assist3d-scene", **_record(check={"ok": True}).to_json(), "points": 7, "files": {}}
    entry = scene_entry(marker)
    assert list(entry) == [k for k in MANIFEST_ENTRY_KEYS if k in marker]
    assert "files" not in entry and "vantage_points" not in entry and entry["points"] == 7


def test_on_top_group_names_are_built_and_read_in_one_place():
    from assist3d.core.contracts import group_kind, on_top_group, on_top_support

    g = on_top_group(7)
    assert g == "on:7" and on_top_support(g) == 7 and group_kind(g) == "obj"
    assert [on_top_support(x) for x in ("floor", "wall", "on:", "on:x", "on:-1")] == [None] * 5
    assert on_top_group(None) == "on:None" and on_top_support("on:None") is None and group_kind("on:None") == "obj"
    assert [group_kind(x) for x in ("floor", "wall", "obj")] == ["floor", "wall", "obj"]


def test_layout_stats_are_typed_and_read_and_write_as_the_mapping_they_were():
    from assist3d.core.contracts import LayoutStats

    raw = {"selected": {"floor": 3, "wall": 1, "obj": 2}, "placed": {"floor": 3, "wall": 1, "obj": 1}, "dropped": 1,
           "selection": {"draws": 4}, "llm_calls": 2, "cache_hits": 1, "repairs": 0, "placement": {"nodes": 10},
           "notes": ["a note"], "timing": {"select": 0.1}, "llm_budget_groups": 0, "future_key": [1]}
    st = LayoutStats.from_json(raw)
    assert st.placed["obj"] == 1 and st.llm_calls == 2 and st.llm_budget_groups == 0 and st.extra == {"future_key": [1]}
    assert st.to_json() == raw and list(st.to_json()) == list(raw)  # same keys, same order: layout.json unchanged
    assert st["notes"] == ["a note"] and st.get("timing") == {"select": 0.1} and "prompt_tokens" not in st
    assert dict(st) == raw and len(st) == len(raw)
    empty = LayoutStats()
    assert empty.prompt_tokens is None and "llm_budget_groups" not in empty.to_json() and empty["dropped"] == 0

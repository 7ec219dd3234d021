"""End to end: build_layout with the LLM planner configured against the local fake server."""

from __future__ import annotations

import json
import logging
import os
import re

import numpy as np
import pytest

from assist3d.assets.catalog import Catalog
from assist3d.config import GenerateConfig
from assist3d.core.contracts import AssetRecord, MeshData, SupportSurface
from llm_fakeserver import SENTINEL, FakeServer, Step, files_containing

layout_mod = pytest.importorskip("assist3d.scene.layout")

MODEL = "fake-e2e"
SPECS = [("table", "floor", (1.2, 0.7, 0.75), True), ("chair", "floor", (0.45, 0.5, 0.9), False),
         ("bed", "floor", (1.4, 2.0, 0.5), True), ("picture", "wall", (0.7, 0.04, 0.5), False),
         ("shelf", "wall", (0.9, 0.25, 0.3), True), ("cup", "obj", (0.08, 0.08, 0.1), False)]


def _catalog(root) -> Catalog:
    import trimesh

    cat = Catalog(root)
    for cls, group, size, sup in SPECS:
        m = trimesh.creation.box(extents=size)
        m.apply_translation((0, 0, size[2] / 2))
        mesh = MeshData(np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.int32),
                        np.full((len(m.faces), 3), 180, np.uint8))
        hw, hd = size[0] * 0.45, size[1] * 0.45
        sups = (SupportSurface(size[2], ((-hw, -hd), (hw, -hd), (hw, hd), (-hw, hd))),) if sup else ()
        cat.add(AssetRecord(id=f"toy:{cls}", source="toy", name=cls, class_name=cls, groups=(group,), size=size,
                            supports=sups), mesh)
    cat.save()
    return cat


def _answer(body: dict) -> Step:
    """A well-formed plan for whatever group is asked; wall groups fail with HTTP 500."""
    text = body["messages"][-1]["content"]
    if "Wall objects to hang" in text:
        return Step(status=500)
    count = int(re.search(r"to (?:arrange|put on it) \((\d+)\)", text).group(1))
    if "Support (the objects rest on it): id " in text:
        sid = int(re.search(r"Support \(the objects rest on it\): id (\d+)", text).group(1))
        rels = [[{"relation": "on", "target": sid}] for _ in range(count)]
    else:
        rels = [[{"relation": "edge"}] + ([{"relation": "near", "target": i - 1}] if i else []) for i in range(count)]
    return Step(json.dumps({"objects": [{"index": i, "relations": r} for i, r in enumerate(rels)]}))


def test_build_layout_records_llm_and_rules_groups(tmp_path, monkeypatch, caplog):
    if not hasattr(layout_mod, "build_layout"):
        pytest.skip("build_layout not available")
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    caplog.set_level(logging.DEBUG)
    cat = _catalog(tmp_path / "cat")
    with FakeServer([], responder=_answer) as srv:
        cfg = GenerateConfig.model_validate({
            "selection": {"floor_count": 5, "wall_count": 2, "on_top_count": 2},
            "layout": {"group_budget_s": 0.3},
            "llm": {"base_url": srv.url, "model": MODEL, "timeout_s": 1.0, "retries": 0,
                    "cache_dir": str(tmp_path / "llm")}})
        lay = layout_mod.build_layout(cat, cfg, 7)
        calls = len(srv.requests)
    assert lay.planner.get("floor") == f"llm:{MODEL}"
    assert lay.planner.get("wall") == "rules"
    on_top = [g for g in lay.planner if g.startswith("on:")]
    assert all(lay.planner[g] == f"llm:{MODEL}" for g in on_top)
    assert lay.stats["llm_calls"] == calls >= 2 and lay.stats["cache_hits"] == 0
    assert lay.stats["repairs"] == 0
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "layout.json").write_text(json.dumps(lay.to_json()))
    assert SENTINEL not in caplog.text
    assert not files_containing(SENTINEL, tmp_path, os.environ["ASSIST3D_CACHE"])
    # a re-run is answered from the cache for every group the server answered
    with FakeServer([Step(status=500)]) as srv2:
        cfg2 = cfg.model_copy(update={"llm": cfg.llm.model_copy(update={"base_url": srv2.url})})
        again = layout_mod.build_layout(cat, cfg2, 7)
    assert again.planner == lay.planner
    assert again.stats["cache_hits"] == calls - 1  # every call but the failed wall one
    assert [i.to_json() for i in again.instances] == [i.to_json() for i in lay.instances]


@pytest.mark.slow
def test_build_layout_survives_a_stalling_and_an_oversized_server(tmp_path, monkeypatch):
    import time

    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    cat = _catalog(tmp_path / "cat")

    def answer(body: dict) -> Step:
        text = body["messages"][-1]["content"]
        if "Floor objects to arrange" in text:
            return Step(sleep=30)  # stalls far past the time-out
        if "Support (the objects rest on it)" in text:
            return Step("x" * 5000)  # over max_response_bytes
        count = int(re.search(r"Wall objects to hang \((\d+)\)", text).group(1))
        return Step(json.dumps({"objects": [{"index": i, "relations": [{"relation": "height", "value": [1.2, 1.5]}]}
                                            for i in range(count)]}))

    with FakeServer([], responder=answer) as srv:
        cfg = GenerateConfig.model_validate({
            "selection": {"floor_count": 4, "wall_count": 2, "on_top_count": 1},
            "layout": {"group_budget_s": 0.3},
            "llm": {"base_url": srv.url, "model": MODEL, "timeout_s": 1.0, "retries": 1, "backoff_s": 0.01,
                    "max_response_bytes": 2000, "max_failures": 10, "cache_dir": str(tmp_path / "llm")}})
        t0 = time.monotonic()
        lay = layout_mod.build_layout(cat, cfg, 3)
        elapsed = time.monotonic() - t0
    assert lay.planner["floor"] == "rules" and lay.planner["wall"] == f"llm:{MODEL}"
    assert all(v == "rules" for g, v in lay.planner.items() if g.startswith("on:"))
    assert lay.instances and elapsed < 1.0 + 3.0  # one stalled request, not one per retry
    assert not files_containing(SENTINEL, tmp_path, os.environ["ASSIST3D_CACHE"])


def _slow(delay: float):
    def answer(body: dict) -> Step:
        step = _answer(body)
        return Step(step.content, status=step.status, sleep=delay if step.status == 200 else 0.0)
    return answer


def _llm_cfg(url: str, tmp_path, **llm) -> GenerateConfig:
    return GenerateConfig.model_validate({
        "selection": {"floor_count": 6, "wall_count": 2, "on_top_count": 2},
        "layout": {"group_budget_s": 5.0},
        "llm": {"base_url": url, "model": MODEL, "timeout_s": 5.0, "retries": 0, "concurrency": 4,
                "cache_dir": str(tmp_path / "llm"), **llm}})


@pytest.mark.slow
def test_on_top_groups_are_planned_concurrently_and_give_the_serial_layout(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    cat = _catalog(tmp_path / "cat")
    layouts, peaks = {}, {}
    for mode, concurrently in (("serial", False), ("concurrent", True)):
        with FakeServer([], responder=_slow(0.3)) as srv:
            cfg = _llm_cfg(srv.url, tmp_path / mode, plan_concurrently=concurrently)
            layouts[mode] = layout_mod.build_layout(cat, cfg, 5)
            peaks[mode] = srv.max_active
    on_top = [g for g in layouts["serial"].planner if g.startswith("on:")]
    assert len(on_top) >= 2 and all(layouts["serial"].planner[g] == f"llm:{MODEL}" for g in on_top)
    assert peaks["serial"] == 1 and peaks["concurrent"] >= 2
    a, b = layouts["serial"], layouts["concurrent"]
    assert a.planner == b.planner and a.stats["llm_calls"] == b.stats["llm_calls"]
    assert [i.to_json() for i in a.instances] == [i.to_json() for i in b.instances]
    assert [d.to_json() for d in a.dropped] == [d.to_json() for d in b.dropped]
    def port_free(notes):
        return [re.sub(r"127\.0\.0\.1:\d+", "HOST", n) for n in notes]
    assert port_free(a.stats["notes"]) == port_free(b.stats["notes"])  # the servers' ports differ


def test_scene_budget_hands_the_remaining_groups_to_the_rules(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    cat = _catalog(tmp_path / "cat")
    with FakeServer([], responder=_slow(0.4)) as srv:
        cfg = _llm_cfg(srv.url, tmp_path, scene_budget_s=0.2)
        lay = layout_mod.build_layout(cat, cfg, 5)
    # the floor group starts inside the budget and takes 0.4 s; every group after it is over
    assert lay.planner["floor"] == f"llm:{MODEL}"
    assert lay.planner["wall"] == "rules"
    on_top = [g for g in lay.planner if g.startswith("on:")]
    assert on_top and all(lay.planner[g] == "rules" for g in on_top)
    assert lay.stats["llm_budget_groups"] == 1 + len(on_top)
    assert sum("LLM planning budget (0.2 s) was spent" in n for n in lay.stats["notes"]) == 1 + len(on_top)
    assert len(srv.requests) == 1

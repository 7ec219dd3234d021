"""build_layout end to end, plan repair, the top-down picture and the `assist3d layout` commands."""

from __future__ import annotations

import json
from dataclasses import dataclass, replace

import numpy as np
import pytest

from assist3d.assets.catalog import Catalog
from assist3d.config import GenerateConfig
from assist3d.core.contracts import AssetRecord, DroppedObject, MeshData, PlacedInstance, Relation, SupportSurface
from assist3d.scene import layout as layout_mod
from assist3d.scene.layout import build_layout, sanitise_plan
from assist3d.planning.relations import GroupPlan, PlannedObject, PlanRequest
from assist3d.planning.rules import RulePlanner

SPECS = [  # class, group, size (w, d, h), has a support
    ("table", "floor", (1.2, 0.7, 0.75), True), ("chair", "floor", (0.45, 0.5, 0.9), False),
    ("bed", "floor", (1.4, 2.0, 0.5), True), ("nightstand", "floor", (0.45, 0.4, 0.55), True),
    ("sofa", "floor", (1.8, 0.85, 0.8), False), ("widget", "floor", (0.3, 0.3, 0.4), False),
    ("picture", "wall", (0.7, 0.04, 0.5), False), ("shelf", "wall", (0.9, 0.25, 0.3), True),
    ("cup", "obj", (0.08, 0.08, 0.1), False), ("book", "obj", (0.2, 0.15, 0.04), False),
]


def _box(size) -> MeshData:
    import trimesh

    m = trimesh.creation.box(extents=size)
    m.apply_translation((0, 0, size[2] / 2))
    return MeshData(np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.int32),
                    np.full((len(m.faces), 3), 180, np.uint8))


def make_catalog(root, per_class: int = 2) -> Catalog:
    cat = Catalog(root)
    for cls, group, size, sup in SPECS:
        for i in range(per_class):
            s = (size[0] * (1 + 0.1 * i), size[1] * (1 + 0.1 * i), size[2])
            hw, hd = s[0] * 0.45, s[1] * 0.45
            sups = (SupportSurface(s[2], ((-hw, -hd), (hw, -hd), (hw, hd), (-hw, hd))),) if sup else ()
            rec = AssetRecord(id=f"toy:{cls}/{i}", source="toy", name=cls, class_name=cls, groups=(group,), size=s,
                              supports=sups)
            cat.add(rec, _box(s))
    cat.save()
    return cat


@dataclass(frozen=True)
class _Result:
    instances: tuple
    dropped: tuple
    score: float
    seconds: float
    stats: dict


def _fake_place(request: PlanRequest, plan: GroupPlan, catalog, *, cfg, rng, next_id):
    """Stand-in placement: objects in a row along x; whatever does not fit the room is dropped."""
    room = np.asarray(request.room.polygon)
    width, depth = room.max(0) - room.min(0)
    insts, dropped, x = [], [], 0.0
    base = np.eye(4)
    if request.support is not None:
        base = np.array(request.support.pose)
    for item in plan.order:
        rec = request.objects[item.source]
        if rec.size[0] > width or rec.size[1] > depth or x + rec.size[0] > width:
            dropped.append(DroppedObject(rec.id, request.group, "no valid cell"))
            continue
        pose = base.copy()
        pose[0, 3] += x + rec.size[0] / 2
        pose[1, 3] += rec.size[1] / 2
        x += rec.size[0] + 0.05
        insts.append(PlacedInstance(next_id + len(insts), rec.id, rec.class_name, request.group, pose,
                                    request.support.id if request.support else None, ()))
    return _Result(tuple(insts), tuple(dropped), 0.0, 0.0, {"candidates": len(plan.order)})


def _fake_random(request, catalog, *, cfg, rng, next_id):
    plan = GroupPlan(request.group, tuple(PlannedObject(i) for i in range(len(request.objects))), "none")
    return _fake_place(request, plan, catalog, cfg=cfg, rng=rng, next_id=next_id)


STANDIN = layout_mod.Placer(_fake_place, _fake_random)


@pytest.fixture(params=["standin", "real"])
def placement(request):
    """The placer a test's layouts use: the stand-in above or the real engine."""
    return STANDIN if request.param == "standin" else layout_mod.Placer()


def _cfg(**sel) -> GenerateConfig:
    return GenerateConfig.model_validate({"selection": {"floor_count": 12, "wall_count": 4, "on_top_count": 2, **sel},
                                          # a budget that never binds: a search cut by the clock is not
                                          # reproducible on a loaded machine; max_backtracks bounds it
                                          "layout": {"group_budget_s": 30.0, "max_backtracks": 200}})


def _strip_timing(d: dict) -> dict:
    d = json.loads(json.dumps(d))
    d.pop("seconds")
    d["stats"].pop("timing")
    d["stats"].get("placement", {}).pop("seconds", None)
    return d


def test_same_seed_same_json_and_contract(tmp_path, placement):
    cat = make_catalog(tmp_path / "cat")
    cfg = _cfg()
    a = build_layout(cat, cfg, 11, scene_index=1, placer=placement)
    b = build_layout(cat, cfg, 11, scene_index=1, placer=placement)
    c = build_layout(cat, cfg, 12, scene_index=1, placer=placement)
    ja = a.to_json()
    assert _strip_timing(ja) == _strip_timing(b.to_json())
    assert _strip_timing(ja) != _strip_timing(c.to_json())
    assert {"room", "instances", "dropped", "seconds", "planner"} <= set(ja)
    ids = [i["id"] for i in ja["instances"]]
    assert ids == list(range(1, len(ids) + 1))
    for inst in ja["instances"]:
        assert {"id", "asset", "class", "group", "pose", "parent"} <= set(inst)
        assert np.asarray(inst["pose"]).shape == (4, 4)
    assert ja["planner"]["floor"] == "rules" and ja["planner"]["wall"] == "rules"
    assert all(v == "rules" for v in ja["planner"].values())
    for d in ja["dropped"]:
        assert {"asset", "group", "reason"} <= set(d) and d["reason"]
    # everything selected is either placed or dropped with a reason
    st = ja["stats"]
    assert sum(st["selected"].values()) == len(ja["instances"]) + len(ja["dropped"])
    assert st["placed"]["floor"] >= 1
    on_top = [i for i in a.instances if i.parent is not None]
    for inst in on_top:
        parent = next(p for p in a.instances if p.id == inst.parent)
        assert inst.group == f"on:{parent.id}" or inst.group == "obj"
        assert cat.get(parent.asset).supports


def test_room_smaller_than_every_object_drops_with_reasons(tmp_path, placement):
    cat = make_catalog(tmp_path / "cat")
    cfg = _cfg().model_copy(update={"room": _cfg().room.model_copy(update={"area_min": 0.04, "area_max": 0.05})})
    lay = build_layout(cat, cfg, 3, placer=placement)
    assert lay.instances == ()
    assert len(lay.dropped) == sum(lay.stats["selected"].values())
    assert all(d.reason for d in lay.dropped)
    assert any(d.reason == "parent not placed" for d in lay.dropped)


class _BadPlanner:
    """Plans with rules, then breaks the plan: a hard relation to an unknown object, a soft one to a
    later object, an unknown relation name and a duplicated object."""

    name = "bad"

    def plan(self, request, *, rng):
        good = RulePlanner().plan(request, rng=rng)
        order = list(good.order)
        if request.group == "floor" and len(order) >= 3:
            order[0] = PlannedObject(order[0].source, (Relation("near", 99, (), True),))
            order[1] = PlannedObject(order[1].source, (Relation("near", 2), Relation("levitate")))
            order.append(order[2])
        return replace(good, order=tuple(order), planner="bad")


def test_broken_plan_is_repaired_not_raised(tmp_path, placement):
    cat = make_catalog(tmp_path / "cat")
    lay = build_layout(cat, _cfg(), 5, planner=_BadPlanner(), placer=placement)
    reasons = [d.reason for d in lay.dropped if d.group == "floor"]
    assert any("unknown or later object 99" in r for r in reasons)
    notes = " | ".join(lay.stats["notes"])
    assert "unknown relation 'levitate'" in notes and "listed twice" in notes and "later object 2" in notes
    assert lay.planner["floor"] == "bad"


def test_sanitise_plan_unit():
    recs = tuple(AssetRecord(id=f"a{i}", source="t", name="x", class_name="x", groups=("floor",), size=(1, 1, 1))
                 for i in range(3))
    from assist3d.core.contracts import Room

    req = PlanRequest("floor", recs, Room(((0, 0), (4, 0), (4, 4), (0, 4)), 2.5))
    plan = GroupPlan("floor", (PlannedObject(2), PlannedObject(0, (Relation("near", 0), Relation("edge", None, (), True))),
                               PlannedObject(0), PlannedObject(7)), "x")
    fixed, dropped, notes = sanitise_plan(plan, req)
    assert [p.source for p in fixed.order] == [2, 0, 1]
    assert fixed.order[1].relations == (Relation("near", 0), Relation("edge", None, (), True))
    assert dropped == [] and len(notes) == 3  # duplicate, out of range, missing object 1


def test_randomrooms_mode_uses_random_placement(tmp_path):
    calls = []

    def spy_random(request, catalog, *, cfg, rng, next_id):
        calls.append(request.group)
        return _fake_random(request, catalog, cfg=cfg, rng=rng, next_id=next_id)

    cat = make_catalog(tmp_path / "cat")
    from assist3d.config.presets import apply_preset

    cfg = apply_preset({}, "randomrooms")
    lay = build_layout(cat, cfg, 2, placer=layout_mod.Placer(_fake_place, spy_random))
    assert calls == ["floor"] and lay.planner == {"floor": "none"}
    assert all(i.group == "floor" for i in lay.instances)


def test_topdown_png(tmp_path):
    from assist3d.export.topdown import render_topdown

    cat = make_catalog(tmp_path / "cat")
    lay = build_layout(cat, _cfg(), 4, placer=STANDIN)
    out = tmp_path / "l.png"
    render_topdown(lay, cat, out, title="t")
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000


@pytest.mark.slow
def test_cli_layout_and_layout_png(tmp_path):
    pytest.importorskip("assist3d.scene.assemble")
    from typer.testing import CliRunner

    from assist3d.cli import app

    make_catalog(tmp_path / "cat")
    cfg = tmp_path / "c.yaml"
    cfg.write_text("selection: {floor_count: 8, wall_count: 2, on_top_count: 1}\n", encoding="utf-8")
    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["layout", "--assets", str(tmp_path / "cat"), "--seed", "3", "--out", str(out),
                                 "--png", "--config", str(cfg)])
    assert r.exit_code == 0, r.output
    assert "placed" in r.output and "dropped" in r.output
    data = json.loads((out / "layout.json").read_text())
    assert data["instances"] and data["planner"]["floor"] == "rules"
    assert (out / "scene.glb").stat().st_size > 0 and (out / "layout.png").read_bytes()[:4] == b"\x89PNG"
    png2 = tmp_path / "again.png"
    r = CliRunner().invoke(app, ["layout-png", str(out / "layout.json"), "--assets", str(tmp_path / "cat"),
                                 "--out", str(png2)])
    assert r.exit_code == 0, r.output
    assert png2.read_bytes()[:4] == b"\x89PNG"


def test_cli_config_precedence(tmp_path):
    from assist3d.config.presets import compose as compose_config
    from assist3d.core.errors import ConfigError

    f = tmp_path / "c.yaml"
    f.write_text("selection: {on_top_count: 1}\nllm: {model: from-file}\n", encoding="utf-8")
    cfg = compose_config(f, "holodeck-style", {"llm": {"model": "from-flag"}})
    assert cfg.preset == "holodeck-style"
    assert cfg.selection.on_top_count == 1  # the file beats the preset (2)
    assert cfg.selection.strategy == "room-type"  # the preset beats the defaults
    assert cfg.llm.model == "from-flag"  # the flag beats the file
    with pytest.raises(ConfigError, match="did you mean"):
        compose_config(None, "holodek-style", {})
    bad = tmp_path / "bad.yaml"
    bad.write_text("- a list\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="mapping"):
        compose_config(bad, None, {})


def test_holodeck_style_room_places_repeated_models(tmp_path):
    """The room-type strategy through the real layout stage: a bedroom's bed and its nightstands
    (copies of one model) are placed as distinct instances, the room type is recorded."""
    from assist3d.config.presets import apply_preset

    cat = make_catalog(tmp_path / "cat")
    cfg = apply_preset({"selection": {"room_types": ["bedroom"], "assets_per_class": None},
                        "layout": {"group_budget_s": 30.0, "max_backtracks": 200}}, "holodeck-style")
    for seed in range(4):
        lay = build_layout(cat, cfg, seed, scene_index=seed)
        assert lay.stats["selection"]["room_type"] == "bedroom"
        classes = [i.class_name for i in lay.instances]
        assert classes.count("bed") == 1 and classes.count("nightstand") >= 1
        stands = [i for i in lay.instances if i.class_name == "nightstand"]
        assert len({i.asset for i in stands}) == 1 and len({i.id for i in stands}) == len(stands)
        bed = next(i for i in lay.instances if i.class_name == "bed")
        for s in stands:  # next to the bed, not somewhere in the room
            assert np.hypot(*(s.pose[:2, 3] - bed.pose[:2, 3])) < 2.0
        assert {i.class_name for i in lay.instances} <= {"bed", "nightstand", "picture", "book", "cup"}


def test_one_set_of_plan_rules_the_repaired_plan_passes_the_strict_check_and_placement_agrees():
    """review_plan is the only plan checker: what it repairs, validate_plan (the LLM repair loop)
    accepts, and the placement engine's resolve_plan drops the same objects for the same reasons."""
    from assist3d.core.contracts import PlacedInstance, Room
    from assist3d.placement.common import resolve_plan
    from assist3d.planning.relations import review_plan, validate_plan

    recs = tuple(AssetRecord(id=f"a{i}", source="t", name="x", class_name="x", groups=("floor",), size=(1, 1, 1))
                 for i in range(5))
    req = PlanRequest("floor", recs, Room(((0, 0), (4, 0), (4, 4), (0, 4)), 2.5),
                      placed=(PlacedInstance(7, "a9", "x", "floor", np.eye(4)),))
    plan = GroupPlan("floor", (
        PlannedObject(3, (Relation("edge"),)),
        PlannedObject(1, (Relation("near", 0), Relation("near", 4, (), True))),  # hard relation to a later object
        PlannedObject(0, (Relation("near", 1), Relation("height", None, (0.0, 1.0)))),  # soft: to a dropped one; wrong group
        PlannedObject(3), PlannedObject(9),
    ), "x")
    review = review_plan(plan, req)
    assert validate_plan(plan, req) == list(review.problems) and len(review.problems) == 5
    # the repair is well-formed by the strict rules; its only gap is the object it took out
    assert validate_plan(review.plan, req) == ["objects never planned: [1]"]
    assert [p.source for p in review.plan.order] == [3, 0, 2, 4]
    assert review.dropped == ((1, "hard relation unusable: relation 'near' to unknown or later object 4 (not an "
                                   "earlier object of the plan)"),)
    assert review.plan.order[1].relations == ()  # both soft relations of object 0 removed, with notes
    items, notes = resolve_plan(req, plan)
    assert [it.record.id for it in items] == ["a3", "a0", "a2", "a4", "a1"]
    assert [it.forced_reason for it in items][-1] == review.dropped[0][1] and notes == list(review.notes)
    fixed, dropped, _ = sanitise_plan(plan, req)
    assert fixed == review.plan and [(d.asset, d.reason) for d in dropped] == [("a1", review.dropped[0][1])]

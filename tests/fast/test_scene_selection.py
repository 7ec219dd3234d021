"""Heterogeneous object selection and class-list matching."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.assets.catalog import Catalog
from assist3d.config import SelectionConfig
from assist3d.core.contracts import AssetRecord, SupportSurface
from assist3d.core.errors import ConfigError
from assist3d.core.taxonomy.classes import canonical_class, resolve_class_list
from assist3d.scene.selection import is_complementary, partner_map, select_objects

FLOOR = ["table", "chair", "bed", "nightstand", "couch", "coffee table", "widget", "gizmo", "doohickey", "thingamajig"]
WALL = ["picture", "clock", "sprocket"]
OBJ = ["cup", "book", "monitor", "keyboard"]
SUPPORTED = {"table", "nightstand", "coffee table", "gizmo"}


def _rec(cls: str, group: str, i: int, cluster: int | None) -> AssetRecord:
    sup = (SupportSurface(0.7, ((-0.3, -0.3), (0.3, -0.3), (0.3, 0.3), (-0.3, 0.3))),) if cls in SUPPORTED else ()
    return AssetRecord(id=f"t:{cls}/{i}", source="test", name=cls, class_name=cls, groups=(group,),
                       size=(0.2, 0.15, 0.1) if group == "obj" else (0.8, 0.6, 0.7), supports=sup, cluster=cluster)


def _catalog(tmp_path, per_class: int = 3, clusters: bool = True, widget_heavy: int = 0) -> Catalog:
    recs = []
    for group, names in (("floor", FLOOR), ("wall", WALL), ("obj", OBJ)):
        for cls in names:
            n = per_class + (widget_heavy if cls == "widget" else 0)
            recs += [_rec(cls, group, i, (i % 3) if clusters else None) for i in range(n)]
    return Catalog(tmp_path / "cat", recs)


def _sel(cat, seed=0, scene_index=0, **kw):
    return select_objects(cat, SelectionConfig(**kw), np.random.default_rng(seed), scene_index=scene_index)


def test_counts_on_top_and_determinism(tmp_path):
    cat = _catalog(tmp_path)
    a = _sel(cat, floor_count=30, wall_count=7, on_top_count=4)
    assert len(a.floor) == 30 and len(a.wall) == 7
    assert len(a.floor_on_top) == 30 and len(a.wall_on_top) == 7
    for rec, items in zip(a.floor, a.floor_on_top):
        assert len(items) == (4 if rec.supports else 0)
        assert all("obj" in r.groups for r in items)
    assert all("floor" in r.groups for r in a.floor) and all("wall" in r.groups for r in a.wall)
    b = _sel(cat, floor_count=30, wall_count=7, on_top_count=4)
    assert [r.id for r in a.floor] == [r.id for r in b.floor]
    assert [[r.id for r in t] for t in a.floor_on_top] == [[r.id for r in t] for t in b.floor_on_top]
    c = _sel(cat, seed=1, floor_count=30, wall_count=7, on_top_count=4)
    assert [r.id for r in a.floor] != [r.id for r in c.floor]
    # without replacement while a class lasts: a class drawn n times uses min(n, 3) distinct assets
    for cls in {r.class_name for r in a.floor}:
        ids = [r.id for r in a.floor if r.class_name == cls]
        assert len(set(ids)) == min(len(ids), 3)
    d = _sel(cat, floor_count=30, wall_count=0, sampling="asset")
    assert len({r.id for r in d.floor}) == 30  # 30 draws from 30 floor assets are all distinct


def test_class_uniform_vs_asset_uniform(tmp_path):
    cat = _catalog(tmp_path, per_class=2, widget_heavy=200)  # 'widget' has 202 of 220 floor assets
    by_class = [r.class_name for s in range(20) for r in _sel(cat, seed=s, floor_count=50, wall_count=0).floor]
    share = by_class.count("widget") / len(by_class)
    assert 0.05 < share < 0.17  # one class in ten
    by_asset = [r.class_name for s in range(20)
                for r in _sel(cat, seed=s, floor_count=50, wall_count=0, sampling="asset").floor]
    assert by_asset.count("widget") / len(by_asset) > 0.8


def test_complementary_alternation_and_real_class_rate(tmp_path):
    assert [is_complementary(i, 0.5) for i in range(6)] == [False, True, False, True, False, True]
    assert not any(is_complementary(i, 0.0) for i in range(10))
    assert all(is_complementary(i, 1.0) for i in range(10))
    assert sum(is_complementary(i, 0.3) for i in range(100)) == 30
    cat = _catalog(tmp_path)
    real = resolve_class_list("scannet18")
    n_real = sum(real.match(c) is not None for c in FLOOR)  # table chair bed nightstand couch coffee table
    assert n_real == 6
    p = 0.7
    comp = _sel(cat, scene_index=1, floor_count=4000, wall_count=0, on_top_count=0, real_class_prob=p)
    assert comp.complementary and not _sel(cat, scene_index=0, floor_count=1, wall_count=0).complementary
    rate = np.mean([real.match(r.class_name) is not None for r in comp.floor])
    expected = p + (1 - p) * n_real / len(FLOOR)
    assert abs(rate - expected) < 0.03
    assert abs(comp.stats["real_draws"] / comp.stats["draws"] - p) < 0.03
    # the wall pool holds one ScanNet18 class only (picture): below min_real_classes, draws stay uniform
    walls = _sel(cat, scene_index=1, floor_count=0, wall_count=3000, on_top_count=0, real_class_prob=p)
    assert walls.stats["real_draws"] == 0
    assert abs(np.mean([r.class_name == "picture" for r in walls.wall]) - 1 / 3) < 0.03
    walls = _sel(cat, scene_index=1, floor_count=0, wall_count=3000, on_top_count=0, real_class_prob=p,
                 min_real_classes=1)
    assert abs(np.mean([r.class_name == "picture" for r in walls.wall]) - (p + (1 - p) / 3)) < 0.03
    plain = _sel(cat, scene_index=0, floor_count=4000, wall_count=0, real_class_prob=p)
    assert abs(np.mean([real.match(r.class_name) is not None for r in plain.floor]) - n_real / len(FLOOR)) < 0.03


def test_pairing_probability(tmp_path):
    cat = _catalog(tmp_path)
    partners = partner_map(tuple(sorted(FLOOR)), 0, "floor")
    assert partners["table"] == "chair" and partners["bed"] == "nightstand" and partners["couch"] == "coffee table"
    assert all(partners[c] != c for c in FLOOR)

    def pair_rate(q: float) -> float:
        hits = 0
        for s in range(300):
            f = _sel(cat, seed=s, floor_count=2, wall_count=0, on_top_count=0, pairing_prob=q).floor
            hits += f[1].class_name == partners[f[0].class_name]
        return hits / 300

    assert pair_rate(1.0) == 1.0
    assert abs(pair_rate(0.0) - 1 / len(FLOOR)) < 0.05  # independent draws
    assert 0.45 < pair_rate(0.5) < 0.65  # q + (1 - q) / C = 0.55


def test_filters_and_errors(tmp_path):
    cat = _catalog(tmp_path)
    sel = _sel(cat, floor_count=40, wall_count=5, clusters=[1])
    assert {r.cluster for r in sel.floor + sel.wall} == {1}
    assert all(r.cluster == 1 for items in sel.floor_on_top for r in items)
    sel = _sel(cat, floor_count=40, wall_count=0, allowed_classes=["sofa", "table"])
    assert {r.class_name for r in sel.floor} == {"couch", "table"}  # 'sofa' matches 'couch' by synonym
    sel = _sel(cat, floor_count=60, wall_count=0, max_classes=5, class_pool_seed=3)
    assert len({r.class_name for r in sel.floor}) <= 5
    with pytest.raises(ConfigError, match="cluster"):
        _sel(_catalog(tmp_path / "b", clusters=False), clusters=[0])
    with pytest.raises(ConfigError, match="no floor asset"):
        _sel(cat, allowed_classes=["spaceship"])


def test_class_lists_and_synonyms(tmp_path):
    s18, s200 = resolve_class_list("scannet18"), resolve_class_list("scannet200")
    assert len(s18) == 18 and len(s200) == 198
    assert "wall" not in s200.classes and "floor" not in s200.classes
    cases18 = {"couch": "sofa", "Bookcase": "bookshelf", "fridge": "refrigerator", "armchair": "chair",
               "office_chair": "chair", "coffee-table": "table", "dining chair": "chair", "painting": "picture"}
    for name, want in cases18.items():
        assert s18.match(name) == want, name
    cases200 = {"night table": "nightstand", "sofa": "couch", "fridge": "refrigerator", "bookcase": "bookshelf",
                "television": "tv", "chairs": "chair"}
    for name, want in cases200.items():
        assert s200.match(name) == want, name
    assert s18.match("widget") is None and s200.match("spaceship") is None
    assert canonical_class("Night_Stand") == "nightstand"
    f = tmp_path / "mine.txt"
    f.write_text("# my classes\nSofa\nlamp\n\n", encoding="utf-8")
    mine = resolve_class_list(str(f))
    assert mine.classes == ("sofa", "lamp") and mine.match("couch") == "sofa" and mine.match("floor lamp") == "lamp"
    with pytest.raises(ConfigError, match="neither"):
        resolve_class_list(str(tmp_path / "missing.txt"))


def test_on_top_draws_fit_their_support(tmp_path):
    recs = [_rec("table", "floor", 0, None)]  # support 0.6 x 0.6, unbounded clearance
    big = AssetRecord(id="t:tv/0", source="test", name="tv", class_name="tv", groups=("obj",), size=(1.2, 0.2, 0.7))
    small = AssetRecord(id="t:cup/0", source="test", name="cup", class_name="cup", groups=("obj",),
                        size=(0.1, 0.1, 0.1))
    long_ = AssetRecord(id="t:ruler/0", source="test", name="ruler", class_name="ruler", groups=("obj",),
                        size=(0.1, 0.55, 0.02))
    cat = Catalog(tmp_path / "fit", recs + [big, small, long_])
    sel = _sel(cat, floor_count=5, wall_count=0, on_top_count=4)
    drawn = {r.id for items in sel.floor_on_top for r in items}
    assert drawn == {"t:cup/0", "t:ruler/0"}
    sel = _sel(cat, floor_count=5, wall_count=0, on_top_count=4, on_top_fit=False)
    assert "t:tv/0" in {r.id for items in sel.floor_on_top for r in items}


def test_pool_cache_follows_catalog_changes(tmp_path):
    from assist3d.core.contracts import MeshData

    cat = _catalog(tmp_path)
    before = {r.class_name for r in _sel(cat, floor_count=200, wall_count=0, on_top_count=0).floor}
    assert "hovercraft" not in before
    mesh = MeshData(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32), np.array([[0, 1, 2]], np.int32),
                    np.zeros((1, 3), np.uint8))
    cat.add(_rec("hovercraft", "floor", 0, 0), mesh)
    after = {r.class_name for r in _sel(cat, floor_count=200, wall_count=0, on_top_count=0).floor}
    assert "hovercraft" in after  # the cached pools were rebuilt for the changed catalog


@pytest.mark.slow
def test_assets_per_class_keeps_a_fixed_few_models_per_class(tmp_path):
    from assist3d.assets.procedural import build_library

    cat = build_library(tmp_path / "lib", count=400, seed=0)
    cfg = SelectionConfig(floor_count=60, wall_count=20, on_top_count=2, assets_per_class=1,
                          complementary_fraction=0.0)
    seen: dict[tuple[str, str], set[str]] = {}
    for k in range(4):
        sel = select_objects(cat, cfg, np.random.default_rng(k), scene_index=k)
        drawn = [("floor", r) for r in sel.floor] + [("wall", r) for r in sel.wall] + \
            [("obj", o) for g in sel.floor_on_top + sel.wall_on_top for o in g]
        for group, r in drawn:
            seen.setdefault((r.class_name, group), set()).add(r.id)
    assert seen and all(len(ids) == 1 for ids in seen.values())  # one model per class and group
    # chosen within each group: a class spanning groups keeps a model in every group it has
    # (choosing across groups left some groups without the class: no floor plant, no floor cabinet)
    from assist3d.scene.selection import _filter

    for g in ("floor", "wall", "obj"):
        full = {r.class_name for r in cat.group(g)}
        kept = _filter(cat.group(g), cfg, cat)
        assert {r.class_name for r in kept} == full and len(kept) == len(full)
    free = SelectionConfig(floor_count=60, wall_count=20, on_top_count=2, complementary_fraction=0.0)
    sel = select_objects(cat, free, np.random.default_rng(0), scene_index=0)
    per_class: dict[str, set[str]] = {}
    for r in sel.floor:
        per_class.setdefault(r.class_name, set()).add(r.id)
    assert any(len(ids) > 1 for ids in per_class.values())


# ----------------------------------------------------------------------------- room-type strategy


def _room_catalog(tmp_path, drop: tuple[str, ...] = (), per_class: int = 3) -> Catalog:
    """Three assets of every class named by the room templates, in the template's group; floor
    and wall assets carry a support surface."""
    from assist3d.core.taxonomy.roomtypes import ROOM_TEMPLATES

    recs, seen = [], set()
    for t in ROOM_TEMPLATES.values():
        for group, names in (("floor", [i.cls for i in t.floor]), ("wall", [i.cls for i in t.wall]),
                             ("obj", list(t.small))):
            for cls in names:
                if cls in drop or (group, cls) in seen:
                    continue
                seen.add((group, cls))
                sup = (SupportSurface(0.7, ((-0.4, -0.4), (0.4, -0.4), (0.4, 0.4), (-0.4, 0.4))),) \
                    if group != "obj" else ()
                size = (0.2, 0.15, 0.1) if group == "obj" else (0.9, 0.6, 0.7)
                recs += [AssetRecord(id=f"r:{group}:{cls}/{i}", source="test", name=cls, class_name=cls,
                                     groups=(group,), size=size, supports=sup) for i in range(per_class)]
    return Catalog(tmp_path / "rooms", recs)


def _room(cat, seed=0, scene_index=0, **kw):
    return _sel(cat, seed=seed, scene_index=scene_index, strategy="room-type", on_top_count=2, **kw)


def test_room_type_follows_the_template(tmp_path):
    from assist3d.core.taxonomy.roomtypes import ROOM_TEMPLATES

    cat = _room_catalog(tmp_path)
    for seed in range(8):
        s = _room(cat, seed=seed, room_types=["dining room"])
        assert s.stats["room_type"] == "dining room" and not s.complementary
        classes = [r.class_name for r in s.floor]
        assert classes.count("dining table") == 1
        chairs = [r.id for r in s.floor if r.class_name == "chair"]
        assert 4 <= len(chairs) <= 6 and len(set(chairs)) == 1  # identical copies of one model
        small = set(ROOM_TEMPLATES["dining room"].small)
        holders = {i.cls for i in ROOM_TEMPLATES["dining room"].floor + ROOM_TEMPLATES["dining room"].wall if i.holds}
        for parent, items in zip(s.floor + s.wall, s.floor_on_top + s.wall_on_top):
            # small objects go on tables and cabinets, not on chairs, pictures or plants
            assert len(items) == (2 if parent.class_name in holders else 0), parent.class_name
            # an asset matches by its class or its canonical class (a mug is a cup)
            assert all(r.class_name in small or canonical_class(r.class_name) in small for r in items)
        assert len(s.floor_on_top[classes.index("dining table")]) == 2
        assert {r.class_name for r in s.wall} <= {i.cls for i in ROOM_TEMPLATES["dining room"].wall}
        assert len(s.floor) < 100  # floor_count is not used
        # varied items are drawn anew for each copy: pictures of a room use distinct models (3 exist)
        pics = [r.id for r in s.wall if r.class_name == "picture"]
        assert len(set(pics)) == len(pics)


def test_room_type_quantities_follow_their_anchor(tmp_path):
    cat = _room_catalog(tmp_path)
    for seed in range(12):
        office = _room(cat, seed=seed, room_types=["office"])
        classes = [r.class_name for r in office.floor]
        assert classes.count("office chair") == classes.count("desk") >= 1
        kitchen = _room(cat, seed=seed, room_types=["kitchen"])
        classes = [r.class_name for r in kitchen.floor]
        assert "refrigerator" in classes
        assert ("chair" in classes) <= ("table" in classes)  # chairs only with a table


def test_room_type_is_seeded_and_covers_every_type(tmp_path):
    from assist3d.core.taxonomy.roomtypes import ROOM_TEMPLATES

    cat = _room_catalog(tmp_path)
    a = [_room(cat, seed=s) for s in range(60)]
    b = [_room(cat, seed=s) for s in range(60)]
    assert [[r.id for r in x.floor] for x in a] == [[r.id for r in x.floor] for x in b]
    assert {x.stats["room_type"] for x in a} == set(ROOM_TEMPLATES)
    # the heterogeneous strategy draws no room type and its draws are unchanged by the new option
    h = _sel(cat, seed=3, floor_count=10, wall_count=3)
    assert "room_type" not in h.stats and len(h.floor) == 10


def test_room_type_missing_class_is_skipped_and_counted(tmp_path):
    cat = _room_catalog(tmp_path, drop=("refrigerator", "stove"))
    s = _room(cat, seed=0, room_types=["kitchen"])
    classes = {r.class_name for r in s.floor}
    assert "refrigerator" not in classes and "counter" in classes
    assert s.stats["template_misses"] >= 1


def test_room_type_with_retrieval_reuses_few_models(tmp_path):
    cat = _room_catalog(tmp_path, per_class=6)
    used: dict[tuple[str, str], set[str]] = {}
    for seed in range(30):
        s = _room(cat, seed=seed, assets_per_class=1)
        drawn = [("floor", r) for r in s.floor] + [("wall", r) for r in s.wall] + \
            [("obj", r) for t in s.floor_on_top + s.wall_on_top for r in t]
        for group, r in drawn:
            used.setdefault((r.class_name, group), set()).add(r.id)
    assert used and all(len(ids) == 1 for ids in used.values()), {c: ids for c, ids in used.items() if len(ids) > 1}


def test_unknown_room_type_is_a_config_error():
    with pytest.raises(ValueError, match="unknown room type"):
        SelectionConfig(room_types=["garage"])


def test_room_item_falls_back_to_qualified_class_names(tmp_path):
    """A catalog without a plain "mug" class but with "coffee mug" still serves the item "mug"
    (as a text retrieval would); an exact class wins when there is one, and a different kind
    sharing the last word ("wine bottle" for "soap bottle") never matches."""
    from assist3d.scene.selection import _Pool

    def rec(cls, i=0):
        return AssetRecord(id=f"q:{cls}/{i}", source="test", name=cls, class_name=cls, groups=("obj",),
                           size=(0.1, 0.1, 0.1))

    pool = _Pool((rec("coffee mug"), rec("wall flat tv"), rec("wine bottle"), rec("tv"), rec("smug")))
    assert [r.class_name for r in pool.item_models("mug", None, 0)] == ["coffee mug"]
    assert [r.class_name for r in pool.item_models("tv", None, 0)] == ["tv"]  # exact match first
    assert pool.item_models("soap bottle", None, 0) == ()

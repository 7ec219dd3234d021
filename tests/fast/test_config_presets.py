"""Generator presets: every preset validates, user values win over preset values, the baselines
change what they claim to change, and the Holodeck-style room templates name real asset classes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from assist3d.config import GenerateConfig
from assist3d.core.errors import ConfigError
from assist3d.config.presets import HOUSEHOLD_CLASSES, PRESETS, apply_preset, compose, preset_overrides


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_every_preset_validates(name):
    cfg = apply_preset({}, name)
    assert isinstance(cfg, GenerateConfig) and cfg.preset == name


def test_baselines_and_ablations_set_what_they_claim():
    default = GenerateConfig()
    rr = apply_preset({}, "randomrooms")
    assert rr.layout.planner == "none" and rr.selection.complementary_fraction == 0.0
    assert rr.selection.wall_count == 0 and rr.selection.on_top_count == 0
    hd = apply_preset({}, "holodeck-style")
    assert hd.selection.strategy == "room-type" and hd.layout.planner == default.layout.planner
    assert hd.selection.assets_per_class == 2 and hd.selection.on_top_count == 2
    assert hd.selection.complementary_fraction == 0.0 and default.selection.strategy == "heterogeneous"
    assert apply_preset({}, "no-context").selection.pairing_prob == pytest.approx(0.66)
    assert apply_preset({}, "assist3d").model_dump(exclude={"preset"}) == default.model_dump(exclude={"preset"})
    assert apply_preset({}, "mesh-sampled").render.point_source == "mesh"
    assert [apply_preset({}, f"pairing-{q}").selection.pairing_prob for q in ("1.0", "0.66", "0.33", "0")] == \
        [1.0, 0.66, 0.33, 0.0]
    assert apply_preset({}, "clusters-3").selection.clusters == [0, 1, 2]
    assert apply_preset({}, "classes-200").selection.max_classes == 200


def test_user_values_override_preset_values():
    cfg = apply_preset({"selection": {"assets_per_class": 5, "room_types": ["office"]}, "seed": 5}, "holodeck-style")
    assert cfg.selection.assets_per_class == 5 and cfg.selection.room_types == ["office"] and cfg.seed == 5
    # keys the user did not set keep the preset's value (a nested merge, not a replacement)
    assert cfg.selection.strategy == "room-type" and cfg.selection.on_top_count == 2
    cfg = apply_preset({"layout": {"planner": "rules"}}, "randomrooms")
    assert cfg.layout.planner == "rules" and cfg.selection.floor_count == 40
    # applying a preset never mutates the preset table, and a config's list is its own
    assert PRESETS["holodeck-style"]["selection"]["assets_per_class"] == 2
    cp = apply_preset({}, "clusters-2")
    cp.selection.clusters.append(4)
    assert PRESETS["clusters-2"]["selection"]["clusters"] == [0, 1]
    assert apply_preset({}, "clusters-2").selection.clusters == [0, 1]


def test_unknown_preset_and_bad_user_values_are_named():
    with pytest.raises(ConfigError, match="did you mean 'randomrooms'"):
        preset_overrides("randomroom")
    with pytest.raises(ConfigError, match="preset no-context"):
        apply_preset({"selection": {"pairing_prob": 3.0}}, "no-context")


@pytest.mark.slow
def test_room_template_classes_exist_in_their_groups_of_the_procedural_library():
    """Each floor item of a room template must be a floor class of the procedural library, each
    wall item a wall class and each small object an on-top class; else the Holodeck-style baseline
    would silently lose that object on the built-in library."""
    from assist3d.assets.procedural import FAMILIES, asset_groups, build_family
    from assist3d.core.taxonomy.classes import canonical_class, normalise_class
    from assist3d.core.taxonomy.roomtypes import ROOM_TEMPLATES

    keys: dict[str, set[str]] = {"floor": set(), "wall": set(), "obj": set()}
    for name, fam in FAMILIES.items():
        for seed in range(12):  # a family's class varies with the seed (bottle / wine bottle)
            a = build_family(name, rng=np.random.default_rng(seed))
            for g in asset_groups(fam.groups, a.size):
                keys[g] |= {normalise_class(a.class_name), canonical_class(a.class_name)}
    for room, t in ROOM_TEMPLATES.items():
        for group, names in (("floor", [i.cls for i in t.floor]), ("wall", [i.cls for i in t.wall]),
                             ("obj", list(t.small))):
            missing = [n for n in names if n not in keys[group]]
            assert missing == [], (room, group, missing)
    assert len(set(HOUSEHOLD_CLASSES)) == len(HOUSEHOLD_CLASSES)


def test_the_household_sparse_config_is_the_measured_one_and_keeps_the_template_classes():
    """configs/household-sparse.yaml (documented for users) must stay the file the fidelity runs used and
    list exactly the room templates' classes, so a change to the templates cannot silently leave it behind."""
    root = Path(__file__).resolve().parents[2]
    shipped = root / "configs" / "household-sparse.yaml"
    measured = root / "experiments" / "holodeck-why-2026-11-28" / "household-sparse.yaml"
    for preset in ("assist3d", "mesh-sampled"):
        a, b = compose(shipped, preset), compose(measured, preset)
        assert a.model_dump() == b.model_dump()
        assert sorted(a.selection.allowed_classes) == sorted(HOUSEHOLD_CLASSES)
        assert (a.selection.floor_count, a.selection.wall_count, a.selection.on_top_count) == (15, 8, 2)
        rest = a.model_dump(exclude={"selection"})
        assert rest == compose(None, preset).model_dump(exclude={"selection"})

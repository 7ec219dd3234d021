"""Generator presets: every preset validates, user values win over preset values, the baselines
change what they claim to change, and the Holodeck-style class list matches real asset classes."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.config import GenerateConfig
from assist3d.errors import ConfigError
from assist3d.presets import HOUSEHOLD_CLASSES, PRESETS, apply_preset, preset_overrides


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
    assert hd.selection.pairing_prob == 1.0 and hd.layout.planner == default.layout.planner
    assert hd.selection.allowed_classes == list(HOUSEHOLD_CLASSES)
    assert hd.selection.floor_count < default.selection.floor_count / 4
    assert apply_preset({}, "no-context").selection.pairing_prob == pytest.approx(0.66)
    assert apply_preset({}, "assist3d").model_dump(exclude={"preset"}) == default.model_dump(exclude={"preset"})
    assert apply_preset({}, "mesh-sampled").render.point_source == "mesh"
    assert [apply_preset({}, f"pairing-{q}").selection.pairing_prob for q in ("1.0", "0.66", "0.33", "0")] == \
        [1.0, 0.66, 0.33, 0.0]
    assert apply_preset({}, "clusters-3").selection.clusters == [0, 1, 2]
    assert apply_preset({}, "classes-200").selection.max_classes == 200


def test_user_values_override_preset_values():
    cfg = apply_preset({"selection": {"pairing_prob": 0.2, "floor_count": 7}, "seed": 5}, "holodeck-style")
    assert cfg.selection.pairing_prob == 0.2 and cfg.selection.floor_count == 7 and cfg.seed == 5
    # keys the user did not set keep the preset's value (a nested merge, not a replacement)
    assert cfg.selection.allowed_classes == list(HOUSEHOLD_CLASSES) and cfg.selection.wall_count == 4
    cfg = apply_preset({"layout": {"planner": "rules"}}, "randomrooms")
    assert cfg.layout.planner == "rules" and cfg.selection.floor_count == 40
    # applying a preset never mutates the preset table, and a config's list is its own
    assert PRESETS["holodeck-style"]["selection"]["pairing_prob"] == 1.0
    hd = apply_preset({}, "holodeck-style")
    hd.selection.allowed_classes.append("spaceship")
    assert "spaceship" not in HOUSEHOLD_CLASSES and "spaceship" not in apply_preset({}, "holodeck-style").selection.allowed_classes


def test_unknown_preset_and_bad_user_values_are_named():
    with pytest.raises(ConfigError, match="did you mean 'randomrooms'"):
        preset_overrides("randomroom")
    with pytest.raises(ConfigError, match="preset no-context"):
        apply_preset({"selection": {"pairing_prob": 3.0}}, "no-context")


def test_household_classes_match_procedural_classes():
    from assist3d.assets.procedural import FAMILIES, build_family
    from assist3d.scene.classes import canonical_class, normalise_class

    built = {build_family(n, rng=np.random.default_rng(0)).class_name for n in FAMILIES}
    keys = {normalise_class(c) for c in built} | {canonical_class(c) for c in built}
    missing = [h for h in HOUSEHOLD_CLASSES if normalise_class(h) not in keys and canonical_class(h) not in keys]
    assert missing == []
    assert len(set(HOUSEHOLD_CLASSES)) == len(HOUSEHOLD_CLASSES)

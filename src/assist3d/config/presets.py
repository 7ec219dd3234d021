"""Generator presets: the paper's method, the baselines it compares with, and its ablations.

A preset is a set of config overrides applied before the user's own config file and flags, so
every generator shares one pipeline and one output format. ``assist3d generate --preset NAME``.
"""

from __future__ import annotations

import difflib
from pathlib import Path

from .files import merge_config, parse_config, read_config_file
from .sections import GenerateConfig
from ..core.errors import ConfigError
from ..core.taxonomy.roomtypes import template_classes

# Every class a Holodeck-style room may hold (the room templates of assist3d.core.taxonomy.roomtypes).
# Canonical names (see assist3d.core.taxonomy.classes): an asset matches when its class or its canonical
# class is listed, so "bookcase" and "bedside table" assets count as bookshelf and nightstand.
# Every name matches classes of the built-in procedural library (tests check it).
HOUSEHOLD_CLASSES = template_classes()

PRESETS: dict[str, dict] = {
    # ASSIST-3D as in the paper: random heterogeneous selection, relations + depth-first search,
    # rendered RGB-D fusion. Half the scenes use the complementary real-class strategy.
    "assist3d": {},
    # RandomRooms-style: random assets, random positions and yaws, no relations, no collision
    # reasoning beyond dropping objects on the floor (or on what lies below).
    "randomrooms": {
        "layout": {"planner": "none"},
        "selection": {"floor_count": 40, "wall_count": 0, "on_top_count": 0, "complementary_fraction": 0.0},
    },
    # Holodeck-style: a room type per scene and the objects an LLM keeps choosing for it (anchors,
    # typical companions, identical copies), a fixed few retrieved models per class, relation-guided
    # placement.
    "holodeck-style": {
        "selection": {"strategy": "room-type", "on_top_count": 2, "assets_per_class": 2,
                      "complementary_fraction": 0.0},
    },
    # ASSIST-3D without context complexity: a class's partner is co-selected with probability 0.66.
    "no-context": {"selection": {"pairing_prob": 0.66}},
    # Ablations of the paper's tables.
    "mesh-sampled": {"render": {"point_source": "mesh"}},
    **{f"pairing-{q}": {"selection": {"pairing_prob": float(q)}} for q in ("1.0", "0.66", "0.33", "0")},
    **{f"clusters-{k}": {"selection": {"clusters": list(range(k))}} for k in range(1, 6)},
    **{f"classes-{n}": {"selection": {"max_classes": n}} for n in (100, 200, 400)},
}


def preset_overrides(name: str) -> dict:
    """The config overrides of preset ``name``; an unknown name lists close matches."""
    if name not in PRESETS:
        close = difflib.get_close_matches(name, PRESETS, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else f"; known presets: {', '.join(PRESETS)}"
        raise ConfigError(f"unknown preset {name!r}{hint}")
    return PRESETS[name]


def apply_preset(data: dict, name: str) -> GenerateConfig:
    """Apply preset ``name`` under the user's config dict ``data`` (the user's values win)."""
    merged = merge_config(preset_overrides(name), data or {})
    merged["preset"] = name
    return parse_config(merged, source=f"preset {name}")


def compose(config: str | Path | None = None, preset: str | None = None,
            overrides: dict | None = None) -> GenerateConfig:
    """The configuration `assist3d generate` and `assist3d layout` run with: the preset's overrides,
    then the YAML file ``config``, then ``overrides`` (the command-line flags); the last wins.

    The preset is ``preset``, else the file's ``preset`` key, else ``assist3d``. A library user
    reproduces a command exactly with ``compose(...)`` and :func:`assist3d.pipeline.generate_dataset`.
    """
    data = merge_config(read_config_file(config) if config is not None else {}, overrides or {})
    name = preset or data.pop("preset", None) or "assist3d"
    data.pop("preset", None)
    return apply_preset(data, name)

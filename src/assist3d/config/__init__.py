"""Typed configuration, loadable from YAML. Every field states its paper default (if any).

One section per pipeline stage (``sections.py``); ``GenerateConfig`` composes them. ``files.py``:
``load_config`` reads a YAML file (unknown keys are an error that lists close matches), and
``dump_config`` writes the resolved copy next to the outputs. ``presets.py``: the named presets and
how a command's preset, file and flags are composed.
"""

from __future__ import annotations

from .files import (
    describe_validation_error,
    validate_config,
    parse_config,
    read_yaml_mapping,
    read_config_file,
    load_config,
    merge_config,
    config_to_dict,
    dump_config,
)
from .sections import (
    Section,
    AssetsConfig,
    RoomConfig,
    SelectionConfig,
    LayoutConfig,
    RenderConfig,
    LLMConfig,
    OutputConfig,
    GenerateConfig,
)

__all__ = [
    "Section",
    "AssetsConfig",
    "RoomConfig",
    "SelectionConfig",
    "LayoutConfig",
    "RenderConfig",
    "LLMConfig",
    "OutputConfig",
    "GenerateConfig",
    "describe_validation_error",
    "validate_config",
    "parse_config",
    "read_yaml_mapping",
    "read_config_file",
    "load_config",
    "merge_config",
    "config_to_dict",
    "dump_config",
]

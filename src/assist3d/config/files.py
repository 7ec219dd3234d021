"""Configurations in and out: validation with errors that name the key and a fix, YAML files read
(unknown keys are an error that lists close matches), merged and written back.
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from ..core.errors import ConfigError, shown
from ..core.fileio import write_text_atomic
from ..core.reading import read_yaml
from .sections import GenerateConfig

M = TypeVar("M", bound=BaseModel)


def describe_validation_error(err: ValidationError, model: type[BaseModel]) -> list[str]:
    """One line per problem: the dotted key, what is wrong, the value given, and for an unknown key the
    closest known key at that level (``"layout.flor_count: unknown key; did you mean 'floor_count'?"``)."""
    lines = []
    for e in err.errors():
        loc = ".".join(str(p) for p in e["loc"]) or "(top level)"
        msg = e["msg"]
        if e["type"] == "extra_forbidden":
            target: Any = model
            for p in e["loc"][:-1]:
                f = target.model_fields.get(str(p)) if hasattr(target, "model_fields") else None
                target = f.annotation if f is not None else None
            names = list(getattr(target, "model_fields", {}).keys())
            close = difflib.get_close_matches(str(e["loc"][-1]), names, n=1)
            msg = "unknown key" + (f"; did you mean {close[0]!r}?" if close else f"; known keys: {', '.join(names)}")
        else:
            value = e.get("input")
            if isinstance(value, (int, float, str, bool)):
                msg += f" (got {shown(repr(value), 60)})"
        lines.append(f"{loc}: {msg}")
    return lines


def validate_config(model: type[M], data: dict | None, *, source: str = "<dict>",
                    what: str = "configuration") -> M:
    """Validate a plain dict into ``model`` (a :class:`Section`); a :class:`ConfigError` names the source,
    every wrong key and a fix."""
    try:
        return model.model_validate(data or {})
    except ValidationError as err:
        detail = "\n".join(f"  {line}" for line in describe_validation_error(err, model))
        raise ConfigError(f"{source}: invalid {what}\n{detail}") from None


def parse_config(data: dict | None, *, source: str = "<dict>") -> GenerateConfig:
    """Validate a plain dict into a :class:`GenerateConfig`; errors name the key and a fix."""
    return validate_config(GenerateConfig, data, source=source)


def read_yaml_mapping(path: str | Path, *, missing: str = "config file not found") -> dict:
    """The mapping at the top of YAML file ``path`` (empty file: ``{}``); a :class:`ConfigError`
    naming the file when it is absent (``missing`` says what to do), not YAML, or not a mapping."""
    p = Path(path)
    loaded = read_yaml(p, error=ConfigError, missing=missing, what="configuration")
    if loaded is not None and not isinstance(loaded, dict):
        raise ConfigError(f"{p}: expected a mapping at the top level, got {type(loaded).__name__}")
    return loaded or {}


def read_config_file(path: str | Path) -> dict:
    """The mapping in YAML file ``path``, validated on its own so an error names the file (a
    preset or flags may still be merged over it: see :func:`assist3d.config.presets.compose`)."""
    data = read_yaml_mapping(path)
    parse_config(data, source=str(path))
    return data


def load_config(path: str | Path | None, overrides: dict | None = None) -> GenerateConfig:
    """Read a YAML config file (or defaults if ``path`` is None) and apply nested ``overrides``."""
    data = read_config_file(path) if path is not None else {}
    if overrides:
        data = merge_config(data, overrides)
    return parse_config(data, source=str(path) if path else "<defaults>")


def merge_config(base: dict, over: dict) -> dict:
    """``base`` with ``over`` merged in, nested mappings key by key (``over`` wins)."""
    out = dict(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = merge_config(out[k], v)
        else:
            out[k] = v
    return out


def config_to_dict(cfg: BaseModel) -> dict:
    """A JSON-safe dict of the resolved config (secrets are never part of it)."""
    return cfg.model_dump(mode="json")


def dump_config(cfg: BaseModel, path: str | Path) -> None:
    write_text_atomic(path, yaml.safe_dump(config_to_dict(cfg), sort_keys=False))

"""The dataset-level ``manifest.json``: resolved config, versions, seed, classes and one entry
per finished scene, rewritten atomically as scenes finish. Scene entries are rebuilt from the
scenes' own completion markers, so the manifest is always consistent with the folders.

Beside it, the split lists ``train.json`` and ``val.json``: JSON lists of scene folder names
(relative to the dataset folder, what Pointcept's ``DefaultDataset`` reads when its ``split`` names a
file). The rule depends on the scene index alone, so a scene never changes split when a dataset
grows or is resumed: every fifth scene (index 0, 5, 10, ...) is validation, the others training."""

from __future__ import annotations

import json
import logging
from importlib import metadata
from pathlib import Path

from .. import __version__
from ..config import GenerateConfig, config_to_dict
from ..core import reading
from ..core.errors import DataError, shown
from ..core.fileio import write_json_atomic
from ..core.records import manifest_entry

log = logging.getLogger(__name__)

__all__ = ["MANIFEST_NAME", "SPLIT_FILES", "VAL_EVERY", "split_of", "versions", "scene_entry", "llm_summary",
           "Manifest", "IGNORED_CONFIG_KEYS", "read_manifest"]

MANIFEST_NAME = "manifest.json"
#: split name -> the file listing its scenes
SPLIT_FILES = {"train": "train.json", "val": "val.json"}
#: scene index k is a validation scene when k % VAL_EVERY == 0
VAL_EVERY = 5


def split_of(index: int) -> str:
    """The split of the scene with index ``index``: ``"val"`` for every fifth one, else ``"train"``."""
    return "val" if int(index) % VAL_EVERY == 0 else "train"


# settings that change speed or extra files, never the arrays: a resume may change them
IGNORED_CONFIG_KEYS = (("render", "threads"), ("output", "ply"), ("output", "save_mesh"))
#: options whose default changed: a config written before the option existed was made with this value,
#: not with today's default
LEGACY_DEFAULTS = {("render", "rays"): "full"}


def read_manifest(root: str | Path, *, fix: str = "") -> dict | None:
    """The ``manifest.json`` of dataset folder ``root`` as a dict, None if the folder has none; a
    :class:`DataError` naming the file (and ``fix``, what to do) if it is unreadable or not an object."""
    path = Path(root) / MANIFEST_NAME
    if not path.is_file():
        return None
    try:
        data = reading.read_json(path, what="manifest")
    except DataError as e:
        raise DataError(f"{shown(path, 400)}: unreadable manifest ({reading.problem(e, path)}){fix}") from None
    if not isinstance(data, dict):
        raise DataError(f"{path}: unreadable manifest (expected a JSON object, got {type(data).__name__}){fix}")
    return data


def versions() -> dict[str, str]:
    """Versions of the packages that determine the output."""
    out = {"assist3d": __version__}
    for pkg in ("numpy", "trimesh", "embreex", "scipy", "shapely", "fpsample"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "missing"
    return out


def scene_entry(meta: dict) -> dict:
    """The manifest entry of a scene, from its completion marker (the keys of
    :data:`assist3d.core.records.MANIFEST_ENTRY_KEYS`)."""
    return manifest_entry(meta)


def llm_summary(scenes: list[dict]) -> dict:
    """Dataset totals of the LLM planner: models used, calls, cache hits, repairs, tokens, seconds,
    and how many groups each planner produced."""
    models = sorted({p.split(":", 1)[1] for e in scenes for p in (e.get("planner") or {}).values()
                     if isinstance(p, str) and p.startswith("llm:")})
    groups: dict[str, int] = {}
    for e in scenes:
        for p in (e.get("planner") or {}).values():
            key = "llm" if isinstance(p, str) and p.startswith("llm:") else str(p)
            groups[key] = groups.get(key, 0) + 1
    totals: dict[str, float] = {}
    for e in scenes:
        for k, v in (e.get("llm") or {}).items():
            totals[k] = totals.get(k, 0) + v
    return {"models": models, "groups_by_planner": groups,
            **{k: (round(v, 3) if isinstance(v, float) else v) for k, v in sorted(totals.items())}}


def _comparable(cfg: dict) -> dict:
    """``cfg`` without the ignored keys and with every option it lacks at today's default (or, for an
    option whose default changed, at :data:`LEGACY_DEFAULTS`): a dataset written before an option
    existed was made as if it had that value, so it stays resumable, and only with that value."""
    out = json.loads(json.dumps(cfg))
    for (section, key), value in LEGACY_DEFAULTS.items():
        if isinstance(out.get(section), dict):
            out[section].setdefault(key, value)
    for section, defaults in config_to_dict(GenerateConfig()).items():
        if isinstance(defaults, dict) and isinstance(out.get(section), dict):
            for key, value in defaults.items():
                out[section].setdefault(key, value)
    for section, key in IGNORED_CONFIG_KEYS:
        out.get(section, {}).pop(key, None)
    return out


class Manifest:
    """The manifest of one output folder."""

    def __init__(self, root: str | Path, config: dict, seed: int, classes: tuple[str, ...], assets: str) -> None:
        self.root = Path(root)
        self.path = self.root / MANIFEST_NAME
        self.data = {"format": "assist3d-dataset", "version": 1, "seed": int(seed), "assets": assets,
                     "classes": list(classes), "versions": versions(), "config": config, "scenes": []}
        self._entries: dict[str, dict] = {}

    def check_compatible(self) -> None:
        """Raise DataError if the folder already holds a dataset made with another config, seed
        or class list (mixing them would silently corrupt it)."""
        old = read_manifest(self.root, fix="; remove it or choose another --out")
        if old is None:
            return
        diffs = []
        if old.get("seed") != self.data["seed"]:
            diffs.append(f"seed {old.get('seed')} != {self.data['seed']}")
        if old.get("classes") != self.data["classes"]:
            diffs.append("class list")
        a, b = _comparable(old.get("config", {})), _comparable(self.data["config"])
        for section in sorted(set(a) | set(b)):
            if a.get(section) != b.get(section):
                diffs.append(f"config.{section}")
        if diffs:
            raise DataError(f"{self.path}: this folder holds a dataset generated with different settings "
                            f"({', '.join(diffs)}); use another --out or delete the folder")

    def add(self, meta: dict) -> None:
        entry = scene_entry(meta)
        self._entries[entry["id"]] = entry

    def write(self) -> None:
        self.data["scenes"] = [self._entries[k] for k in sorted(self._entries)]
        self.data["llm"] = llm_summary(self.data["scenes"])
        for split, name in SPLIT_FILES.items():
            write_json_atomic(self.root / name, [e["id"] for e in self.data["scenes"]
                                                 if split_of(e.get("index", 0)) == split])
        write_json_atomic(self.path, self.data)

    @property
    def entries(self) -> list[dict]:
        return [self._entries[k] for k in sorted(self._entries)]
